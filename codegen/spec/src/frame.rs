//! Decoding whole frames by a spec's own framing and command table. Used to check the
//! datasheet examples, and by `coforge decode`.

use crate::model::{Command, Device, Direction, ExampleValue, FieldType, Framing, LengthCounts, Serial};
use std::collections::BTreeMap;

/// A frame split by the framing rule: the command code byte(s) and the data after them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Split {
    pub code: u32,
    /// DataLen byte >= the extension threshold (length_byte framing only).
    pub length_code: Option<u32>,
    pub data: Vec<u8>,
}

/// Splits a frame per the framing rule, checking lengths, start byte and CRC.
pub fn split(framing: &Framing, bytes: &[u8]) -> Result<Split, String> {
    match framing {
        Framing::NibbleLength { .. } => {
            let (&head, data) = bytes.split_first().ok_or("the frame is empty")?;
            let len = usize::from(head & 0x0F);
            if data.len() != len {
                return Err(format!("the length nibble says {len} data bytes but {} follow", data.len()));
            }
            Ok(Split { code: u32::from(head >> 4), length_code: None, data: data.to_vec() })
        }
        Framing::LengthByte { extension_threshold, .. } => {
            let [code, len, data @ ..] = bytes else { return Err("a frame needs a command byte and a DataLen byte".into()) };
            if *len >= *extension_threshold {
                return Ok(Split { code: u32::from(*code), length_code: Some(u32::from(*len)), data: data.to_vec() });
            }
            if data.len() != usize::from(*len) {
                return Err(format!("DataLen says {len} data bytes but {} follow", data.len()));
            }
            Ok(Split { code: u32::from(*code), length_code: None, data: data.to_vec() })
        }
        Framing::StartLengthCrc { start_byte, start_bits, length_bytes, length_counts, max_payload, crc } => {
            let (&start, rest) = bytes.split_first().ok_or("the frame is empty")?;
            // With option bits the start byte chooses CRC and length width; otherwise it is fixed.
            let (has_crc, width) = match start_bits {
                Some(bits) => bits.options(start, *length_bytes)?,
                None if start == *start_byte => (true, *length_bytes),
                None => return Err(format!("the frame starts with {start:#04X}, not the start byte {start_byte:#04X}")),
            };
            let lb = usize::from(width);
            let len_raw = rest.get(..lb).ok_or("the frame ends inside the length field")?;
            let declared = len_raw.iter().rev().fold(0_usize, |acc, &b| acc << 8 | usize::from(b));
            let crc_len = if has_crc { usize::from(crc.width).div_ceil(8) } else { 0 };
            let payload_len = match length_counts {
                LengthCounts::Payload => Some(declared),
                LengthCounts::PayloadAndCrc => declared.checked_sub(crc_len),
                LengthCounts::Frame => declared.checked_sub(1 + lb + crc_len),
            }
            .ok_or_else(|| format!("the length field ({declared}) is too small for the frame overhead"))?;
            if payload_len > usize::from(*max_payload) {
                return Err(format!("the payload is {payload_len} bytes; the maximum is {max_payload}"));
            }
            let after_len = &rest[lb..];
            if after_len.len() != payload_len + crc_len {
                return Err(format!(
                    "the length field says a {payload_len}-byte payload, so the frame should be {} bytes, but it is {}",
                    1 + lb + payload_len + crc_len,
                    bytes.len()
                ));
            }
            let (payload, crc_bytes) = after_len.split_at(payload_len);
            let mut covered = Vec::new();
            if crc.covers_start {
                covered.push(start);
            }
            if crc.covers_length {
                covered.extend_from_slice(len_raw);
            }
            if crc.covers_payload {
                covered.extend_from_slice(payload);
            }
            if !has_crc {
                let (&code, data) = payload.split_first().ok_or("the payload is empty: no command code")?;
                return Ok(Split { code: u32::from(code), length_code: None, data: data.to_vec() });
            }
            let got = if crc.little_endian {
                crc_bytes.iter().rev().fold(0_u64, |a, &b| a << 8 | u64::from(b))
            } else {
                crc_bytes.iter().fold(0_u64, |a, &b| a << 8 | u64::from(b))
            };
            let want = crc.compute(&covered);
            if got != want {
                return Err(format!("the CRC is {got:#06X} but the covered bytes give {want:#06X}"));
            }
            let (&code, data) = payload.split_first().ok_or("the payload is empty: no command code")?;
            Ok(Split { code: u32::from(code), length_code: None, data: data.to_vec() })
        }
    }
}

