//! Object dictionary rules.

use super::hex4;
use crate::diag::{Diagnostic, Diagnostics};
use crate::model::{Device, Object, Value, modes_overlap};
use crate::types::{Access, DataType, ObjectKind, Storage, Sub0};
use std::collections::BTreeMap;

pub fn duplicate(d: &Device, diags: &mut Diagnostics) {
    for (i, a) in d.objects.iter().enumerate() {
        for b in d.objects.iter().skip(i + 1).take_while(|b| b.index == a.index) {
            // Two generated objects collide only through a repeated PDO: `pdo-duplicate` says so.
            if modes_overlap(&a.modes, &b.modes) && !(a.generated && b.generated) {
                let what = if b.generated { " (generated from `pdo:`; do not list PDO parameter objects in `objects:`)" } else { "" };
                diags.push(
                    Diagnostic::error("od-duplicate", b.span, format!("object {} is defined twice{what}", hex4(a.index))).note_at(a.span, "first defined here"),
                );
            }
        }
        let mut seen: BTreeMap<u8, usize> = BTreeMap::new();
        for (k, e) in a.entries.iter().enumerate() {
            if let Some(&first) = seen.get(&e.sub) {
                let prev = &a.entries[first];
                if modes_overlap(&prev.modes, &e.modes) {
                    diags.push(
                        Diagnostic::error("od-duplicate", e.spans.at, format!("sub-index {} of object {} is defined twice", e.sub, hex4(a.index)))
                            .note_at(prev.spans.at, "first defined here"),
                    );
                }
            } else {
                seen.insert(e.sub, k);
            }
        }
    }
}

pub fn ident_collision(d: &Device, diags: &mut Diagnostics) {
    let mut by_ident: BTreeMap<&str, Vec<&Object>> = BTreeMap::new();
    for o in &d.objects {
        by_ident.entry(o.ident.as_str()).or_default().push(o);
    }
    for (ident, objs) in by_ident {
        for (i, b) in objs.iter().enumerate() {
            if let Some(a) = objs[..i].iter().find(|a| a.index != b.index && modes_overlap(&a.modes, &b.modes)) {
                diags.push(
                    Diagnostic::error(
                        "od-ident-collision",
                        b.span,
                        format!("objects {} and {} both become the identifier `{ident}`", hex4(a.index), hex4(b.index)),
                    )
                    .note_at(a.span, "the other object")
                    .note("give one of them an `ident:`"),
                );
            }
        }
    }
    for o in &d.objects {
        let mut seen: BTreeMap<&str, u8> = BTreeMap::new();
        for e in &o.entries {
            match seen.get(e.ident.as_str()) {
                Some(&sub) if sub != e.sub => diags.push(
                    Diagnostic::error(
                        "od-ident-collision",
                        e.spans.at,
                        format!("subs {sub} and {} of object {} both become the identifier `{}`", e.sub, hex4(o.index), e.ident),
                    )
                    .note("give one of them an `ident:`"),
                ),
                _ => {
                    seen.insert(e.ident.as_str(), e.sub);
                }
            }
        }
    }
}

/// CiA 301 table 43: which index ranges may hold objects.
fn index_area(index: u16) -> Option<&'static str> {
    match index {
        0x0001..=0x025F => Some("data types"),
        0x1000..=0x1FFF => Some("communication profile"),
        0x2000..=0x5FFF => Some("manufacturer-specific"),
        0x6000..=0x9FFF => Some("standardised device profile"),
        0xA000..=0xBFFF => Some("standardised interface profile"),
        _ => None,
    }
}

pub fn index_range(d: &Device, diags: &mut Diagnostics) {
    for o in &d.objects {
        if index_area(o.index).is_none() {
            diags.push(
                Diagnostic::error("od-index-range", o.span, format!("index {} is reserved by CiA 301", hex4(o.index)))
                    .note("objects live in 0x0001-0x025F, 0x1000-0x1FFF, 0x2000-0x5FFF, 0x6000-0x9FFF or 0xA000-0xBFFF"),
            );
        }
    }
}

