//! CANopenIA framing: start byte, length, payload (command code first), CRC-16.
//!
//! With [`StartBits`] the start byte carries options: the network number (never 0), whether
//! a CRC follows, and whether the length field has two bytes. Bytes before a valid start byte
//! are skipped, so the decoder finds the next frame after garbage by itself.

use crate::crc::Crc16;
use crate::{Deframer, EncodeError, Frame, FrameError, Millis, elapsed, put};

/// Masks of the start byte's option bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StartBits {
    pub network: u8,
    pub crc: u8,
    pub long_length: u8,
}

/// What the length field counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthCounts {
    Payload,
    PayloadAndCrc,
    Frame,
}

#[derive(Debug, Clone, Copy)]
pub struct StartCrcConfig {
    /// The start byte the device sends (and the only one accepted without `start_bits`).
    pub start_byte: u8,
    pub start_bits: Option<StartBits>,
    /// Width of the length field when the start byte does not select a 2-byte one.
    pub length_bytes: u8,
    pub length_counts: LengthCounts,
    pub max_payload: u16,
    pub crc: &'static Crc16,
    pub crc_little_endian: bool,
    pub crc_covers_start: bool,
    pub crc_covers_length: bool,
    /// A longer gap inside a frame drops it (`None`: no timing rule).
    pub inter_byte_timeout_ms: Option<u32>,
}

/// Options a start byte selects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Options {
    network: Option<u8>,
    has_crc: bool,
    length_bytes: u8,
}

impl StartCrcConfig {
    fn options(&self, start: u8) -> Result<Options, FrameError> {
        match self.start_bits {
            None if start == self.start_byte => Ok(Options { network: None, has_crc: true, length_bytes: self.length_bytes }),
            None => Err(FrameError::BadStart(start)),
            Some(b) => {
                if start & !(b.network | b.crc | b.long_length) != 0 || start & b.network == 0 {
                    return Err(FrameError::BadStart(start));
                }
                let network = (start & b.network) >> b.network.trailing_zeros();
                Ok(Options {
                    network: Some(network),
                    has_crc: start & b.crc != 0,
                    length_bytes: if start & b.long_length != 0 { 2 } else { self.length_bytes },
                })
            }
        }
    }

    /// The length field's value for a payload of `payload` bytes.
    fn length_value(&self, o: Options, payload: usize) -> usize {
        let crc = if o.has_crc { 2 } else { 0 };
        match self.length_counts {
            LengthCounts::Payload => payload,
            LengthCounts::PayloadAndCrc => payload + crc,
            LengthCounts::Frame => 1 + usize::from(o.length_bytes) + payload + crc,
        }
    }

    /// The payload length a length field announces, if it is consistent.
    fn payload_len(&self, o: Options, value: usize) -> Option<usize> {
        let crc = if o.has_crc { 2 } else { 0 };
        match self.length_counts {
            LengthCounts::Payload => Some(value),
            LengthCounts::PayloadAndCrc => value.checked_sub(crc),
            LengthCounts::Frame => value.checked_sub(1 + usize::from(o.length_bytes) + crc),
        }
    }
}

/// Encodes a frame with the default start byte: `code` is the first payload byte.
pub fn encode(config: &StartCrcConfig, code: u8, data: &[u8], out: &mut [u8]) -> Result<usize, EncodeError> {
    encode_with_start(config, config.start_byte, code, data, out)
}

/// The payload of a frame encoded with the default start byte (as [`encode`] writes it).
pub fn payload_of<'a>(config: &StartCrcConfig, frame: &'a [u8]) -> Option<&'a [u8]> {
    let o = config.options(config.start_byte).ok()?;
    let (&start, rest) = frame.split_first()?;
    if start != config.start_byte {
        return None;
    }
    let length = rest.get(..usize::from(o.length_bytes))?;
    let value = length.iter().rev().fold(0_usize, |v, &b| v << 8 | usize::from(b));
    let len = config.payload_len(o, value)?;
    rest.get(usize::from(o.length_bytes)..usize::from(o.length_bytes) + len)
}

