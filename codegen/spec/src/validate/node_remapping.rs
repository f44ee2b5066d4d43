//! `node-remapping-type`: the object `node.remapping_object` names is an UNSIGNED8, the type of
//! the switch it transcribes (CO401GW1 2102h "Remapping Enabled Info": 0 = remapping disabled,
//! 1..255 = enabled).
//!
//! That the object exists in every mode, is a VAR and can be read is what every object setting
//! must meet (`node-object`, `node-object-type`, `node-object-access`); this rule only narrows
//! the type, and leaves an object of the wrong shape to `node-object-type`.

use super::hex4;
use super::node::in_modes;
use crate::diag::{Diagnostic, Diagnostics};
use crate::model::Device;
use crate::types::DataType;

pub fn remapping_type(d: &Device, diags: &mut Diagnostics) {
    let Some(index) = d.node.remapping_object else { return };
    for o in d.objects.iter().filter(|o| o.index == index) {
        let Some(e) = o.entry(0).filter(|_| o.entries.len() == 1) else { continue };
        if e.data_type != DataType::Unsigned8 {
            diags.push(
                Diagnostic::error(
                    "node-remapping-type",
                    d.node_spans.remapping_object,
                    format!(
                        "`node.remapping_object` names {}{} of type {}, but the remapping switch must be an UNSIGNED8",
                        hex4(index),
                        in_modes(o),
                        e.data_type
                    ),
                )
                .note("0 disables PDO remapping, 1..255 enables it")
                .note_at(e.spans.data_type, "the object's type"),
            );
        }
    }
}
