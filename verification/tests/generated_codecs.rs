//! The generated serial codecs: every datasheet example exchange decodes to the intended
//! command and encodes back to the same bytes, and `decode(encode(x)) == x` for every command
//! a frame can carry (random frames, all devices).

use coforge_link::{Deframer, Frame};
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

macro_rules! device_codec_tests {
    ($device:ident, $spec:literal, $examples:ident, $round_trip:ident) => {
        #[test]
        fn $examples() {
            use $device::serial;
            let d = spec($spec);
            let default_start = match d.serial.as_ref().map(|s| &s.framing) {
                Some(coforge_spec::model::Framing::StartLengthCrc { start_byte, .. }) => Some(*start_byte),
                _ => None,
            };
            let mut n = 0;
            for cmd in &d.serial.as_ref().expect("serial").commands {
                for ex in &cmd.examples {
                    let (code, length_code, data) =
                        deframe(&mut serial::decoder(), &ex.bytes).unwrap_or_else(|| panic!("`{}` {:02X?} does not deframe", cmd.name, ex.bytes));
                    let frame = Frame { code, length_code, network: None, data: &data };
                    let mut out = [0_u8; 300];
                    let encoded = match cmd.direction {
                        Direction::HostToDevice => {
                            let x = serial::HostToDevice::decode(&frame).unwrap_or_else(|e| panic!("`{}` {:02X?}: {e:?}", cmd.name, ex.bytes));
                            assert_eq!(x.name(), cmd.name, "{:02X?}", ex.bytes);
                            x.encode(&mut out)
                        }
                        Direction::DeviceToHost => {
                            let x = serial::DeviceToHost::decode(&frame).unwrap_or_else(|e| panic!("`{}` {:02X?}: {e:?}", cmd.name, ex.bytes));
                            assert_eq!(x.name(), cmd.name, "{:02X?}", ex.bytes);
                            x.encode(&mut out)
                        }
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

        proptest! {
            #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]
            #[test]
            fn $round_trip(code in any::<u8>(), extension in proptest::option::of(0x80_u8..), data in proptest::collection::vec(any::<u8>(), 0..40)) {
                use $device::serial;
                let frame = Frame { code, length_code: extension, network: None, data: &data };
                let mut out = [0_u8; 300];
                if let Ok(x) = serial::HostToDevice::decode(&frame) {
                    let len = x.encode(&mut out).expect("a decoded command encodes");
                    let (c, l, d) = deframe(&mut serial::decoder(), &out[..len]).expect("an encoded frame deframes");
                    prop_assert_eq!(serial::HostToDevice::decode(&Frame { code: c, length_code: l, network: None, data: &d }), Ok(x));
                }
                if let Ok(x) = serial::DeviceToHost::decode(&frame) {
                    let len = x.encode(&mut out).expect("a decoded command encodes");
                    let (c, l, d) = deframe(&mut serial::decoder(), &out[..len]).expect("an encoded frame deframes");
                    prop_assert_eq!(serial::DeviceToHost::decode(&Frame { code: c, length_code: l, network: None, data: &d }), Ok(x));
                }
            }
        }
    };
}

device_codec_tests!(co401memory1, "co401memory1.yaml", co401memory1_examples_round_trip, co401memory1_decode_encode_identity);
device_codec_tests!(co401gw1, "co401gw1.yaml", co401gw1_examples_round_trip, co401gw1_decode_encode_identity);
device_codec_tests!(canopenia, "canopenia.yaml", canopenia_examples_round_trip, canopenia_decode_encode_identity);
