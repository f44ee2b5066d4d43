//! Serial framing and integrity for coforge devices, `no_std` and allocation-free.
//!
//! Three framings, one per datasheet protocol, each with an encoder and a streaming decoder:
//! - [`nibble`]: CO401Memory1, `CMD << 4 | LEN` then LEN data bytes; a pause resynchronises;
//! - [`length_byte`]: CO401GW1, command byte, DataLen byte, data; a gap between bytes
//!   invalidates a frame, a longer pause resynchronises, DataLen >= a threshold is an extension;
//! - [`start_crc`]: CANopenIA, start byte (with option bits), length, payload, CRC-16.
//!
//! Decoders are fed one byte at a time with a millisecond timestamp, never panic, never index
//! out of bounds, and reject an oversize length before buffering a single data byte.
#![no_std]
#![forbid(unsafe_code)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]
#![cfg_attr(test, allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod checksum;
pub mod crc;
pub mod fields;
pub mod length_byte;
pub mod nibble;
pub mod properties;
pub mod start_crc;

/// Milliseconds from a free-running clock. It may wrap; only differences are used.
pub type Millis = u32;

/// Time from `earlier` to `later` on a wrapping millisecond clock.
#[inline]
pub fn elapsed(earlier: Millis, later: Millis) -> u32 {
    later.wrapping_sub(earlier)
}

/// Bytes waiting for the host: answers are encoded into it and handed out whenever the
/// runtime asks, so a device can also answer late or unasked.
#[derive(Debug, Clone)]
pub struct Outbox<const N: usize> {
    bytes: [u8; N],
    start: usize,
    end: usize,
    /// Frames dropped because the runtime did not take the earlier ones.
    pub overflows: u32,
}

impl<const N: usize> Default for Outbox<N> {
    fn default() -> Self {
        Outbox { bytes: [0; N], start: 0, end: 0, overflows: 0 }
    }
}

impl<const N: usize> Outbox<N> {
    /// Appends one frame that `encode` writes into the free space (returning its length, or
    /// `None` if it does not fit); a frame that does not fit is dropped whole and counted.
    pub fn push_with(&mut self, encode: impl FnOnce(&mut [u8]) -> Option<usize>) -> bool {
        if self.start == self.end {
            (self.start, self.end) = (0, 0);
        }
        let written = self.bytes.get_mut(self.end..).and_then(encode);
        match written {
            Some(n) if self.end + n <= N => {
                self.end += n;
                true
            }
            _ => {
                self.overflows = self.overflows.wrapping_add(1);
                false
            }
        }
    }

    /// Moves waiting bytes into `out`; returns how many.
    pub fn take(&mut self, out: &mut [u8]) -> usize {
        let waiting = self.bytes.get(self.start..self.end).unwrap_or(&[]);
        // Byte by byte: answers are a few bytes, shorter than a `memcpy` call's set-up.
        let mut n = 0;
        for (dst, &src) in out.iter_mut().zip(waiting) {
            *dst = src;
            n += 1;
        }
        self.start += n;
        n
    }

    pub fn is_empty(&self) -> bool {
        self.start == self.end
    }

    /// Bytes a frame pushed now may take (all of it once everything was taken).
    pub fn free(&self) -> usize {
        if self.is_empty() { N } else { N.saturating_sub(self.end) }
    }
}

/// A decoded frame, borrowed from the decoder's buffer until the next byte is pushed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Frame<'a> {
    /// The command code: the high nibble, the command byte, or the first payload byte.
    pub code: u8,
    /// A DataLen byte at or above the extension threshold (length-byte framing only).
    pub length_code: Option<u8>,
    /// The network number from the start byte (start+CRC framing only).
    pub network: Option<u8>,
    /// The data after the command code.
    pub data: &'a [u8],
}

/// Why a frame in progress was dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameError {
    /// The gap between two bytes of one frame was longer than the framing allows.
    Gap,
    /// The declared length exceeds the framing's or the buffer's maximum.
    TooLong { declared: u16 },
    /// The CRC did not match the covered bytes.
    Crc { received: u16, computed: u16 },
    /// A start byte with reserved bits set or network 0.
    BadStart(u8),
    /// A frame with no command code (empty payload).
    Empty,
}

/// Why a frame could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EncodeError {
    /// The output buffer is too small; `needed` bytes are required.
    BufferTooSmall { needed: usize },
    /// More data than the framing can carry in one frame.
    DataTooLong { max: usize },
    /// The command code does not fit the framing (a nibble framing's code is 0..=15).
    CodeOutOfRange,
}

/// A streaming decoder: bytes in, frames out.
pub trait Deframer {
    /// Feeds one byte received at `now`. Returns a frame when this byte completes one, or an
    /// error when this byte shows that the frame in progress is invalid.
    fn push(&mut self, byte: u8, now: Millis) -> Option<Result<Frame<'_>, FrameError>>;
    /// Forgets any frame in progress.
    fn reset(&mut self);
}

/// One direction's commands of a generated serial protocol (`serial::HostToDevice`,
/// `serial::DeviceToHost`), borrowing the frame's data for `'a`.
pub trait Message<'a>: Sized + Copy + PartialEq + core::fmt::Debug {
    /// The command a decoded frame carries.
    fn decode(frame: &Frame<'a>) -> Result<Self, fields::DecodeError>;
    /// Writes the whole frame into `out`; returns its length.
    fn encode(&self, out: &mut [u8]) -> Result<usize, EncodeError>;
    /// The command's name in the spec.
    fn name(&self) -> &'static str;
}

/// A device's generated serial protocol as one type (`serial::Codec`), so that code can be
/// generic over devices: its decoder and the commands of both directions.
pub trait SerialCodec {
    type Decoder: Deframer;
    type HostToDevice<'a>: Message<'a>;
    type DeviceToHost<'a>: Message<'a>;

    /// A fresh decoder.
    fn decoder() -> Self::Decoder;
}

/// Writes `bytes` to the front of `out`, or says how much room was needed.
fn put(out: &mut [u8], bytes: &[u8]) -> Result<usize, EncodeError> {
    let dst = out.get_mut(..bytes.len()).ok_or(EncodeError::BufferTooSmall { needed: bytes.len() })?;
    dst.copy_from_slice(bytes);
    Ok(bytes.len())
}

/// What the unit tests collect from a decoder: `(code, length_code or network, data)` or the error.
#[cfg(test)]
type Decoded = core::result::Result<(u8, Option<u8>, std::vec::Vec<u8>), FrameError>;

#[cfg(test)]
extern crate std;

#[cfg(test)]
mod outbox_tests {
    use super::*;

    #[test]
    fn the_outbox_keeps_frames_whole_and_in_order() {
        let mut o = Outbox::<6>::default();
        assert_eq!(o.free(), 6);
        assert!(o.push_with(|b| b.get_mut(..3).map(|d| d.copy_from_slice(&[1, 2, 3])).map(|()| 3)));
        assert_eq!(o.free(), 3);
        assert!(!o.push_with(|b| b.get_mut(..4).map(|_| 4)), "no room for 4 more: dropped whole");
        assert_eq!(o.overflows, 1);
        let mut out = [0; 2];
        assert_eq!(o.take(&mut out), 2);
        assert_eq!(out, [1, 2]);
        assert_eq!(o.free(), 3, "taken bytes come back only once all are taken");
        assert_eq!(o.take(&mut out), 1);
        assert_eq!(out[0], 3);
        assert!(o.is_empty());
        assert!(o.push_with(|b| b.get_mut(..6).map(|_| 6)), "emptied: the whole buffer is free again");
        assert_eq!(o.take(&mut [0; 8]), 6);
    }
}
