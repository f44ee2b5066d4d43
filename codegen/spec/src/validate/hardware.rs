//! Hardware tables and operating modes.

use super::hex4;
use crate::diag::{Diagnostic, Diagnostics};
use crate::model::{Device, Selector, SelectorSource};
use std::collections::BTreeMap;

fn check_selector(d: &Device, name: &str, s: &Selector, diags: &mut Diagnostics) {
    let width = match &s.source {
        SelectorSource::Pins { pins, .. } => Some(u32::try_from(pins.len()).unwrap_or(32)),
        SelectorSource::Object { index, sub } => {
            match d.objects.iter().find(|o| o.index == *index).and_then(|o| o.entry(*sub)) {
                None => diags.push(Diagnostic::error("hardware-codes", s.span, format!("`{name}` reads {}.{sub}, which does not exist", hex4(*index)))),
                Some(e) => return check_codes(name, s, e.data_type.bits(), diags),
            }
            None
        }
        SelectorSource::Configuration => None,
    };
    check_codes(name, s, width, diags);
}

fn check_codes(name: &str, s: &Selector, width: Option<u32>, diags: &mut Diagnostics) {
    let max = width.map(|w| (1_i64 << w.min(62)) - 1);
    let mut seen = BTreeMap::new();
    for row in &s.codes {
        if let Some(max) = max.filter(|&m| row.code < 0 || row.code > m) {
            diags.push(Diagnostic::error(
                "hardware-codes",
                row.span,
                format!("code {} of `{name}` does not fit its {} bits (0..={max})", row.code, width.unwrap_or(0)),
            ));
        }
        if let Some(first) = seen.insert(row.code, row.span) {
            diags.push(
                Diagnostic::error("hardware-codes", row.span, format!("code {} of `{name}` is listed twice", row.code)).note_at(first, "first listed here"),
            );
        }
        if let Some((lo, hi)) = s.range.filter(|(lo, hi)| (*lo..=*hi).contains(&row.code)) {
            diags.push(Diagnostic::error("hardware-codes", row.span, format!("code {} of `{name}` is already covered by its range {lo}..={hi}", row.code)));
        }
    }
    if let (Some((lo, hi)), Some(max)) = (s.range, max)
        && (lo < 0 || hi > max || lo > hi)
    {
        diags.push(Diagnostic::error("hardware-codes", s.span, format!("range {lo}..={hi} of `{name}` does not fit 0..={max}")));
    }
}

pub fn codes(d: &Device, diags: &mut Diagnostics) {
    let hw = &d.hardware;
    for (name, sel) in [("node_id", &hw.node_id), ("can_bitrate", &hw.can_bitrate), ("serial_bitrate", &hw.serial_bitrate)] {
        if let Some(s) = sel {
            check_selector(d, name, s, diags);
        }
    }
    if let Some(cfg) = &hw.config_pins {
        for s in &cfg.settings {
            if !cfg.pins.contains(&s.pin) {
                diags.push(Diagnostic::error("hardware-codes", s.span, format!("setting names pin `{}`, which is not in `config_pins.pins`", s.pin)));
            }
        }
    }
}

pub fn mode_select(d: &Device, diags: &mut Diagnostics) {
    let pins = d.hardware.config_pins.as_ref().map(|c| c.pins.clone()).unwrap_or_default();
    for m in &d.modes {
        for pin in m.pins.keys() {
            if !pins.contains(pin) {
                diags.push(Diagnostic::error("mode-select", m.span, format!("mode `{}` is selected by pin `{pin}`, which is not a configuration pin", m.name)));
            }
        }
        if let Some((index, sub, value)) = m.object {
            match d.objects.iter().find(|o| o.index == index).and_then(|o| o.entry(sub)) {
                None => diags.push(Diagnostic::error(
                    "mode-select",
                    m.span,
                    format!("mode `{}` is selected by {}.{sub}, which does not exist", m.name, hex4(index)),
                )),
                Some(e) if e.data_type.int_range().is_some_and(|(lo, hi)| !(lo..=hi).contains(&i128::from(value))) => {
                    diags.push(Diagnostic::error(
                        "mode-select",
                        m.span,
                        format!("mode `{}` needs {}.{sub} = {value}, which a {} cannot hold", m.name, hex4(index), e.data_type),
                    ));
                }
                Some(_) => {}
            }
        }
        if let Some(cmd) = &m.command
            && !d.serial.as_ref().is_some_and(|s| s.commands.iter().any(|c| &c.name == cmd))
        {
            diags.push(Diagnostic::error("mode-select", m.span, format!("mode `{}` is selected by command `{cmd}`, which is not a serial command", m.name)));
        }
    }
}
