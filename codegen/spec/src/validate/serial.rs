//! Serial protocol rules: command table, field layout, datasheet examples, CRC.

use crate::diag::{Diagnostic, Diagnostics};
use crate::frame;
use crate::model::{Command, Device, ExampleValue, FieldType, Framing, modes_overlap};
use std::collections::BTreeMap;

fn commands(d: &Device) -> &[Command] {
    d.serial.as_ref().map_or(&[], |s| &s.commands)
}

fn codes_text(c: &Command) -> String {
    let codes = c.codes();
    match (codes.first(), codes.last()) {
        (Some(a), Some(b)) if a != b => format!("{a:#04X}..={b:#04X}"),
        (Some(a), _) => format!("{a:#04X}"),
        _ => String::new(),
    }
}

pub fn code_collision(d: &Device, diags: &mut Diagnostics) {
    let cmds = commands(d);
    for (i, a) in cmds.iter().enumerate() {
        for b in &cmds[i + 1..] {
            if a.direction != b.direction || a.length_code != b.length_code || !modes_overlap(&a.modes, &b.modes) {
                continue;
            }
            let codes_b = b.codes();
            if let Some(code) = a.codes().into_iter().find(|c| codes_b.contains(c)) {
                diags.push(
                    Diagnostic::error(
                        "serial-code-collision",
                        b.code_span,
                        format!("`{}` and `{}` both use code {code:#04X} in direction {}", a.name, b.name, a.direction.name()),
                    )
                    .note_at(a.code_span, format!("`{}` uses {}", a.name, codes_text(a))),
                );
            }
        }
    }
}

pub fn length(d: &Device, diags: &mut Diagnostics) {
    let Some(serial) = &d.serial else { return };
    for c in &serial.commands {
        let fixed = c.fixed_size();
        let (min, max) = c.length;
        let ok = match c.tail() {
            Some(t) => {
                let tail_max = match t.ty {
                    FieldType::Tail { max } => max,
                    _ => 0,
                };
                min <= max && min >= fixed && max <= fixed + tail_max
            }
            None => min == fixed && max == fixed,
        };
        if !ok {
            let declared = if min == max { min.to_string() } else { format!("{min}..={max}") };
            let sum = match c.tail() {
                Some(_) => format!("{fixed} fixed bytes plus a tail"),
                None => format!("{fixed} bytes"),
            };
            diags.push(Diagnostic::error("serial-length", c.length_span, format!("`{}` declares length {declared} but its fields take {sum}", c.name)));
        }
        if let Some(code) = c.length_code {
            match serial.framing {
                Framing::LengthByte { extension_threshold, .. } if code >= u32::from(extension_threshold) => {}
                Framing::LengthByte { extension_threshold, .. } => diags.push(Diagnostic::error(
                    "serial-length",
                    c.span,
                    format!(
                        "`length_code` {code:#04X} of `{}` is below the extension threshold {extension_threshold:#04X}; use `length` for real lengths",
                        c.name
                    ),
                )),
                _ => diags.push(Diagnostic::error("serial-length", c.span, format!("`length_code` of `{}` only applies to `length_byte` framing", c.name))),
            }
        }
    }
}

pub fn field_layout(d: &Device, diags: &mut Diagnostics) {
    let Some(serial) = &d.serial else { return };
    let frame_max = serial.framing.max_data();
    for c in &serial.commands {
        let mut names: BTreeMap<&str, ()> = BTreeMap::new();
        if let Some(p) = &c.code_param {
            names.insert(p.name.as_str(), ());
        }
        for (i, f) in c.fields.iter().enumerate() {
            if names.insert(f.name.as_str(), ()).is_some() {
                diags.push(Diagnostic::error("serial-field-layout", f.span, format!("field name `{}` is used twice in `{}`", f.name, c.name)));
            }
            if matches!(f.ty, FieldType::Tail { .. }) && i + 1 != c.fields.len() {
                diags.push(Diagnostic::error("serial-field-layout", f.span, format!("tail field `{}` of `{}` must be the last field", f.name, c.name)));
            }
            for g in &c.fields[..i] {
                let (a0, a1) = (g.at, g.at + g.ty.fixed_size().max(1));
                let (b0, b1) = (f.at, f.at + f.ty.fixed_size().max(1));
                if a0 < b1 && b0 < a1 {
                    diags.push(
                        Diagnostic::error(
                            "serial-field-layout",
                            f.span,
                            format!("field `{}` (bytes {b0}..{b1}) overlaps `{}` (bytes {a0}..{a1}) in `{}`", f.name, g.name, c.name),
                        )
                        .note_at(g.span, "the other field"),
                    );
                }
            }
            let end = f.at + f.ty.fixed_size();
            if end > c.length.1 {
                diags.push(Diagnostic::error(
                    "serial-field-layout",
                    f.span,
                    format!("field `{}` ends at byte {end}, past the {} data bytes of `{}`", f.name, c.length.1, c.name),
                ));
            }
        }
        if c.length.1 > frame_max && c.length_code.is_none() {
            diags.push(Diagnostic::error(
                "serial-field-layout",
                c.length_span,
                format!("`{}` carries up to {} data bytes; {} framing allows at most {frame_max}", c.name, c.length.1, serial.framing.kind()),
            ));
        }
    }
}

