//! Every example frame of every spec decodes through the `no_std` streaming decoders exactly
//! as the spec's own (host-side) rules split it: the firmware and the spec agree on the wire.

use coforge_link::Deframer;
use coforge_link::crc::{Crc16, CrcParams};
use coforge_link::length_byte::{LengthByteConfig, LengthByteDecoder};
use coforge_link::nibble::{NibbleConfig, NibbleDecoder};
use coforge_link::start_crc::{LengthCounts, StartBits, StartCrcConfig, StartCrcDecoder};
use coforge_spec::model::{self, Framing};
use std::path::PathBuf;

fn decoder(framing: &Framing) -> Box<dyn Deframer> {
    match framing {
        Framing::NibbleLength { resync_pause_ms } => Box::new(NibbleDecoder::new(NibbleConfig { resync_pause_ms: *resync_pause_ms })),
        Framing::LengthByte { inter_byte_timeout_ms, resync_pause_ms, extension_threshold } => Box::new(LengthByteDecoder::<255>::new(LengthByteConfig {
            inter_byte_timeout_ms: *inter_byte_timeout_ms,
            resync_pause_ms: *resync_pause_ms,
            extension_threshold: *extension_threshold,
        })),
        Framing::StartLengthCrc { start_byte, start_bits, length_bytes, length_counts, max_payload, crc } => {
            let params = CrcParams {
                poly: crc.poly as u16,
                init: crc.init as u16,
                reflect_in: crc.reflect_in,
                reflect_out: crc.reflect_out,
                xor_out: crc.xor_out as u16,
            };
            let table: &'static Crc16 = Box::leak(Box::new(Crc16::new(params)));
            Box::new(StartCrcDecoder::<512>::new(StartCrcConfig {
                start_byte: *start_byte,
                start_bits: start_bits.map(|b| StartBits { network: b.network, crc: b.crc, long_length: b.long_length }),
                length_bytes: *length_bytes,
                length_counts: match length_counts {
                    model::LengthCounts::Payload => LengthCounts::Payload,
                    model::LengthCounts::PayloadAndCrc => LengthCounts::PayloadAndCrc,
                    model::LengthCounts::Frame => LengthCounts::Frame,
                },
                max_payload: *max_payload,
                crc: table,
                crc_little_endian: crc.little_endian,
                crc_covers_start: crc.covers_start,
                crc_covers_length: crc.covers_length,
                inter_byte_timeout_ms: None,
            }))
        }
    }
}

#[test]
fn every_spec_example_decodes_through_the_firmware_decoders() {
    let mut checked = 0;
    for name in ["co401memory1.yaml", "co401gw1.yaml", "canopenia.yaml"] {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../spec").join(name);
        let device = coforge_spec::load_file(&path).into_device().unwrap_or_else(|| panic!("{name} loads"));
        let serial = device.serial.as_ref().expect("serial protocol");
        for cmd in &serial.commands {
            for ex in &cmd.examples {
                let want = coforge_spec::frame::split(&serial.framing, &ex.bytes).expect("the spec decodes its own example");
                let mut d = decoder(&serial.framing);
                let mut frames = Vec::new();
                for (i, &b) in ex.bytes.iter().enumerate() {
                    if let Some(r) = d.push(b, i as u32) {
                        frames.push(r.map(|f| (u32::from(f.code), f.length_code.map(u32::from), f.data.to_vec())));
                    }
                }
                assert_eq!(frames, [Ok((want.code, want.length_code, want.data.clone()))], "{name} `{}` example {:02X?}", cmd.name, ex.bytes);
                checked += 1;
            }
        }
    }
    assert!(checked >= 40, "only {checked} example vectors");
}
