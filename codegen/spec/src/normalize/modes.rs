//! `modes:`: operating modes and what selects each.

use super::hardware::level;
use super::{Cx, span};
use crate::expr::Vars;
use crate::model::Mode;
use crate::raw::{self, S};
use std::collections::BTreeMap;

pub(super) fn mode(cx: &mut Cx<'_>, m: &S<raw::Mode>) -> Mode {
    let v = &m.value;
    let mut pins = BTreeMap::new();
    let mut command = None;
    let mut object = None;
    if let Some(sel) = &v.select {
        for (pin, lvl) in &sel.value.pins {
            if let Some(l) = level(cx, lvl) {
                pins.insert(pin.clone(), l);
            }
        }
        command = sel.value.command.as_ref().map(|c| c.value.clone());
        if let Some(o) = &sel.value.object {
            let none = Vars::new();
            let index = cx.int_in(&o.value.index, &none, "index", 1, 0xFFFF);
            let sub = o.value.sub.as_ref().map_or(Some(0), |n| cx.int_in(n, &none, "sub", 0, 254));
            let value = cx.int(&o.value.value, &none, "value");
            if let (Some(index), Some(sub), Some(value)) = (index, sub, value) {
                object = Some((index, sub, value));
            }
        }
    }
    Mode { name: v.name.value.clone(), description: v.description.clone().unwrap_or_default(), pins, command, object, span: span(m) }
}
