//! CO401GW1 framing: command byte, DataLen byte, then DataLen data bytes.
//!
//! DataLen at or above the extension threshold is not a length but an extension code (the
//! gateway's "enable CANopen, alternate mode" is `02 81`): such a frame ends after DataLen.
//! A gap longer than [`LengthByteConfig::inter_byte_timeout_ms`] inside a frame invalidates
//! it; the decoder then ignores bytes until a pause of [`LengthByteConfig::resync_pause_ms`].

use crate::{Deframer, EncodeError, Frame, FrameError, Millis, elapsed, put};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LengthByteConfig {
    pub inter_byte_timeout_ms: u32,
    pub resync_pause_ms: u32,
    pub extension_threshold: u8,
}

/// Encodes `code`, DataLen and `data`.
pub fn encode(config: &LengthByteConfig, code: u8, data: &[u8], out: &mut [u8]) -> Result<usize, EncodeError> {
    let max = usize::from(config.extension_threshold).saturating_sub(1);
    let len = u8::try_from(data.len()).ok().filter(|&l| l < config.extension_threshold).ok_or(EncodeError::DataTooLong { max })?;
    let total = 2 + data.len();
    if out.len() < total {
        return Err(EncodeError::BufferTooSmall { needed: total });
    }
    put(out, &[code, len])?;
    put(out.get_mut(2..).unwrap_or(&mut []), data)?;
    Ok(total)
}

/// Encodes a frame whose DataLen is an extension code (no data follows).
pub fn encode_extension(config: &LengthByteConfig, code: u8, length_code: u8, out: &mut [u8]) -> Result<usize, EncodeError> {
    if length_code < config.extension_threshold {
        return Err(EncodeError::CodeOutOfRange);
    }
    put(out, &[code, length_code])
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// Between frames: the next byte is a command byte.
    Idle,
    /// After the command byte.
    Length,
    /// Collecting data; the value is the DataLen.
    Data(usize),
    /// After an invalid frame: ignore bytes until a resync pause.
    Resync,
}

/// Streaming decoder for the length-byte framing; `N` is the largest DataLen accepted.
#[derive(Debug, Clone)]
pub struct LengthByteDecoder<const N: usize> {
    config: LengthByteConfig,
    state: State,
    code: u8,
    buf: [u8; N],
    filled: usize,
    last: Option<Millis>,
}

impl<const N: usize> LengthByteDecoder<N> {
    pub const fn new(config: LengthByteConfig) -> Self {
        LengthByteDecoder { config, state: State::Idle, code: 0, buf: [0; N], filled: 0, last: None }
    }

    fn frame(&self, length_code: Option<u8>) -> Frame<'_> {
        Frame { code: self.code, length_code, network: None, data: self.buf.get(..self.filled).unwrap_or(&[]) }
    }
}

