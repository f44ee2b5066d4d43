//! `serial:`: settings, framing, CRC parameters, commands and their fields.

use super::host_access::host_rule;
use super::{Cx, hex_bytes, scalar_kind, span};
use crate::diag::Span;
use crate::expr::{Expr, Vars};
use crate::model::{
    Ack, CodeParam, Command, CommandKind, CrcParams, Direction, ErrorBit, Example, ExampleValue, Field, FieldType, Framing, HostRead, HostRule, HostWrite,
    LengthCounts, Serial, SerialSettings, StartBits,
};
use crate::raw::{self, Num, S, Scalar};
use std::collections::BTreeMap;

pub(super) fn serial(cx: &mut Cx<'_>, s: &S<raw::Serial>) -> Option<Serial> {
    let v = &s.value;
    let framing = framing(cx, &v.framing)?;
    let none = Vars::new();
    let host_access = match &v.host_access {
        Some(h) => host_rule(cx, h)?,
        None => HostRule { read: HostRead::None, write: HostWrite::None, readable: Vec::new(), writable: Vec::new(), description: String::new() },
    };
    let error_bits = v
        .error_bits
        .iter()
        .filter_map(|b| {
            Some(ErrorBit {
                bit: cx.int_in(&b.value.bit, &none, "error bit", 0, 63)?,
                name: b.value.name.value.clone(),
                description: b.value.description.clone().unwrap_or_default(),
                span: span(b),
            })
        })
        .collect();
    let commands = v.commands.iter().filter_map(|c| command(cx, c, &framing)).collect();
    let settings =
        v.settings.as_ref().map(|st| SerialSettings { data_bits: st.value.data_bits, parity: st.value.parity.value.clone(), stop_bits: st.value.stop_bits });
    Some(Serial {
        settings,
        framing,
        host_access,
        error_bits,
        commands,
        description: v.description.clone().unwrap_or_default(),
        framing_span: span(&v.framing),
    })
}

