//! `node:` rules: the objects the node settings name are ones the node can read its setting from.
//!
//! The stack reads sub 0 of each named object at run time (boot-up, start-up, bus off, a PDO
//! mapping write) as an unsigned number of at most 4 bytes, in whichever mode the device runs.
//! The remapping switch's type has a rule of its own (`node_remapping`).

use super::hex4;
use crate::diag::{Diagnostic, Diagnostics};
use crate::model::{Device, Object};
use crate::types::DataType;

/// The object definitions one setting names: (spec key, index, every definition of the index).
fn named(d: &Device) -> impl Iterator<Item = (&'static str, u16, Vec<&Object>)> {
    d.node.objects().into_iter().filter_map(|(key, index)| {
        let index = index?;
        Some((key, index, d.objects.iter().filter(|o| o.index == index).collect()))
    })
}

/// ` (in mode `mixed`)` for a definition that exists in some modes only.
pub(super) fn in_modes(o: &Object) -> String {
    o.modes.as_ref().map_or(String::new(), |m| format!(" (in mode {})", m.iter().map(|m| format!("`{m}`")).collect::<Vec<_>>().join(", ")))
}

/// The data types a setting's object may have: the restart time is frenzel+berg's UNSIGNED16
/// in ms (2180h); a switch may be any unsigned integer the stack reads whole (at most 32 bits).
/// `None`: a rule of its own checks the type (`remapping_object`: `node-remapping-type`).
fn allowed_types(key: &str) -> Option<&'static [DataType]> {
    match key {
        "restart_time_object" => Some(&[DataType::Unsigned16]),
        "remapping_object" => None,
        _ => Some(&[DataType::Unsigned8, DataType::Unsigned16, DataType::Unsigned24, DataType::Unsigned32]),
    }
}

pub fn object(d: &Device, diags: &mut Diagnostics) {
    for (key, index, _) in named(d) {
        let missing: Vec<&str> = d.mode_names().into_iter().filter(|m| d.object(index, *m).is_none()).map(|m| m.unwrap_or("")).collect();
        if missing.is_empty() {
            continue;
        }
        let at = d.node_spans.of(key);
        let diag = if missing.len() == d.mode_names().len() {
            Diagnostic::error("node-object", at, format!("`node.{key}` names {}, which does not exist", hex4(index)))
        } else {
            let modes = missing.iter().map(|m| format!("`{m}`")).collect::<Vec<_>>().join(", ");
            Diagnostic::error("node-object", at, format!("`node.{key}` names {}, which does not exist in mode {modes}", hex4(index)))
                .note("the node reads this object in every mode")
        };
        diags.push(diag);
    }
}

pub fn object_type(d: &Device, diags: &mut Diagnostics) {
    for (key, index, objects) in named(d) {
        for o in objects {
            let at = d.node_spans.of(key);
            let Some(e) = o.entry(0).filter(|_| o.entries.len() == 1) else {
                diags.push(
                    Diagnostic::error(
                        "node-object-type",
                        at,
                        format!(
                            "`node.{key}` names {}{}, {} {} with sub-indices up to {}",
                            hex4(index),
                            in_modes(o),
                            if o.kind.name().starts_with('A') { "an" } else { "a" },
                            o.kind.name(),
                            o.highest_sub()
                        ),
                    )
                    .note("the node reads its setting from sub 0 of a VAR")
                    .note_at(o.span, "the object is defined here"),
                );
                continue;
            };
            let Some(allowed) = allowed_types(key) else { continue };
            if !allowed.contains(&e.data_type) {
                let rule = if key == "restart_time_object" {
                    "the bus-off restart time must be an UNSIGNED16 (ms)".to_string()
                } else {
                    let names: Vec<String> = allowed.iter().map(ToString::to_string).collect();
                    format!("the node reads it as an unsigned integer of at most 32 bits ({})", names.join(", "))
                };
                diags.push(
                    Diagnostic::error("node-object-type", at, format!("`node.{key}` names {}{} of type {}, but {rule}", hex4(index), in_modes(o), e.data_type))
                        .note_at(e.spans.data_type, "the object's type"),
                );
            }
        }
    }
}

pub fn object_access(d: &Device, diags: &mut Diagnostics) {
    for (key, index, objects) in named(d) {
        for o in objects {
            let Some(e) = o.entry(0).filter(|_| o.entries.len() == 1) else { continue };
            if !e.access.readable() {
                diags.push(
                    Diagnostic::error(
                        "node-object-access",
                        d.node_spans.of(key),
                        format!("`node.{key}` names {}{}, which cannot be read (access `{}`)", hex4(index), in_modes(o), e.access),
                    )
                    .note("a master must be able to read back the setting the node acts on")
                    .note_at(e.spans.access, "the object's access"),
                );
            }
        }
    }
}