/// A frame encoded with the default start byte, written again with the options of `start`
/// (network, CRC or none, 8- or 16-bit length): how a device answers a command in the form the
/// command came in.
pub fn reencode(config: &StartCrcConfig, frame: &[u8], start: u8, out: &mut [u8]) -> Result<usize, EncodeError> {
    let (&code, data) = payload_of(config, frame).and_then(<[u8]>::split_first).ok_or(EncodeError::CodeOutOfRange)?;
    encode_with_start(config, start, code, data, out)
}

/// Encodes a frame with start byte `start` and the options it selects.
pub fn encode_with_start(config: &StartCrcConfig, start: u8, code: u8, data: &[u8], out: &mut [u8]) -> Result<usize, EncodeError> {
    let o = config.options(start).map_err(|_| EncodeError::CodeOutOfRange)?;
    let payload = 1 + data.len();
    let max = usize::from(config.max_payload);
    if payload > max {
        return Err(EncodeError::DataTooLong { max: max.saturating_sub(1) });
    }
    let lb = usize::from(o.length_bytes);
    let crc_len = if o.has_crc { 2 } else { 0 };
    let total = 1 + lb + payload + crc_len;
    if out.len() < total {
        return Err(EncodeError::BufferTooSmall { needed: total });
    }
    let value = config.length_value(o, payload);
    if lb < 2 && value > 0xFF {
        return Err(EncodeError::DataTooLong { max: max.min(0xFF).saturating_sub(1) });
    }
    let mut length = [0_u8; 2];
    for (i, b) in length.iter_mut().enumerate().take(lb) {
        *b = (value >> (8 * i)) as u8;
    }
    let mut at = put(out, &[start])?;
    let length = length.get(..lb).unwrap_or(&[]);
    at += put(out.get_mut(at..).unwrap_or(&mut []), length)?;
    at += put(out.get_mut(at..).unwrap_or(&mut []), &[code])?;
    at += put(out.get_mut(at..).unwrap_or(&mut []), data)?;
    if o.has_crc {
        let crc = config.crc;
        let mut c = crc.start();
        if config.crc_covers_start {
            c = crc.step(c, start);
        }
        if config.crc_covers_length {
            c = crc.update(c, length);
        }
        c = crc.finish(crc.update(crc.step(c, code), data));
        let bytes = if config.crc_little_endian { c.to_le_bytes() } else { c.to_be_bytes() };
        at += put(out.get_mut(at..).unwrap_or(&mut []), &bytes)?;
    }
    Ok(at)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    Hunt,
    Length { have: u8, value: usize },
    Payload { len: usize },
    Crc { have: u8, value: u16 },
}

/// Streaming decoder; `N` is the payload buffer (at least `max_payload` for full frames).
#[derive(Debug, Clone)]
pub struct StartCrcDecoder<const N: usize> {
    config: StartCrcConfig,
    state: State,
    options: Options,
    /// The start byte of the frame in progress (or last completed).
    start: u8,
    crc: u16,
    buf: [u8; N],
    filled: usize,
    last: Option<Millis>,
    /// Bytes skipped while looking for a start byte.
    pub skipped: u32,
}

impl<const N: usize> StartCrcDecoder<N> {
    pub const fn new(config: StartCrcConfig) -> Self {
        StartCrcDecoder {
            config,
            state: State::Hunt,
            options: Options { network: None, has_crc: true, length_bytes: 1 },
            start: config.start_byte,
            crc: 0,
            buf: [0; N],
            filled: 0,
            last: None,
            skipped: 0,
        }
    }

    /// The start byte of the frame last completed (or in progress): an answer uses its options.
    pub fn start_byte(&self) -> u8 {
        self.start
    }

    fn payload(&self) -> &[u8] {
        self.buf.get(..self.filled).unwrap_or(&[])
    }