fn framing(cx: &mut Cx<'_>, f: &S<raw::Framing>) -> Option<Framing> {
    let none = Vars::new();
    let v = &f.value;
    let at = span(f);
    // Which keys each kind takes, so that a key meant for another kind is reported.
    let given: [(&str, Option<Span>); 9] = [
        ("resync_pause_ms", v.resync_pause_ms.as_ref().map(span)),
        ("inter_byte_timeout_ms", v.inter_byte_timeout_ms.as_ref().map(span)),
        ("extension_threshold", v.extension_threshold.as_ref().map(span)),
        ("start_byte", v.start_byte.as_ref().map(span)),
        ("start_byte_bits", v.start_byte_bits.as_ref().map(span)),
        ("length_bytes", v.length_bytes.as_ref().map(span)),
        ("length_counts", v.length_counts.as_ref().map(span)),
        ("max_payload", v.max_payload.as_ref().map(span)),
        ("crc", v.crc.as_ref().map(span)),
    ];
    let allowed: &[&str] = match v.kind.value.as_str() {
        "nibble_length" => &["resync_pause_ms"],
        "length_byte" => &["resync_pause_ms", "inter_byte_timeout_ms", "extension_threshold"],
        "start_length_crc" => {
            &["start_byte", "start_byte_bits", "length_bytes", "length_counts", "max_payload", "crc", "resync_pause_ms", "inter_byte_timeout_ms"]
        }
        other => {
            cx.err("spec-value", span(&v.kind), format!("unknown framing kind `{other}`; expected one of: nibble_length, length_byte, start_length_crc"));
            return None;
        }
    };
    for (key, sp) in given {
        if let Some(sp) = sp
            && !allowed.contains(&key)
        {
            cx.err("spec-structure", sp, format!("`{key}` does not apply to `{}` framing", v.kind.value));
        }
    }
    let mut need = |n: &Option<Num>, key: &str, lo: i64, hi: i64| -> Option<i64> {
        match n {
            Some(n) => cx.int_in(n, &none, key, lo, hi),
            None => {
                cx.err("spec-structure", at, format!("`{}` framing needs `{key}`", v.kind.value));
                None
            }
        }
    };
    Some(match v.kind.value.as_str() {
        "nibble_length" => Framing::NibbleLength { resync_pause_ms: u32::try_from(need(&v.resync_pause_ms, "resync_pause_ms", 1, 60_000)?).ok()? },
        "length_byte" => Framing::LengthByte {
            inter_byte_timeout_ms: u32::try_from(need(&v.inter_byte_timeout_ms, "inter_byte_timeout_ms", 1, 60_000)?).ok()?,
            resync_pause_ms: u32::try_from(need(&v.resync_pause_ms, "resync_pause_ms", 1, 60_000)?).ok()?,
            extension_threshold: u8::try_from(need(&v.extension_threshold, "extension_threshold", 1, 0xFF)?).ok()?,
        },
        _ => {
            let start_byte = u8::try_from(need(&v.start_byte, "start_byte", 0, 0xFF)?).ok()?;
            let length_bytes = u8::try_from(need(&v.length_bytes, "length_bytes", 1, 2)?).ok()?;
            let max_payload = u16::try_from(need(&v.max_payload, "max_payload", 1, 0xFFFF)?).ok()?;
            let length_counts = match &v.length_counts {
                Some(l) => cx.keyword(
                    l,
                    "length_counts",
                    |s| match s {
                        "payload" => Some(LengthCounts::Payload),
                        "payload_and_crc" => Some(LengthCounts::PayloadAndCrc),
                        "frame" => Some(LengthCounts::Frame),
                        _ => None,
                    },
                    "payload, payload_and_crc, frame",
                )?,
                None => LengthCounts::Payload,
            };
            let Some(crc) = &v.crc else {
                cx.err("spec-structure", at, "`start_length_crc` framing needs `crc`");
                return None;
            };
            let start_bits = match &v.start_byte_bits {
                Some(b) => {
                    let mut mask = |n: &Num, what: &str| cx.int_in::<u8>(n, &none, what, 1, 0xFF);
                    let bits = StartBits {
                        network: mask(&b.value.network, "network mask")?,
                        crc: mask(&b.value.crc, "crc flag")?,
                        long_length: mask(&b.value.long_length, "long_length flag")?,
                    };
                    if bits.network & bits.crc != 0 || bits.network & bits.long_length != 0 || bits.crc & bits.long_length != 0 {
                        cx.err("spec-structure", span(b), "the start byte's `network`, `crc` and `long_length` bits must not overlap");
                        return None;
                    }
                    if let Err(e) = bits.options(start_byte, length_bytes) {
                        cx.err("spec-value", span(b), format!("the default {e}"));
                        return None;
                    }
                    Some(bits)
                }
                None => None,
            };
            Framing::StartLengthCrc { start_byte, start_bits, length_bytes, length_counts, max_payload, crc: crc_params(cx, crc)? }
        }
    })
}

fn crc_params(cx: &mut Cx<'_>, c: &S<raw::Crc>) -> Option<CrcParams> {
    let none = Vars::new();
    let v = &c.value;
    let width: u8 = cx.int_in(&v.width, &none, "crc width", 8, 64)?;
    let max = if width == 64 { i64::MAX } else { (1_i64 << width) - 1 };
    let mut p = |n: &Num, what: &str| cx.int_in::<u64>(n, &none, what, 0, max);
    let (poly, init, xor_out, check) = (p(&v.poly, "poly")?, p(&v.init, "init")?, p(&v.xor_out, "xor_out")?, p(&v.check, "check")?);
    let little_endian = cx.keyword(
        &v.byte_order,
        "byte order",
        |s| match s {
            "little" => Some(true),
            "big" => Some(false),
            _ => None,
        },
        "little, big",
    )?;
    let mut covers = (false, false, false);
    for part in &v.covers.value {
        match part.value.as_str() {
            "start" => covers.0 = true,
            "length" => covers.1 = true,
            "payload" => covers.2 = true,
            other => cx.err("spec-value", span(part), format!("unknown CRC coverage `{other}`; expected start, length, payload")),
        }
    }
    Some(CrcParams {
        width,
        poly,
        init,
        reflect_in: v.reflect_in,
        reflect_out: v.reflect_out,
        xor_out,
        check,
        little_endian,
        covers_start: covers.0,
        covers_length: covers.1,
        covers_payload: covers.2,
        check_span: span(&v.check),
    })
}