pub fn mandatory(d: &Device, diags: &mut Diagnostics) {
    for mode in d.mode_names() {
        let suffix = mode.map(|m| format!(" in mode `{m}`")).unwrap_or_default();
        for (index, name) in [(0x1000, "device type"), (0x1001, "error register"), (0x1018, "identity object")] {
            if d.object(index, mode).is_none() {
                diags.push(Diagnostic::error("od-mandatory", d.identity.span, format!("mandatory object {} ({name}) is missing{suffix}", hex4(index))));
            }
        }
        if let Some(id) = d.object(0x1018, mode)
            && id.entry(1).is_none()
        {
            diags.push(Diagnostic::error("od-mandatory", id.span, format!("1018 must have sub-index 1 (vendor ID){suffix}")));
        }
    }
}

pub fn sub0(d: &Device, diags: &mut Diagnostics) {
    for o in d.objects.iter().filter(|o| o.kind.has_subs()) {
        let Some(e) = o.entry(0) else {
            diags.push(Diagnostic::error("od-sub0", o.span, format!("{} {} has no sub-index 0", o.kind.name(), hex4(o.index))));
            continue;
        };
        if e.data_type != DataType::Unsigned8 {
            diags.push(Diagnostic::error("od-sub0", e.spans.data_type, format!("sub 0 of {} must be UNSIGNED8, not {}", hex4(o.index), e.data_type)));
        }
        let highest = i64::from(o.highest_sub());
        let value = e.default.as_ref().and_then(|v| v.int_for(1));
        match o.sub0 {
            Sub0::Highest => {
                if !matches!(e.access, Access::Ro | Access::Const) {
                    diags.push(
                        Diagnostic::error("od-sub0", e.spans.access, format!("sub 0 of {} must be read-only, not {}", hex4(o.index), e.access))
                            .note("if sub 0 counts valid entries (like 1003), set `sub0: count` on the object"),
                    );
                }
                if value != Some(highest) {
                    let found = value.map_or("no default".to_string(), |v| format!("{v}"));
                    diags.push(Diagnostic::error(
                        "od-sub0",
                        e.spans.default,
                        format!("sub 0 of {} must be {highest} (the highest sub-index), found {found}", hex4(o.index)),
                    ));
                }
            }
            Sub0::Count => {
                if value.is_some_and(|v| v > highest) {
                    diags.push(Diagnostic::error(
                        "od-sub0",
                        e.spans.default,
                        format!("sub 0 of {} counts entries but exceeds the highest sub-index {highest}", hex4(o.index)),
                    ));
                }
            }
        }
    }
}

pub fn array_uniform(d: &Device, diags: &mut Diagnostics) {
    for o in d.objects.iter().filter(|o| o.kind == ObjectKind::Array) {
        let mut subs = o.entries.iter().filter(|e| e.sub != 0);
        let Some(first) = subs.next() else { continue };
        for e in subs.filter(|e| e.data_type != first.data_type) {
            diags.push(
                Diagnostic::error(
                    "od-array-uniform",
                    e.spans.data_type,
                    format!("ARRAY {} mixes {} (sub {}) and {} (sub {})", hex4(o.index), first.data_type, first.sub, e.data_type, e.sub),
                )
                .note("all elements of an ARRAY share one type; use `kind: record` for mixed types"),
            );
        }
    }
}

/// The integer range an entry's values must lie in: type range narrowed by its limits.
fn int_bounds(e: &crate::model::Entry) -> Option<(i128, i128)> {
    let (lo, hi) = e.data_type.int_range()?;
    let lim = |v: &Option<Value>| v.as_ref().and_then(|v| v.int_for(1)).map(i128::from);
    Some((lim(&e.low).unwrap_or(lo).max(lo), lim(&e.high).unwrap_or(hi).min(hi)))
}

