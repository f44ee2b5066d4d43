//! `hardware:`: pin and object selectors with their code tables, and configuration pins.

use super::{Cx, span};
use crate::expr::Vars;
use crate::model::{CodeRow, ConfigPins, Hardware, Level, PinSetting, Selector, SelectorSource};
use crate::raw::{self, Num, S};

pub(super) fn level(cx: &mut Cx<'_>, s: &S<String>) -> Option<Level> {
    cx.keyword(
        s,
        "pin level",
        |l| match l {
            "high" => Some(Level::High),
            "low" => Some(Level::Low),
            "any" => Some(Level::Any),
            _ => None,
        },
        "high, low, any",
    )
}

pub(super) fn hardware(cx: &mut Cx<'_>, h: &raw::Hardware) -> Hardware {
    let mut sel = |s: &Option<S<raw::Selector>>| s.as_ref().and_then(|s| selector(cx, s));
    let node_id = sel(&h.node_id);
    let can_bitrate = sel(&h.can_bitrate);
    let serial_bitrate = sel(&h.serial_bitrate);
    let config_pins = h.config_pins.as_ref().map(|c| {
        let settings = c
            .value
            .settings
            .iter()
            .filter_map(|s| {
                Some(PinSetting { pin: s.value.pin.value.clone(), level: level(cx, &s.value.level)?, meaning: s.value.meaning.clone(), span: span(s) })
            })
            .collect();
        ConfigPins {
            pins: c.value.pins.iter().map(|p| p.value.clone()).collect(),
            inverted: c.value.inverted,
            settings,
            description: c.value.description.clone().unwrap_or_default(),
        }
    });
    Hardware { node_id, can_bitrate, serial_bitrate, config_pins }
}

fn selector(cx: &mut Cx<'_>, s: &S<raw::Selector>) -> Option<Selector> {
    let none = Vars::new();
    let v = &s.value;
    let source = match (&v.pins[..], &v.object) {
        ([], None) => SelectorSource::Configuration,
        (pins, None) => SelectorSource::Pins { pins: pins.iter().map(|p| p.value.clone()).collect(), inverted: v.inverted },
        ([], Some(o)) => {
            let index = cx.int_in(&o.value.index, &none, "index", 1, 0xFFFF)?;
            let sub = match &o.value.sub {
                Some(n) => cx.int_in(n, &none, "sub", 0, 254)?,
                None => 0,
            };
            SelectorSource::Object { index, sub }
        }
        _ => {
            cx.err("spec-structure", span(s), "a selector reads either `pins` or an `object`, not both");
            return None;
        }
    };
    let range = match &v.range {
        Some(r) => Some((cx.int(&r.value.0, &none, "range start")?, cx.int(&r.value.1, &none, "range end")?)),
        None => None,
    };
    let mut codes = Vec::new();
    for c in &v.codes {
        let row = &c.value;
        let opt = |cx: &mut Cx<'_>, n: &Option<Num>, what: &str| n.as_ref().and_then(|n| cx.int(n, &none, what));
        let value = opt(cx, &row.value, "value");
        if (row.reserved && value.is_some()) || (!row.reserved && value.is_none() && row.meaning.is_none()) {
            cx.err("spec-structure", span(c), "a code row has a `value`, or is `reserved: true`, or states its `meaning` (a special code such as LSS)");
            continue;
        }
        codes.push(CodeRow {
            code: cx.int(&row.code, &none, "code")?,
            value,
            exact: opt(cx, &row.exact, "exact"),
            reserved: row.reserved,
            meaning: row.meaning.clone().unwrap_or_default(),
            note: row.note.clone().unwrap_or_default(),
            span: span(c),
        });
    }
    Some(Selector {
        source,
        unit: v.unit.as_ref().map(|u| u.value.clone()),
        range,
        codes,
        description: v.description.clone().unwrap_or_default(),
        span: span(s),
    })
}
