//! Framings: round trips, totality of the decoders, resynchronisation after garbage.

use coforge_link::crc::{Crc16, XMODEM};
use coforge_link::length_byte::{self, LengthByteConfig, LengthByteDecoder};
use coforge_link::nibble::{self, NibbleConfig, NibbleDecoder};
use coforge_link::start_crc::{self, LengthCounts, StartBits, StartCrcConfig, StartCrcDecoder};
use coforge_link::{Deframer, Frame, FrameError, Millis};

/// CO401Memory1's framing parameters (spec: `resync_pause_ms: 100`).
pub const MEMORY1: NibbleConfig = NibbleConfig { resync_pause_ms: 100 };
/// CO401GW1's framing parameters.
pub const GW1: LengthByteConfig = LengthByteConfig { inter_byte_timeout_ms: 10, resync_pause_ms: 50, extension_threshold: 0x80 };
static XMODEM_TABLE: Crc16 = Crc16::new(XMODEM);
/// CANopenIA's framing, with a 50 ms inter-byte timeout so that a pause resynchronises.
pub const CANOPENIA: StartCrcConfig = StartCrcConfig {
    start_byte: 0x11,
    start_bits: Some(StartBits { network: 0x0F, crc: 0x10, long_length: 0x20 }),
    length_bytes: 1,
    length_counts: LengthCounts::Payload,
    max_payload: 35,
    crc: &XMODEM_TABLE,
    crc_little_endian: true,
    crc_covers_start: false,
    crc_covers_length: true,
    inter_byte_timeout_ms: Some(50),
};
/// A pause after which the CANopenIA decoder has resynchronised: longer than its inter-byte
/// timeout. A constant of its own rather than `CANOPENIA.inter_byte_timeout_ms` in the
/// property: Kani 0.63's compiler panics on that projection of an `Option` field out of a
/// constant ("Range is out of bounds", a rustc StableMIR bug).
pub const IA_RESYNC_PAUSE_MS: Millis = match CANOPENIA.inter_byte_timeout_ms {
    Some(ms) => ms + 1,
    None => 1,
};
/// Largest GW1 DataLen the decoder buffers in these proofs.
pub const GW1_MAX: usize = 127;
pub const IA_MAX: usize = 35;