/// Decodes a command's fields from its data; values of integer fields as integers.
pub fn decode_fields(cmd: &Command, split: &Split) -> Result<BTreeMap<String, ExampleValue>, String> {
    let data = &split.data;
    let n = u32::try_from(data.len()).unwrap_or(u32::MAX);
    if split.length_code.is_none() && (n < cmd.length.0 || n > cmd.length.1) {
        let want = if cmd.length.0 == cmd.length.1 { cmd.length.0.to_string() } else { format!("{}..={}", cmd.length.0, cmd.length.1) };
        return Err(format!("`{}` carries {want} data bytes, this frame has {n}", cmd.name));
    }
    let mut out = BTreeMap::new();
    if let Some(p) = &cmd.code_param {
        out.insert(p.name.clone(), ExampleValue::Int(i64::from((split.code & p.mask) >> p.mask.trailing_zeros())));
    }
    for f in &cmd.fields {
        let at = usize::try_from(f.at).unwrap_or(usize::MAX);
        let value = match f.ty {
            FieldType::Tail { max } => {
                let tail = data.get(at..).unwrap_or(&[]);
                if tail.len() > usize::try_from(max).unwrap_or(usize::MAX) {
                    return Err(format!("field `{}` has {} bytes; at most {max}", f.name, tail.len()));
                }
                ExampleValue::Bytes(tail.to_vec())
            }
            FieldType::Bytes(size) => ExampleValue::Bytes(
                data.get(at..at + usize::try_from(size).unwrap_or(0)).ok_or_else(|| format!("the frame ends inside field `{}`", f.name))?.to_vec(),
            ),
            FieldType::Unsigned(size) | FieldType::Signed(size) => {
                let raw = data.get(at..at + usize::from(size)).ok_or_else(|| format!("the frame ends inside field `{}`", f.name))?;
                let mut v = if f.big_endian {
                    raw.iter().fold(0_i64, |a, &b| a << 8 | i64::from(b))
                } else {
                    raw.iter().rev().fold(0_i64, |a, &b| a << 8 | i64::from(b))
                };
                if matches!(f.ty, FieldType::Signed(_)) && v >> (8 * size - 1) & 1 == 1 {
                    v -= 1 << (8 * size);
                }
                ExampleValue::Int(v)
            }
        };
        out.insert(f.name.clone(), value);
    }
    Ok(out)
}

/// Finds the commands a frame could be, in one direction.
pub fn candidates<'a>(serial: &'a Serial, direction: Direction, split: &Split) -> Vec<&'a Command> {
    serial.commands.iter().filter(|c| c.direction == direction && c.codes().contains(&split.code) && c.length_code == split.length_code).collect()
}

/// Decodes a hex frame into readable lines, one per command it can be (`coforge decode`).
pub fn describe(device: &Device, hex: &str, direction: Option<Direction>) -> Result<String, String> {
    let serial = device.serial.as_ref().ok_or_else(|| format!("{} has no serial protocol", device.identity.name))?;
    let bytes: Vec<u8> = crate::normalize::hex_bytes(hex, false)?.into_iter().flatten().collect();
    let split = split(&serial.framing, &bytes)?;
    let dirs = match direction {
        Some(d) => vec![d],
        None => vec![Direction::HostToDevice, Direction::DeviceToHost],
    };
    let mut out = String::new();
    let mut problems = Vec::new();
    for dir in dirs {
        for cmd in candidates(serial, dir, &split) {
            match decode_fields(cmd, &split) {
                Ok(values) => {
                    let fields: Vec<String> = values
                        .iter()
                        .map(|(k, v)| match v {
                            ExampleValue::Int(i) => format!("{k}={i:#X}"),
                            ExampleValue::Bytes(b) => format!("{k}=[{}]", b.iter().map(|x| format!("{x:02X}")).collect::<Vec<_>>().join(" ")),
                        })
                        .collect();
                    out.push_str(&format!("{} ({}, {}): {}\n", cmd.name, dir.name(), cmd.kind.name(), fields.join(" ")));
                }
                Err(e) => problems.push(format!("`{}`: {e}", cmd.name)),
            }
        }
    }
    if out.is_empty() {
        return Err(if problems.is_empty() { format!("no command uses code {:#04X}", split.code) } else { problems.join("; ") });
    }
    Ok(out)
}