fn command(cx: &mut Cx<'_>, c: &S<raw::Command>, framing: &Framing) -> Option<Command> {
    let none = Vars::new();
    let v = &c.value;
    let code_max: i64 = match framing {
        Framing::NibbleLength { .. } => 0xF,
        _ => 0xFF,
    };
    let code = match &v.code.value {
        Scalar::Str(s) if s.chars().count() == 1 && !s.starts_with(|ch: char| ch.is_ascii_digit()) => u32::from(s.chars().next().unwrap_or('\0')),
        _ => cx.int_in(&v.code, &none, "command code", 0, code_max)?,
    };
    if i64::from(code) > code_max {
        cx.err("spec-value", span(&v.code), format!("command code {code:#X} does not fit the {} framing (at most {code_max:#X})", framing.kind()));
        return None;
    }
    let code_param = match &v.code_param {
        Some(p) => Some(CodeParam {
            name: p.value.name.value.clone(),
            mask: cx.int_in(&p.value.mask, &none, "code_param mask", 1, code_max)?,
            range: match &p.value.range {
                Some(r) => Some((cx.int_in(&r.value.0, &none, "range start", 0, code_max)?, cx.int_in(&r.value.1, &none, "range end", 0, code_max)?)),
                None => None,
            },
            values: match &p.value.values {
                Some(list) => {
                    if p.value.range.is_some() {
                        cx.err("spec-structure", span(list), "`code_param` takes either `range` or `values`");
                    }
                    let mut v = Vec::new();
                    for n in &list.value {
                        v.push(cx.int_in(n, &none, "code parameter value", 0, code_max)?);
                    }
                    Some(v)
                }
                None => None,
            },
        }),
        None => None,
    };
    let direction = cx.keyword(
        &v.direction,
        "direction",
        |s| match s {
            "host_to_device" => Some(Direction::HostToDevice),
            "device_to_host" => Some(Direction::DeviceToHost),
            _ => None,
        },
        "host_to_device, device_to_host",
    )?;
    let kind = cx.keyword(
        &v.kind,
        "command kind",
        |s| match s {
            "request" => Some(CommandKind::Request),
            "response" => Some(CommandKind::Response),
            "command" => Some(CommandKind::Command),
            "ack" => Some(CommandKind::Ack),
            "indication" => Some(CommandKind::Indication),
            _ => None,
        },
        "request, response, command, ack, indication",
    )?;
    let fields = fields(cx, &v.fields, framing)?;
    let fixed: u32 = fields.iter().map(|f| f.ty.fixed_size()).sum();
    let tail_max = fields.iter().find_map(|f| match f.ty {
        FieldType::Tail { max } => Some(max),
        _ => None,
    });
    let len_int = |cx: &mut Cx<'_>, s: &Scalar, sp: &S<raw::Length>| -> Option<u32> {
        cx.int_in(&S { value: s.clone(), referenced: sp.referenced, defined: sp.defined }, &none, "length", 0, 0xFFFF)
    };
    let length = match &v.length {
        Some(l) => match &l.value {
            raw::Length::Fixed(n) => {
                let n = len_int(cx, n, l)?;
                (n, n)
            }
            raw::Length::Range { min, max } => (len_int(cx, min, l)?, len_int(cx, max, l)?),
        },
        None => (fixed, fixed + tail_max.unwrap_or(0)),
    };
    let ack = match &v.ack {
        Some(a) => Some(Ack {
            field: a.value.field.value.clone(),
            positive: cx.int(&a.value.positive, &none, "positive")?,
            negative: cx.int(&a.value.negative, &none, "negative")?,
            span: span(a),
        }),
        None => None,
    };
    let mut examples = Vec::new();
    for ex in &v.examples {
        let bytes = match &ex.value.bytes.value {
            Scalar::Str(s) => match hex_bytes(s, false) {
                Ok(b) => b.into_iter().flatten().collect(),
                Err(m) => {
                    cx.err("spec-value", span(&ex.value.bytes), m);
                    continue;
                }
            },
            Scalar::Int(i) if (0..=255).contains(i) => vec![u8::try_from(*i).unwrap_or(0)],
            other => {
                cx.err("spec-value", span(&ex.value.bytes), format!("example `bytes` must be hex bytes such as `33 12 50 04`, found {}", scalar_kind(other)));
                continue;
            }
        };
        let mut values = BTreeMap::new();
        for (name, val) in &ex.value.fields {
            // Strings for byte fields are hex bytes (`"81"` is one byte 0x81); for integer
            // fields they are expressions.
            let byte_field = fields.iter().any(|f| &f.name == name && matches!(f.ty, FieldType::Bytes(_) | FieldType::Tail { .. }));
            let parsed = match &val.value {
                Scalar::Int(i) => i64::try_from(*i).ok().map(ExampleValue::Int),
                Scalar::Str(s) if byte_field => hex_bytes(s, false).ok().map(|b| ExampleValue::Bytes(b.into_iter().flatten().collect())),
                Scalar::Str(s) => Expr::parse(s).and_then(|e| e.eval(&none, None)).ok().map(ExampleValue::Int),
                _ => None,
            };
            match parsed {
                Some(p) => {
                    values.insert(name.clone(), (p, span(val)));
                }
                None => cx.err("spec-value", span(val), format!("example value for `{name}` must be an integer or hex bytes")),
            }
        }
        examples.push(Example { bytes, fields: values, note: ex.value.note.clone().unwrap_or_default(), span: span(ex) });
    }
    Some(Command {
        name: v.name.value.clone(),
        code,
        code_param,
        direction,
        kind,
        reply: v.reply.as_ref().map(|r| r.value.clone()),
        length,
        length_code: match &v.length_code {
            Some(n) => Some(cx.int_in(n, &none, "length_code", 0, 0xFF)?),
            None => None,
        },
        ack,
        description: v.description.clone().unwrap_or_default(),
        fields,
        examples,
        modes: cx.modes(v.modes.as_ref(), &None),
        span: span(c),
        code_span: span(&v.code),
        length_span: v.length.as_ref().map_or(span(c), span),
        reply_span: v.reply.as_ref().map_or(span(c), span),
    })
}

