//! CO401Memory1 framing: the first byte is `CMD << 4 | LEN`, then LEN (0..=15) data bytes.
//!
//! Bytes of one frame follow each other without delay; a pause of about
//! [`NibbleConfig::resync_pause_ms`] ends whatever was in progress, and the next byte starts a
//! new frame.

use crate::{Deframer, EncodeError, Frame, FrameError, Millis, elapsed, put};

/// The most data bytes one frame can carry (the length nibble).
pub const MAX_DATA: usize = 15;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NibbleConfig {
    pub resync_pause_ms: u32,
}

/// Encodes a frame into `out`; returns the number of bytes written.
pub fn encode(code: u8, data: &[u8], out: &mut [u8]) -> Result<usize, EncodeError> {
    if code > 0x0F {
        return Err(EncodeError::CodeOutOfRange);
    }
    let len = u8::try_from(data.len()).ok().filter(|&l| usize::from(l) <= MAX_DATA).ok_or(EncodeError::DataTooLong { max: MAX_DATA })?;
    let total = 1 + data.len();
    let (head, rest) = out.split_first_mut().ok_or(EncodeError::BufferTooSmall { needed: total })?;
    if rest.len() < data.len() {
        return Err(EncodeError::BufferTooSmall { needed: total });
    }
    *head = code << 4 | len;
    put(rest, data)?;
    Ok(total)
}

/// Streaming decoder for the nibble-length framing.
#[derive(Debug, Clone)]
pub struct NibbleDecoder {
    config: NibbleConfig,
    buf: [u8; MAX_DATA],
    code: u8,
    /// Data bytes still expected; `None` between frames.
    remaining: Option<usize>,
    filled: usize,
    last: Option<Millis>,
    /// Frames cut short by a pause (counted, since the next byte already starts a new frame).
    pub truncated: u32,
}

impl NibbleDecoder {
    pub const fn new(config: NibbleConfig) -> Self {
        NibbleDecoder { config, buf: [0; MAX_DATA], code: 0, remaining: None, filled: 0, last: None, truncated: 0 }
    }

    /// The data buffer, whole: the last frame's data is its first `data.len()` bytes. A
    /// caller that must keep the data past the next `push` copies this fixed-size array,
    /// which costs a few stores where a copy of `data.len()` bytes is a `memcpy` call.
    pub const fn buffer(&self) -> &[u8; MAX_DATA] {
        &self.buf
    }

    fn frame(&self) -> Frame<'_> {
        Frame { code: self.code, length_code: None, network: None, data: self.buf.get(..self.filled).unwrap_or(&[]) }
    }
}

impl Deframer for NibbleDecoder {
    fn push(&mut self, byte: u8, now: Millis) -> Option<Result<Frame<'_>, FrameError>> {
        let paused = self.last.is_some_and(|t| elapsed(t, now) >= self.config.resync_pause_ms);
        self.last = Some(now);
        if paused && self.remaining.is_some() {
            self.truncated = self.truncated.wrapping_add(1);
            self.remaining = None;
        }
        match self.remaining {
            None => {
                self.code = byte >> 4;
                self.filled = 0;
                let len = usize::from(byte & 0x0F);
                if len == 0 {
                    return Some(Ok(self.frame()));
                }
                self.remaining = Some(len);
                None
            }
            Some(left) => {
                if let Some(slot) = self.buf.get_mut(self.filled) {
                    *slot = byte;
                }
                self.filled += 1;
                if left <= 1 {
                    self.remaining = None;
                    Some(Ok(self.frame()))
                } else {
                    self.remaining = Some(left - 1);
                    None
                }
            }
        }
    }

    fn reset(&mut self) {
        self.remaining = None;
        self.filled = 0;
        self.last = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode_all(d: &mut NibbleDecoder, bytes: &[u8], t0: Millis) -> Option<(u8, [u8; 16], usize)> {
        let mut last = None;
        for (i, &b) in bytes.iter().enumerate() {
            if let Some(Ok(f)) = d.push(b, t0 + i as Millis) {
                let mut data = [0; 16];
                data[..f.data.len()].copy_from_slice(f.data);
                last = Some((f.code, data, f.data.len()));
            }
        }
        last
    }

    #[test]
    fn datasheet_read_memory_request_round_trips() {
        let mut out = [0; 16];
        let n = encode(0x3, &[0x12, 0x50, 0x04], &mut out);
        assert_eq!(n, Ok(4));
        assert_eq!(out[..4], [0x33, 0x12, 0x50, 0x04]);
        let mut d = NibbleDecoder::new(NibbleConfig { resync_pause_ms: 100 });
        let (code, data, len) = decode_all(&mut d, &out[..4], 0).unwrap_or_default();
        assert_eq!((code, &data[..len]), (0x3, &[0x12, 0x50, 0x04][..]));
    }

    #[test]
    fn a_pause_drops_the_partial_frame_and_resynchronises() {
        let mut d = NibbleDecoder::new(NibbleConfig { resync_pause_ms: 100 });
        assert_eq!(d.push(0x33, 0), None);
        assert_eq!(d.push(0x12, 1), None);
        // 150 ms later a new frame starts: 0x00 (read status request) completes at once.
        assert_eq!(d.push(0x00, 151), Some(Ok(Frame { code: 0, length_code: None, network: None, data: &[] })));
        assert_eq!(d.truncated, 1);
    }

    #[test]
    fn encode_rejects_what_the_framing_cannot_carry() {
        let mut out = [0; 32];
        assert_eq!(encode(0x10, &[], &mut out), Err(EncodeError::CodeOutOfRange));
        assert_eq!(encode(0x1, &[0; 16], &mut out), Err(EncodeError::DataTooLong { max: 15 }));
        assert_eq!(encode(0x1, &[0; 3], &mut out[..3]), Err(EncodeError::BufferTooSmall { needed: 4 }));
    }
}