pub fn example(d: &Device, diags: &mut Diagnostics) {
    let Some(serial) = &d.serial else { return };
    for c in &serial.commands {
        for ex in &c.examples {
            let fail = |msg: String| Diagnostic::error("serial-example", ex.span, format!("example of `{}` does not decode: {msg}", c.name));
            let split = match frame::split(&serial.framing, &ex.bytes) {
                Ok(s) => s,
                Err(e) => {
                    diags.push(fail(e));
                    continue;
                }
            };
            if !c.codes().contains(&split.code) || c.length_code != split.length_code {
                let found = frame::candidates(serial, c.direction, &split).iter().map(|o| format!("`{}`", o.name)).collect::<Vec<_>>();
                let which = if found.is_empty() { "no command".to_string() } else { found.join(", ") };
                diags.push(fail(format!("its code {:#04X} selects {which}, not `{}` ({})", split.code, c.name, codes_text(c))));
                continue;
            }
            let values = match frame::decode_fields(c, &split) {
                Ok(v) => v,
                Err(e) => {
                    diags.push(fail(e));
                    continue;
                }
            };
            for (name, (want, at)) in &ex.fields {
                match values.get(name) {
                    None => diags.push(Diagnostic::error(
                        "serial-example",
                        *at,
                        format!("example of `{}` names field `{name}`, which the command does not have", c.name),
                    )),
                    Some(got) if !same(got, want) => diags.push(Diagnostic::error(
                        "serial-example",
                        *at,
                        format!("example of `{}`: field `{name}` decodes as {} but the example says {}", c.name, show(got), show(want)),
                    )),
                    Some(_) => {}
                }
            }
        }
    }
}

fn same(a: &ExampleValue, b: &ExampleValue) -> bool {
    match (a, b) {
        (ExampleValue::Bytes(x), ExampleValue::Int(i)) | (ExampleValue::Int(i), ExampleValue::Bytes(x)) => x.len() == 1 && i64::from(x[0]) == *i,
        _ => a == b,
    }
}

fn show(v: &ExampleValue) -> String {
    match v {
        ExampleValue::Int(i) => format!("{i:#X}"),
        ExampleValue::Bytes(b) => format!("[{}]", b.iter().map(|x| format!("{x:02X}")).collect::<Vec<_>>().join(" ")),
    }
}

pub fn reply(d: &Device, diags: &mut Diagnostics) {
    let cmds = commands(d);
    for c in cmds {
        if let Some(r) = &c.reply {
            match cmds.iter().find(|o| &o.name == r) {
                None => diags.push(Diagnostic::error("serial-reply", c.reply_span, format!("`{}` is answered by `{r}`, which is not a command", c.name))),
                Some(o) if o.direction == c.direction => diags.push(
                    Diagnostic::error("serial-reply", c.reply_span, format!("`{}` and its reply `{r}` travel in the same direction", c.name))
                        .note_at(o.span, "the reply"),
                ),
                Some(_) => {}
            }
        }
        if let Some(ack) = &c.ack
            && !c.fields.iter().any(|f| f.name == ack.field)
        {
            diags.push(Diagnostic::error(
                "serial-reply",
                ack.span,
                format!("`ack` of `{}` names field `{}`, which the command does not have", c.name, ack.field),
            ));
        }
    }
}

pub fn crc(d: &Device, diags: &mut Diagnostics) {
    let Some(serial) = &d.serial else { return };
    if let Framing::StartLengthCrc { crc, .. } = &serial.framing {
        let got = crc.compute(b"123456789");
        if got != crc.check {
            diags.push(Diagnostic::error(
                "serial-crc",
                crc.check_span,
                format!("these CRC parameters give {got:#X} over \"123456789\", not the stated check value {:#X}", crc.check),
            ));
        }
        if !crc.covers_payload {
            diags.push(Diagnostic::error("serial-crc", serial.framing_span, "the CRC must cover the payload"));
        }
    }
}