    /// The finished frame, or `Empty` for a payload without a command code.
    fn frame(&self) -> Result<Frame<'_>, FrameError> {
        let (&code, data) = self.payload().split_first().ok_or(FrameError::Empty)?;
        Ok(Frame { code, length_code: None, network: self.options.network, data })
    }

    fn hunt(&mut self, byte: u8) {
        match self.config.options(byte) {
            Ok(o) => {
                self.options = o;
                self.start = byte;
                self.filled = 0;
                let crc = self.config.crc;
                self.crc = if self.config.crc_covers_start { crc.step(crc.start(), byte) } else { crc.start() };
                self.state = State::Length { have: 0, value: 0 };
            }
            Err(_) => self.skipped = self.skipped.wrapping_add(1),
        }
    }

    /// After the length field: check it, then expect payload (or an empty frame's CRC).
    fn length_done(&mut self, value: usize) -> Option<Result<Frame<'_>, FrameError>> {
        let too_long = || FrameError::TooLong { declared: u16::try_from(value).unwrap_or(u16::MAX) };
        let Some(len) = self.config.payload_len(self.options, value) else {
            self.state = State::Hunt;
            return Some(Err(too_long()));
        };
        if len > usize::from(self.config.max_payload) || len > N {
            self.state = State::Hunt;
            return Some(Err(too_long()));
        }
        if len == 0 {
            self.state = State::Hunt;
            return Some(Err(FrameError::Empty));
        }
        self.state = State::Payload { len };
        None
    }

    fn payload_done(&mut self) -> Option<Result<Frame<'_>, FrameError>> {
        if self.options.has_crc {
            self.state = State::Crc { have: 0, value: 0 };
            None
        } else {
            self.state = State::Hunt;
            Some(self.frame())
        }
    }
}