pub fn default_range(d: &Device, diags: &mut Diagnostics) {
    for o in &d.objects {
        for e in &o.entries {
            if let (Some(values), Some((lo, hi))) = (&e.values, e.data_type.int_range()) {
                if let Some(v) = values.iter().find(|v| !(lo..=hi).contains(&i128::from(**v))) {
                    diags.push(Diagnostic::error(
                        "od-default-range",
                        e.spans.values,
                        format!("allowed value {v:#X} of {}.{} does not fit {}", hex4(o.index), e.sub, e.data_type),
                    ));
                }
                if let Some(v) = e.default.as_ref().and_then(|v| v.int_for(1)).filter(|v| !values.contains(v)) {
                    diags.push(
                        Diagnostic::error(
                            "od-default-range",
                            e.spans.default,
                            format!("default {v:#X} of {}.{} is not one of its allowed `values`", hex4(o.index), e.sub),
                        )
                        .note_at(e.spans.values, "allowed values"),
                    );
                }
            }
            let Some(default) = &e.default else { continue };
            match default {
                Value::Int(expr) => {
                    let Some((lo, hi)) = int_bounds(e) else { continue };
                    // A `$NODEID` default must fit for every node ID 1..127.
                    let nodes: Vec<u8> = if expr.uses_node_id() { vec![1, 127] } else { vec![1] };
                    for n in nodes {
                        let Some(v) = default.int_for(n).map(i128::from) else { continue };
                        if !(lo..=hi).contains(&v) {
                            let at = if expr.uses_node_id() { format!(" for node ID {n}") } else { String::new() };
                            diags.push(Diagnostic::error(
                                "od-default-range",
                                e.spans.default,
                                format!(
                                    "default {v:#X}{at} of {}.{} lies outside {lo:#X}..={hi:#X} ({}{})",
                                    hex4(o.index),
                                    e.sub,
                                    e.data_type,
                                    if e.low.is_some() || e.high.is_some() { " within its limits" } else { "" }
                                ),
                            ));
                            break;
                        }
                    }
                }
                Value::Str(s) => {
                    if let Some(max) = e.length {
                        let len = u32::try_from(s.len()).unwrap_or(u32::MAX);
                        if len > max {
                            diags.push(Diagnostic::error(
                                "od-default-range",
                                e.spans.default,
                                format!("default of {}.{} is {len} bytes long; its `length` is {max}", hex4(o.index), e.sub),
                            ));
                        }
                    }
                    if e.data_type == DataType::VisibleString && !s.bytes().all(|b| (0x20..=0x7E).contains(&b)) {
                        diags.push(Diagnostic::error(
                            "od-default-range",
                            e.spans.default,
                            format!("default of {}.{} has characters outside VISIBLE_STRING (0x20..0x7E)", hex4(o.index), e.sub),
                        ));
                    }
                }
                Value::Real(x) => {
                    if e.data_type == DataType::Real32 && x.is_finite() && x.abs() > f64::from(f32::MAX) {
                        diags.push(Diagnostic::error(
                            "od-default-range",
                            e.spans.default,
                            format!("default {x} of {}.{} does not fit REAL32", hex4(o.index), e.sub),
                        ));
                    }
                }
            }
        }
    }
}

pub fn limits(d: &Device, diags: &mut Diagnostics) {
    for o in &d.objects {
        for e in &o.entries {
            let Some((tlo, thi)) = e.data_type.int_range() else { continue };
            let lim = |v: &Option<Value>| v.as_ref().and_then(|v| v.int_for(1)).map(i128::from);
            let (lo, hi) = (lim(&e.low), lim(&e.high));
            for (v, span, what) in [(lo, e.spans.low, "low"), (hi, e.spans.high, "high")] {
                if let Some(v) = v.filter(|v| !(tlo..=thi).contains(v)) {
                    diags.push(Diagnostic::error(
                        "od-limits",
                        span,
                        format!("{what} limit {v:#X} of {}.{} does not fit {}", hex4(o.index), e.sub, e.data_type),
                    ));
                }
            }
            if let (Some(lo), Some(hi)) = (lo, hi)
                && lo > hi
            {
                diags.push(
                    Diagnostic::error("od-limits", e.spans.low, format!("low limit {lo:#X} of {}.{} exceeds its high limit {hi:#X}", hex4(o.index), e.sub))
                        .note_at(e.spans.high, "high limit"),
                );
            }
        }
    }
}

