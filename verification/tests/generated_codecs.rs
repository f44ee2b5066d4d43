//! The generated serial codecs: every datasheet example exchange decodes to the intended
//! command and encodes back to the same bytes, and `decode(encode(x)) == x` for every command
//! a frame can carry (random frames, all devices).

use coforge_link::properties::{Direction as LinkDirection, prop_decoder_total, prop_round_trip};
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
/// `length_code` and `data` carries: the property the generated Kani harnesses prove
/// (`coforge_link::properties`), here on random frames.
fn decode_encode_identity<C: SerialCodec>(code: u8, length_code: Option<u8>, data: &[u8]) {
    let (mut out, mut copy) = ([0_u8; 1024], [0_u8; 1024]);
    for direction in [LinkDirection::HostToDevice, LinkDirection::DeviceToHost] {
        prop_round_trip::<C>(direction, code, length_code, data, &mut out, &mut copy);
    }
}

/// Every command of `spec_name`, each of its codes, `runs` random data of every length the
/// generated harness of the command tries (and up to 40 bytes of a longer tail): the
/// generated harnesses' inputs, drawn at random.
fn every_command_round_trips<C: SerialCodec>(spec_name: &str, runs: usize) {
    let d = spec(spec_name);
    let mut rng = proptest::test_runner::TestRng::deterministic_rng(proptest::test_runner::RngAlgorithm::ChaCha);
    let (mut out, mut copy) = ([0_u8; 1024], [0_u8; 1024]);
    let mut checked = 0;
    for cmd in &d.serial.as_ref().expect("serial").commands {
        let direction = match cmd.direction {
            Direction::HostToDevice => LinkDirection::HostToDevice,
            Direction::DeviceToHost => LinkDirection::DeviceToHost,
        };
        let harness_max = coforge_codegen::serial_proofs::harness_data_len(cmd);
        let max = harness_max.max(cmd.length.1.min(40));
        for code in cmd.codes() {
            for len in cmd.length.0.min(harness_max)..=max {
                for _ in 0..runs {
                    let data: Vec<u8> = (0..len).map(|_| rng.next_u32() as u8).collect();
                    prop_round_trip::<C>(direction, code as u8, cmd.length_code.map(|x| x as u8), &data, &mut out, &mut copy);
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 0, "{spec_name}: no command checked");
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

#[test]
fn co401memory1_every_command_round_trips() {
    every_command_round_trips::<co401memory1::serial::Codec>("co401memory1.yaml", 20);
}

#[test]
fn co401gw1_every_command_round_trips() {
    every_command_round_trips::<co401gw1::serial::Codec>("co401gw1.yaml", 20);
}

#[test]
fn canopenia_every_command_round_trips() {
    every_command_round_trips::<canopenia::serial::Codec>("canopenia.yaml", 20);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]
    #[test]
    fn co401memory1_decode_encode_identity(code in any::<u8>(), extension in proptest::option::of(0x80_u8..), data in proptest::collection::vec(any::<u8>(), 0..40)) {
        decode_encode_identity::<co401memory1::serial::Codec>(code, extension, &data);
    }

    #[test]
    fn co401gw1_decode_encode_identity(code in any::<u8>(), extension in proptest::option::of(0x80_u8..), data in proptest::collection::vec(any::<u8>(), 0..40)) {
        decode_encode_identity::<co401gw1::serial::Codec>(code, extension, &data);
    }

    #[test]
    fn canopenia_decode_encode_identity(code in any::<u8>(), extension in proptest::option::of(0x80_u8..), data in proptest::collection::vec(any::<u8>(), 0..40)) {
        decode_encode_identity::<canopenia::serial::Codec>(code, extension, &data);
    }

    /// The generated `decoder_total` harnesses' property on random bytes and gaps.
    #[test]
    fn generated_decoders_are_total(bytes in proptest::collection::vec(any::<u8>(), 0..200), gaps in proptest::collection::vec(0_u8..60, 0..4)) {
        let mut out = [0_u8; 1024];
        prop_decoder_total::<co401memory1::serial::Codec>(&bytes, &gaps, &mut out);
        prop_decoder_total::<co401gw1::serial::Codec>(&bytes, &gaps, &mut out);
        prop_decoder_total::<canopenia::serial::Codec>(&bytes, &gaps, &mut out);
    }
}