impl<const N: usize> Deframer for StartCrcDecoder<N> {
    fn push(&mut self, byte: u8, now: Millis) -> Option<Result<Frame<'_>, FrameError>> {
        let gap = self.last.map(|t| elapsed(t, now));
        self.last = Some(now);
        if self.state != State::Hunt && gap.zip(self.config.inter_byte_timeout_ms).is_some_and(|(g, limit)| g > limit) {
            // The frame in progress is dropped; this byte may start the next one.
            self.state = State::Hunt;
            self.hunt(byte);
            return Some(Err(FrameError::Gap));
        }
        match self.state {
            State::Hunt => {
                self.hunt(byte);
                None
            }
            State::Length { have, value } => {
                if self.config.crc_covers_length {
                    self.crc = self.config.crc.step(self.crc, byte);
                }
                let value = value | usize::from(byte) << (8 * have);
                let have = have + 1;
                if have < self.options.length_bytes {
                    self.state = State::Length { have, value };
                    return None;
                }
                self.length_done(value)
            }
            State::Payload { len } => {
                if let Some(slot) = self.buf.get_mut(self.filled) {
                    *slot = byte;
                }
                self.filled += 1;
                self.crc = self.config.crc.step(self.crc, byte);
                if self.filled >= len { self.payload_done() } else { None }
            }
            State::Crc { have, value } => {
                let value = if self.config.crc_little_endian { value | u16::from(byte) << (8 * have) } else { value << 8 | u16::from(byte) };
                if have == 0 {
                    self.state = State::Crc { have: 1, value };
                    return None;
                }
                self.state = State::Hunt;
                let computed = self.config.crc.finish(self.crc);
                if value != computed {
                    return Some(Err(FrameError::Crc { received: value, computed }));
                }
                Some(self.frame())
            }
        }
    }

    fn reset(&mut self) {
        self.state = State::Hunt;
        self.filled = 0;
        self.last = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crc::XMODEM;
    use std::vec::Vec;

    static CRC: Crc16 = Crc16::new(XMODEM);
    const IA: StartCrcConfig = StartCrcConfig {
        start_byte: 0x11,
        start_bits: Some(StartBits { network: 0x0F, crc: 0x10, long_length: 0x20 }),
        length_bytes: 1,
        length_counts: LengthCounts::Payload,
        max_payload: 35,
        crc: &CRC,
        crc_little_endian: true,
        crc_covers_start: false,
        crc_covers_length: true,
        inter_byte_timeout_ms: None,
    };

    fn feed(d: &mut StartCrcDecoder<64>, bytes: &[u8]) -> Vec<crate::Decoded> {
        let mut out = Vec::new();
        for (i, &b) in bytes.iter().enumerate() {
            if let Some(r) = d.push(b, i as Millis) {
                out.push(r.map(|f| (f.code, f.network, f.data.to_vec())));
            }
        }
        out
    }

    #[test]
    fn spec_examples_decode_in_every_start_byte_variant() {
        let mut d = StartCrcDecoder::<64>::new(IA);
        let want = Ok((b'R', Some(1), [0x00, 0x5F, 0x02].to_vec()));
        assert_eq!(feed(&mut d, &[0x11, 0x04, 0x52, 0x00, 0x5F, 0x02, 0x96, 0x2F]), core::slice::from_ref(&want));
        assert_eq!(feed(&mut d, &[0x01, 0x04, 0x52, 0x00, 0x5F, 0x02]), core::slice::from_ref(&want));
        assert_eq!(feed(&mut d, &[0x31, 0x04, 0x00, 0x52, 0x00, 0x5F, 0x02, 0x31, 0xA0]), [want]);
    }

    #[test]
    fn garbage_is_skipped_and_bad_crc_reported() {
        let mut d = StartCrcDecoder::<64>::new(IA);
        let frames = feed(&mut d, &[0xC0, 0x40, 0x11, 0x04, 0x52, 0x00, 0x5F, 0x02, 0x96, 0x2E]);
        assert_eq!(frames, [Err(FrameError::Crc { received: 0x2E96, computed: 0x2F96 })]);
        assert_eq!(d.skipped, 2);
    }

    #[test]
    fn oversize_length_is_rejected_before_buffering() {
        let mut d = StartCrcDecoder::<64>::new(IA);
        assert_eq!(feed(&mut d, &[0x11, 36]), [Err(FrameError::TooLong { declared: 36 })]);
        let mut small = StartCrcDecoder::<4>::new(IA);
        assert_eq!(small.push(0x11, 0), None);
        assert_eq!(small.push(5, 1), Some(Err(FrameError::TooLong { declared: 5 })));
    }

    #[test]
    fn encode_round_trips() {
        let mut out = [0; 64];
        let n = encode(&IA, b'R', &[0x00, 0x5F, 0x02], &mut out).unwrap_or(0);
        assert_eq!(out[..n], [0x11, 0x04, 0x52, 0x00, 0x5F, 0x02, 0x96, 0x2F]);
        assert_eq!(encode(&IA, b'W', &[0; 35], &mut out), Err(EncodeError::DataTooLong { max: 34 }));
    }

    #[test]
    fn an_answer_takes_the_start_byte_of_its_command() {
        let mut d = StartCrcDecoder::<64>::new(IA);
        // No CRC, then a 16-bit length on network 2: the decoder remembers each start byte.
        assert_eq!(feed(&mut d, &[0x01, 0x04, 0x52, 0x00, 0x5F, 0x02]).len(), 1);
        assert_eq!(d.start_byte(), 0x01);
        assert_eq!(feed(&mut d, &[0x32, 0x04, 0x00, 0x52, 0x00, 0x5F, 0x02, 0x31, 0xA0]).len(), 1);
        assert_eq!(d.start_byte(), 0x32);
        let mut frame = [0; 64];
        let n = encode(&IA, b'R', &[0x00, 0x5F, 0x02, 0, 0, 7], &mut frame).unwrap_or(0);
        assert_eq!(payload_of(&IA, &frame[..n]), Some(&[b'R', 0x00, 0x5F, 0x02, 0, 0, 7][..]));
        let mut out = [0; 64];
        for (start, want) in
            [(0x11, &frame[..n]), (0x01, &[0x01, 0x07, b'R', 0x00, 0x5F, 0x02, 0, 0, 7][..]), (0x21, &[0x21, 0x07, 0x00, b'R', 0x00, 0x5F, 0x02, 0, 0, 7][..])]
        {
            let m = reencode(&IA, &frame[..n], start, &mut out).unwrap_or(0);
            assert_eq!(&out[..m], want, "start {start:02X}");
        }
        // Each re-encoded frame decodes to the same payload, with its own options.
        let m = reencode(&IA, &frame[..n], 0x32, &mut out).unwrap_or(0);
        assert_eq!(feed(&mut d, &out[..m]), [Ok((b'R', Some(2), [0x00, 0x5F, 0x02, 0, 0, 7].to_vec()))]);
        // Not a frame of the default start byte, or a start byte the framing refuses.
        assert_eq!(reencode(&IA, &out[..m], 0x11, &mut frame), Err(EncodeError::CodeOutOfRange));
        assert_eq!(reencode(&IA, &out[..0], 0x11, &mut frame), Err(EncodeError::CodeOutOfRange));
        let n = encode(&IA, b'R', &[1], &mut frame).unwrap_or(0);
        assert_eq!(reencode(&IA, &frame[..n], 0x10, &mut out), Err(EncodeError::CodeOutOfRange), "network 0 is reserved");
    }
}
