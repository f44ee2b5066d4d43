//! Emergency rules.

use super::hex4;
use crate::diag::{Diagnostic, Diagnostics};
use crate::model::{Device, modes_overlap};

pub fn example(d: &Device, diags: &mut Diagnostics) {
    for e in &d.emergencies {
        let Some(ex) = &e.example else { continue };
        let frame = e.frame();
        let matches = ex.len() == 8 && frame.iter().zip(ex).all(|(want, got)| want.is_none_or(|w| w == *got));
        if !matches {
            let show = |b: &[Option<u8>]| b.iter().map(|x| x.map_or("xx".to_string(), |v| format!("{v:02X}"))).collect::<Vec<_>>().join(" ");
            let given: Vec<Option<u8>> = ex.iter().copied().map(Some).collect();
            diags.push(
                Diagnostic::error(
                    "emcy-example",
                    e.example_span,
                    format!("example {} of emergency `{}` does not match its fields, which give {}", show(&given), e.name, show(&frame)),
                )
                .note("bytes 0..1 are the code (little-endian), byte 2 the error register, bytes 3..7 `manufacturer`"),
            );
        }
    }
}

/// CiA 301 (1001h): the generic error bit is set whenever any other error bit is.
pub fn register(d: &Device, diags: &mut Diagnostics) {
    for e in &d.emergencies {
        if e.error_register != 0 && e.error_register & 0x01 == 0 {
            diags.push(
                Diagnostic::error(
                    "emcy-register",
                    e.span,
                    format!("emergency `{}` sends error register {:#04X} without the generic error bit 0", e.name, e.error_register),
                )
                .note("CiA 301 sets bit 0 of 1001h whenever any error is active"),
            );
        }
    }
}

pub fn duplicate(d: &Device, diags: &mut Diagnostics) {
    for (i, a) in d.emergencies.iter().enumerate() {
        if !a.name.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_') || a.name.is_empty() {
            diags.push(Diagnostic::error("emcy-duplicate", a.span, format!("emergency name `{}` must be snake_case (it becomes an identifier)", a.name)));
        }
        for b in &d.emergencies[i + 1..] {
            if !modes_overlap(&a.modes, &b.modes) {
                continue;
            }
            if a.event.is_some() && a.event == b.event {
                let event = a.event.map_or("", |e| e.name());
                diags.push(
                    Diagnostic::error("emcy-duplicate", b.span, format!("emergencies `{}` and `{}` are both sent for stack event `{event}`", a.name, b.name))
                        .note_at(a.span, "the other emergency"),
                );
            }
            if a.name == b.name {
                diags.push(
                    Diagnostic::error("emcy-duplicate", b.span, format!("emergency `{}` is defined twice", b.name)).note_at(a.span, "first defined here"),
                );
            } else if a.frame() == b.frame() {
                diags.push(
                    Diagnostic::error(
                        "emcy-duplicate",
                        b.span,
                        format!("emergencies `{}` and `{}` send the same frame; a master cannot tell them apart", a.name, b.name),
                    )
                    .note_at(a.span, "the other emergency"),
                );
            }
        }
    }
}

pub fn reference(d: &Device, diags: &mut Diagnostics) {
    for e in &d.emergencies {
        if let Some(index) = e.enabled_by
            && !d.objects.iter().any(|o| o.index == index)
        {
            diags.push(Diagnostic::error("emcy-reference", e.span, format!("emergency `{}` is enabled by {}, which does not exist", e.name, hex4(index))));
        }
    }
}