/// Feeds `bytes` one millisecond apart from `t0`; returns the last result and its time.
fn feed<D: Deframer>(d: &mut D, bytes: &[u8], t0: Millis, mut check: impl FnMut(Result<Frame<'_>, FrameError>)) -> Millis {
    let mut t = t0;
    for &b in bytes {
        if let Some(r) = d.push(b, t) {
            check(r);
        }
        t = t.wrapping_add(1);
    }
    t
}

fn expect_one<D: Deframer>(d: &mut D, bytes: &[u8], t0: Millis, code: u8, length_code: Option<u8>, data: &[u8]) {
    let mut seen = 0;
    feed(d, bytes, t0, |r| {
        seen += 1;
        match r {
            Ok(f) => {
                assert_eq!((f.code, f.length_code), (code, length_code));
                assert_eq!(f.data, data);
            }
            Err(e) => panic!("a frame just encoded failed to decode: {e:?}"),
        }
    });
    assert_eq!(seen, 1, "exactly one frame");
}

/// `decode(encode(x)) == x` for the nibble framing (codes 0..=15, up to 15 data bytes).
pub fn prop_nibble_round_trip(code: u8, data: &[u8]) {
    let mut buf = [0_u8; 16];
    let Ok(n) = nibble::encode(code, data, &mut buf) else {
        assert!(code > 0x0F || data.len() > nibble::MAX_DATA, "encode refused a valid frame");
        return;
    };
    let mut d = NibbleDecoder::new(MEMORY1);
    expect_one(&mut d, buf.get(..n).unwrap_or(&[]), 0, code, None, data);
}

/// `decode(encode(x)) == x` for the length-byte framing, including extension codes.
pub fn prop_length_byte_round_trip(code: u8, data: &[u8], extension: Option<u8>) {
    let mut buf = [0_u8; GW1_MAX + 2];
    let mut d = LengthByteDecoder::<GW1_MAX>::new(GW1);
    match extension {
        Some(x) => match length_byte::encode_extension(&GW1, code, x, &mut buf) {
            Ok(n) => expect_one(&mut d, buf.get(..n).unwrap_or(&[]), 0, code, Some(x), &[]),
            Err(_) => assert!(x < GW1.extension_threshold),
        },
        None => match length_byte::encode(&GW1, code, data, &mut buf) {
            Ok(n) => expect_one(&mut d, buf.get(..n).unwrap_or(&[]), 0, code, None, data),
            Err(_) => assert!(data.len() >= usize::from(GW1.extension_threshold)),
        },
    }
}

/// `decode(encode(x)) == x` for the start+CRC framing.
pub fn prop_start_crc_round_trip(code: u8, data: &[u8]) {
    let mut buf = [0_u8; IA_MAX + 5];
    let mut d = StartCrcDecoder::<IA_MAX>::new(CANOPENIA);
    match start_crc::encode(&CANOPENIA, code, data, &mut buf) {
        Ok(n) => expect_one(&mut d, buf.get(..n).unwrap_or(&[]), 0, code, None, data),
        Err(_) => assert!(data.len() >= IA_MAX),
    }
}

/// Time before byte `i`: `gaps` cycled, 1 ms if there are none.
fn gap_at(gaps: &[u8], i: usize) -> u32 {
    if gaps.is_empty() { 1 } else { u32::from(gaps.get(i % gaps.len()).copied().unwrap_or(1)) }
}

/// Feeds any bytes at any times; `check` sees every frame the decoder yields.
fn drive<D: Deframer>(d: &mut D, bytes: &[u8], gaps: &[u8], mut check: impl FnMut(&Frame<'_>)) {
    let mut t: Millis = 0;
    for (i, &b) in bytes.iter().enumerate() {
        t = t.wrapping_add(gap_at(gaps, i));
        if let Some(Ok(f)) = d.push(b, t) {
            check(&f);
        }
    }
}

/// The nibble decoder never panics on any input, and its frames fit the framing.
pub fn prop_nibble_total(bytes: &[u8], gaps: &[u8]) {
    drive(&mut NibbleDecoder::new(MEMORY1), bytes, gaps, |f| assert!(f.code <= 0x0F && f.data.len() <= nibble::MAX_DATA));
}

/// The length-byte decoder never panics on any input, and its frames fit the framing.
pub fn prop_length_byte_total(bytes: &[u8], gaps: &[u8]) {
    drive(&mut LengthByteDecoder::<GW1_MAX>::new(GW1), bytes, gaps, |f| {
        assert!(f.data.len() < usize::from(GW1.extension_threshold));
        assert!(f.length_code.is_none() || f.data.is_empty());
    });
}

/// The start+CRC decoder never panics on any input, and its frames fit the framing.
pub fn prop_start_crc_total(bytes: &[u8], gaps: &[u8]) {
    drive(&mut StartCrcDecoder::<IA_MAX>::new(CANOPENIA), bytes, gaps, |f| {
        assert!(f.data.len() < IA_MAX);
        assert!(f.network.is_some_and(|n| (1..=15).contains(&n)));
    });
}

/// All three decoders on the same input.
pub fn prop_decoders_total(bytes: &[u8], gaps: &[u8]) {
    prop_nibble_total(bytes, gaps);
    prop_length_byte_total(bytes, gaps);
    prop_start_crc_total(bytes, gaps);
}

/// Splits fuzzer input into gaps and bytes: the first byte says how many gaps follow.
pub fn split_fuzz_input(input: &[u8]) -> (&[u8], &[u8]) {
    let Some((&n, rest)) = input.split_first() else { return (&[], &[]) };
    rest.split_at(usize::from(n % 16).min(rest.len()))
}

/// After any garbage, a pause and then a valid frame decode exactly that frame.
pub fn prop_resync_after_garbage(garbage: &[u8], code: u8, data: &[u8]) {
    let data = data.get(..data.len().min(8)).unwrap_or(&[]);
    let mut buf = [0_u8; 48];

    let mut d = NibbleDecoder::new(MEMORY1);
    let t = feed(&mut d, garbage, 0, |_| {});
    if let Ok(n) = nibble::encode(code & 0x0F, data, &mut buf) {
        expect_last(&mut d, buf.get(..n).unwrap_or(&[]), t.wrapping_add(MEMORY1.resync_pause_ms), code & 0x0F, data);
    }

    let mut d = LengthByteDecoder::<GW1_MAX>::new(GW1);
    let t = feed(&mut d, garbage, 0, |_| {});
    if let Ok(n) = length_byte::encode(&GW1, code, data, &mut buf) {
        expect_last(&mut d, buf.get(..n).unwrap_or(&[]), t.wrapping_add(GW1.resync_pause_ms), code, data);
    }

    let mut d = StartCrcDecoder::<IA_MAX>::new(CANOPENIA);
    let t = feed(&mut d, garbage, 0, |_| {});
    if let Ok(n) = start_crc::encode(&CANOPENIA, code, data, &mut buf) {
        expect_last(&mut d, buf.get(..n).unwrap_or(&[]), t.wrapping_add(IA_RESYNC_PAUSE_MS), code, data);
    }
}

/// The frame's bytes after a pause: the last result must be exactly this frame.
fn expect_last<D: Deframer>(d: &mut D, bytes: &[u8], t0: Millis, code: u8, data: &[u8]) {
    let mut last_ok = false;
    let mut t = t0;
    for (i, &b) in bytes.iter().enumerate() {
        let result = d.push(b, t).map(|r| r.map(|f| f.code == code && f.data == data));
        if i + 1 == bytes.len() {
            last_ok = result == Some(Ok(true));
        }
        t = t.wrapping_add(1);
    }
    assert!(last_ok, "the frame after the pause did not decode exactly");
}