fn fields(cx: &mut Cx<'_>, list: &[S<raw::Field>], framing: &Framing) -> Option<Vec<Field>> {
    let none = Vars::new();
    let mut out = Vec::new();
    let mut next = 0_u32;
    let mut ok = true;
    for f in list {
        let v = &f.value;
        let ty = match v.field_type.value.as_str() {
            "u8" => FieldType::Unsigned(1),
            "u16" => FieldType::Unsigned(2),
            "u24" => FieldType::Unsigned(3),
            "u32" => FieldType::Unsigned(4),
            "i8" => FieldType::Signed(1),
            "i16" => FieldType::Signed(2),
            "i32" => FieldType::Signed(4),
            "bytes" => match &v.size {
                Some(n) => FieldType::Bytes(cx.int_in(n, &none, "size", 1, 0xFFFF)?),
                None => {
                    cx.err("spec-structure", span(f), "a `bytes` field needs `size`");
                    ok = false;
                    continue;
                }
            },
            "tail" => FieldType::Tail {
                max: match &v.max {
                    Some(n) => cx.int_in(n, &none, "max", 0, 0xFFFF)?,
                    None => framing.max_data().saturating_sub(next),
                },
            },
            other => {
                cx.err(
                    "spec-value",
                    span(&v.field_type),
                    format!("unknown field type `{other}`; expected one of: u8, u16, u24, u32, i8, i16, i32, bytes, tail"),
                );
                ok = false;
                continue;
            }
        };
        if v.size.is_some() && !matches!(ty, FieldType::Bytes(_)) {
            cx.err("spec-structure", span(f), "`size` only applies to `bytes` fields");
        }
        if v.max.is_some() && !matches!(ty, FieldType::Tail { .. }) {
            cx.err("spec-structure", span(f), "`max` only applies to `tail` fields");
        }
        let big_endian = match &v.order {
            Some(o) => cx.keyword(
                o,
                "byte order",
                |s| match s {
                    "le" => Some(false),
                    "be" => Some(true),
                    _ => None,
                },
                "le, be",
            )?,
            None => false,
        };
        let at = match &v.at {
            Some(n) => cx.int_in(n, &none, "at", 0, 0xFFFF)?,
            None => next,
        };
        next = at + ty.fixed_size();
        out.push(Field {
            name: v.name.value.clone(),
            ty,
            big_endian,
            at,
            explicit_at: v.at.is_some(),
            description: v.description.clone().unwrap_or_default(),
            span: span(f),
        });
    }
    ok.then_some(out)
}