pub fn storage(d: &Device, diags: &mut Diagnostics) {
    for mode in d.mode_names() {
        let persistent = d
            .objects
            .iter()
            .filter(|o| !o.generated && crate::model::in_mode(&o.modes, mode))
            .find_map(|o| o.entries.iter().find(|e| e.storage == Storage::Persistent).map(|e| (o, e)));
        let Some((o, e)) = persistent else { continue };
        for (index, what) in [(0x1010, "store parameters"), (0x1011, "restore default parameters")] {
            if d.object(index, mode).is_none() {
                diags.push(
                    Diagnostic::error(
                        "od-storage",
                        e.spans.at,
                        format!("{}.{} is `persistent`, but {} ({what}) does not exist", hex4(o.index), e.sub, hex4(index)),
                    )
                    .note("persistent entries are saved by 1010 and restored by 1011; add them or use `storage: ram`"),
                );
            }
        }
    }
}

pub fn identity(d: &Device, diags: &mut Diagnostics) {
    let id = &d.identity;
    for o in d.objects.iter().filter(|o| o.index == 0x1018) {
        for (sub, want, what) in [(1, id.vendor_id, "vendor_id"), (2, id.product_code, "product_code"), (3, id.revision, "revision")] {
            let Some(e) = o.entry(sub) else { continue };
            if let Some(v) = e.default.as_ref().and_then(|v| v.int_for(1))
                && v != i64::from(want)
            {
                diags.push(
                    Diagnostic::error("od-identity", e.spans.default, format!("1018.{sub} defaults to {v:#010X} but `device.{what}` is {want:#010X}"))
                        .note_at(id.span, "device identity"),
                );
            }
        }
    }
    for o in d.objects.iter().filter(|o| o.index == 0x1000) {
        let Some(e) = o.entry(0) else { continue };
        if let Some(v) = e.default.as_ref().and_then(|v| v.int_for(1))
            && v & 0xFFFF != i64::from(id.profile)
        {
            diags.push(
                Diagnostic::error(
                    "od-identity",
                    e.spans.default,
                    format!("1000 defaults to {v:#010X}, whose low 16 bits should be the profile {}", id.profile),
                )
                .note_at(id.span, "device identity"),
            );
        }
    }
}

pub fn redundant_pair(d: &Device, diags: &mut Diagnostics) {
    for pair in &d.redundant_pairs {
        let (Some(a), Some(b)) = (d.objects.iter().find(|o| o.index == pair.primary), d.objects.iter().find(|o| o.index == pair.shadow)) else {
            let missing = if d.objects.iter().any(|o| o.index == pair.primary) { pair.shadow } else { pair.primary };
            diags.push(Diagnostic::error("redundant-pair", pair.span, format!("redundant pair names {}, which does not exist", hex4(missing))));
            continue;
        };
        let shape = |o: &Object| o.entries.iter().map(|e| (e.sub, e.data_type, e.access, e.default.clone())).collect::<Vec<_>>();
        if a.kind != b.kind || shape(a) != shape(b) {
            diags.push(
                Diagnostic::error(
                    "redundant-pair",
                    pair.span,
                    format!("{} and {} must have the same subs, types, access and defaults to be compared", hex4(a.index), hex4(b.index)),
                )
                .note_at(a.span, "primary")
                .note_at(b.span, "shadow"),
            );
        }
    }
}
