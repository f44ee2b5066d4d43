//! The generated serial codecs: every datasheet example exchange decodes to the intended
//! command and encodes back to the same bytes, and `decode(encode(x)) == x` for every command
//! a frame can carry (random frames, all devices).

use coforge_link::{Deframer, EncodeError, Frame, Message, SerialCodec};
use coforge_spec::model::Direction;
use proptest::prelude::*;
use std::path::PathBuf;

fn spec(name: &str) -> coforge_spec::Device {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../spec").join(name);
    coforge_spec::load_file(&path).into_device().unwrap_or_else(|| panic!("{name} loads"))
}

/// Feeds a whole frame to a decoder and returns what the last byte produced, owned.
fn deframe<D: Deframer>(d: &mut D, bytes: &[u8]) -> Option<(u8, Option<u8>, Vec<u8>)> {
    let mut out = None;
    for (i, &b) in bytes.iter().enumerate() {
        if let Some(r) = d.push(b, i as u32) {
            out = r.ok().map(|f| (f.code, f.length_code, f.data.to_vec()));
        }
    }
    out
}

/// Every datasheet example exchange of `spec` deframes, decodes to its command and encodes back
/// to the same bytes with codec `C`.
fn examples_round_trip<C: SerialCodec>(spec_name: &str) {
    let d = spec(spec_name);
    let default_start = match d.serial.as_ref().map(|s| &s.framing) {
        Some(coforge_spec::model::Framing::StartLengthCrc { start_byte, .. }) => Some(*start_byte),
        _ => None,
    };
    let mut n = 0;
    for cmd in &d.serial.as_ref().expect("serial").commands {
        for ex in &cmd.examples {
            let (code, length_code, data) =
                deframe(&mut C::decoder(), &ex.bytes).unwrap_or_else(|| panic!("`{}` {:02X?} does not deframe", cmd.name, ex.bytes));
            let frame = Frame { code, length_code, network: None, data: &data };
            let mut out = [0_u8; 300];
            let encoded = match cmd.direction {
                Direction::HostToDevice => reencode::<C::HostToDevice<'_>>(&frame, &cmd.name, &ex.bytes, &mut out),
                Direction::DeviceToHost => reencode::<C::DeviceToHost<'_>>(&frame, &cmd.name, &ex.bytes, &mut out),
            };
            let len = encoded.unwrap_or_else(|e| panic!("`{}` re-encode: {e:?}", cmd.name));
            // Frames with another start byte (CANopenIA options) re-encode with the default one.
            if default_start.is_none_or(|s| ex.bytes.first() == Some(&s)) {
                assert_eq!(&out[..len], &ex.bytes[..], "`{}` round trip", cmd.name);
            }
            n += 1;
        }
    }
    assert!(n > 0);
}

/// Decodes `frame` as the command called `name` and encodes it into `out`.
fn reencode<'a, M: Message<'a>>(frame: &Frame<'a>, name: &str, bytes: &[u8], out: &mut [u8]) -> Result<usize, EncodeError> {
    let x = M::decode(frame).unwrap_or_else(|e| panic!("`{name}` {bytes:02X?}: {e:?}"));
    assert_eq!(x.name(), name, "{bytes:02X?}");
    x.encode(out)
}

/// `decode(encode(x)) == x` for whatever command of either direction a frame of `code`,
/// `length_code` and `data` carries.
fn decode_encode_identity<C: SerialCodec>(code: u8, length_code: Option<u8>, data: &[u8]) -> Result<(), TestCaseError> {
    let frame = Frame { code, length_code, network: None, data };
    let (mut to_device, mut to_host) = (Vec::new(), Vec::new());
    identity::<C, C::HostToDevice<'_>>(&frame, &mut to_device)?;
    identity::<C, C::DeviceToHost<'_>>(&frame, &mut to_host)
}

/// The identity for one direction; the re-deframed data goes to `scratch`, which lives as long
/// as the frame's data, so both decodings have the same type.
fn identity<'a, C: SerialCodec, M: Message<'a>>(frame: &Frame<'a>, scratch: &'a mut Vec<u8>) -> Result<(), TestCaseError> {
    let Ok(x) = M::decode(frame) else { return Ok(()) };
    let mut out = [0_u8; 300];
    let len = x.encode(&mut out).expect("a decoded command encodes");
    let (code, length_code, data) = deframe(&mut C::decoder(), &out[..len]).expect("an encoded frame deframes");
    *scratch = data;
    let data: &'a [u8] = scratch;
    prop_assert_eq!(M::decode(&Frame { code, length_code, network: None, data }), Ok(x));
    Ok(())
}

#[test]
fn co401memory1_examples_round_trip() {
    examples_round_trip::<co401memory1::serial::Codec>("co401memory1.yaml");
}

#[test]
fn co401gw1_examples_round_trip() {
    examples_round_trip::<co401gw1::serial::Codec>("co401gw1.yaml");
}

#[test]
fn canopenia_examples_round_trip() {
    examples_round_trip::<canopenia::serial::Codec>("canopenia.yaml");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]
    #[test]
    fn co401memory1_decode_encode_identity(code in any::<u8>(), extension in proptest::option::of(0x80_u8..), data in proptest::collection::vec(any::<u8>(), 0..40)) {
        decode_encode_identity::<co401memory1::serial::Codec>(code, extension, &data)?;
    }

    #[test]
    fn co401gw1_decode_encode_identity(code in any::<u8>(), extension in proptest::option::of(0x80_u8..), data in proptest::collection::vec(any::<u8>(), 0..40)) {
        decode_encode_identity::<co401gw1::serial::Codec>(code, extension, &data)?;
    }

    #[test]
    fn canopenia_decode_encode_identity(code in any::<u8>(), extension in proptest::option::of(0x80_u8..), data in proptest::collection::vec(any::<u8>(), 0..40)) {
        decode_encode_identity::<canopenia::serial::Codec>(code, extension, &data)?;
    }
}