impl<const N: usize> Deframer for LengthByteDecoder<N> {
    fn push(&mut self, byte: u8, now: Millis) -> Option<Result<Frame<'_>, FrameError>> {
        let gap = self.last.map(|t| elapsed(t, now));
        self.last = Some(now);
        let paused = gap.is_some_and(|g| g >= self.config.resync_pause_ms);
        let mut error = None;
        match self.state {
            State::Resync if !paused => return None,
            State::Length | State::Data(_) if gap.is_some_and(|g| g > self.config.inter_byte_timeout_ms) => {
                // The frame in progress is invalid. A long enough pause also resynchronises,
                // so this byte may start the next frame; otherwise wait for a pause.
                error = Some(FrameError::Gap);
                self.state = if paused { State::Idle } else { State::Resync };
                if !paused {
                    return Some(Err(FrameError::Gap));
                }
            }
            _ => {}
        }
        match self.state {
            State::Idle | State::Resync => {
                self.code = byte;
                self.filled = 0;
                self.state = State::Length;
                error.map(Err)
            }
            State::Length => {
                if byte >= self.config.extension_threshold {
                    self.state = State::Idle;
                    self.filled = 0;
                    return Some(Ok(self.frame(Some(byte))));
                }
                let len = usize::from(byte);
                if len > N {
                    // Reject before buffering anything; what follows is not a frame start.
                    self.state = State::Resync;
                    return Some(Err(FrameError::TooLong { declared: u16::from(byte) }));
                }
                if len == 0 {
                    self.state = State::Idle;
                    return Some(Ok(self.frame(None)));
                }
                self.state = State::Data(len);
                None
            }
            State::Data(len) => {
                if let Some(slot) = self.buf.get_mut(self.filled) {
                    *slot = byte;
                }
                self.filled += 1;
                if self.filled >= len {
                    self.state = State::Idle;
                    Some(Ok(self.frame(None)))
                } else {
                    None
                }
            }
        }
    }

    fn reset(&mut self) {
        self.state = State::Idle;
        self.filled = 0;
        self.last = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GW1: LengthByteConfig = LengthByteConfig { inter_byte_timeout_ms: 10, resync_pause_ms: 50, extension_threshold: 0x80 };

    fn feed<const N: usize>(d: &mut LengthByteDecoder<N>, bytes: &[u8], t0: Millis, step: Millis) -> Vec<crate::Decoded> {
        let mut out = Vec::new();
        for (i, &b) in bytes.iter().enumerate() {
            if let Some(r) = d.push(b, t0 + i as Millis * step) {
                out.push(r.map(|f| (f.code, f.length_code, f.data.to_vec())));
            }
        }
        out
    }

    use std::vec::Vec;

    #[test]
    fn datasheet_examples_decode() {
        let mut d = LengthByteDecoder::<127>::new(GW1);
        let frames = feed(&mut d, &[0x21, 0x07, 0x18, 0x10, 0x04, 0x78, 0x56, 0x34, 0x12], 0, 1);
        assert_eq!(frames, [Ok((0x21, None, [0x18, 0x10, 0x04, 0x78, 0x56, 0x34, 0x12].to_vec()))]);
        assert_eq!(feed(&mut d, &[0x02, 0x81], 100, 1), [Ok((0x02, Some(0x81), Vec::new()))]);
        assert_eq!(feed(&mut d, &[0x50, 0x00], 200, 1), [Ok((0x50, None, Vec::new()))]);
    }

    #[test]
    fn a_gap_invalidates_and_a_pause_resynchronises() {
        let mut d = LengthByteDecoder::<127>::new(GW1);
        assert_eq!(d.push(0x21, 0), None);
        assert_eq!(d.push(0x03, 1), None);
        // 20 ms gap inside the frame: invalid; the following bytes are ignored...
        assert_eq!(d.push(0x18, 21), Some(Err(FrameError::Gap)));
        assert_eq!(d.push(0x50, 22), None);
        assert_eq!(d.push(0x00, 23), None);
        // ...until a 50 ms pause: then a frame decodes exactly.
        assert_eq!(feed(&mut d, &[0x50, 0x00], 80, 1), [Ok((0x50, None, Vec::new()))]);
    }

    #[test]
    fn oversize_lengths_are_rejected_before_buffering() {
        let mut d = LengthByteDecoder::<8>::new(GW1);
        assert_eq!(feed(&mut d, &[0x21, 0x09, 1, 2, 3], 0, 1), [Err(FrameError::TooLong { declared: 9 })]);
    }

    #[test]
    fn encode_matches_the_datasheet() {
        let mut out = [0; 16];
        assert_eq!(encode(&GW1, 0x21, &[0x18, 0x10, 0x04], &mut out), Ok(5));
        assert_eq!(out[..5], [0x21, 0x03, 0x18, 0x10, 0x04]);
        assert_eq!(encode_extension(&GW1, 0x02, 0x81, &mut out), Ok(2));
        assert_eq!(encode(&GW1, 0x30, &[0; 0x80], &mut [0; 200]), Err(EncodeError::DataTooLong { max: 0x7F }));
        assert_eq!(encode(&GW1, 0x30, &[1, 2], &mut out[..3]), Err(EncodeError::BufferTooSmall { needed: 4 }));
    }
}
