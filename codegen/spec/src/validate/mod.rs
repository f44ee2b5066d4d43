//! Validation passes. Each rule lives in its own module, has an id that appears in its
//! diagnostics, and has a fixture under `tests/fixtures/invalid/<id>*.yaml` that breaks it.

use crate::diag::Diagnostics;
use crate::model::Device;

mod emcy;
mod errata;
mod hardware;
mod node;
mod node_remapping;
mod od;
mod pdo;
mod serial;

/// One validation rule.
#[derive(Debug)]
pub struct Rule {
    pub id: &'static str,
    pub summary: &'static str,
    pub check: fn(&Device, &mut Diagnostics),
}

/// Every rule, in the order they run.
pub const RULES: &[Rule] = &[
    Rule { id: "od-duplicate", summary: "an index, or a sub-index within an object, is defined twice in one mode", check: od::duplicate },
    Rule {
        id: "od-ident-collision",
        summary: "two objects (or two subs of one object) get the same identifier after case conversion",
        check: od::ident_collision,
    },
    Rule { id: "od-index-range", summary: "an index lies outside the ranges CiA 301 allows for objects", check: od::index_range },
    Rule { id: "od-mandatory", summary: "a mandatory object (1000, 1001, 1018 with sub 1) is missing", check: od::mandatory },
    Rule { id: "od-sub0", summary: "ARRAY/RECORD sub 0 is not a read-only UNSIGNED8 equal to the highest sub-index", check: od::sub0 },
    Rule { id: "od-array-uniform", summary: "the sub-entries 1..n of an ARRAY do not share one data type", check: od::array_uniform },
    Rule { id: "od-default-range", summary: "a default does not fit its data type, its length or its limits", check: od::default_range },
    Rule { id: "od-limits", summary: "a low limit exceeds the high limit, or a limit does not fit the type", check: od::limits },
    Rule { id: "od-storage", summary: "persistent entries exist but the store/restore objects 1010/1011 do not", check: od::storage },
    Rule { id: "od-identity", summary: "1000/1018 defaults disagree with the device identity", check: od::identity },
    Rule { id: "node-object", summary: "a `node` setting names an object that is missing in some mode", check: node::object },
    Rule {
        id: "node-object-type",
        summary: "a `node` setting names an object that is not a VAR of an unsigned integer type (restart time: UNSIGNED16; remapping switch: `node-remapping-type`)",
        check: node::object_type,
    },
    Rule { id: "node-object-access", summary: "a `node` setting names an object that cannot be read (`wo` or `none`)", check: node::object_access },
    Rule { id: "node-remapping-type", summary: "`node.remapping_object` names an object that is not UNSIGNED8", check: node_remapping::remapping_type },
    Rule { id: "pdo-duplicate", summary: "a PDO number is defined twice in one mode", check: pdo::duplicate },
    Rule { id: "pdo-mapping-target", summary: "a default mapping points at a missing object or sub-index", check: pdo::mapping_target },
    Rule { id: "pdo-mapping-mappable", summary: "a default mapping maps an entry that is not PDO-mappable", check: pdo::mapping_mappable },
    Rule { id: "pdo-mapping-length", summary: "a mapping's bit length disagrees with the mapped entry's size", check: pdo::mapping_length },
    Rule { id: "pdo-mapping-access", summary: "an RPDO maps a non-writable entry, or a TPDO a non-readable one", check: pdo::mapping_access },
    Rule { id: "pdo-mapping-size", summary: "a mapping exceeds 64 bits or the number of mapping entries", check: pdo::mapping_size },
    Rule { id: "pdo-cob-id", summary: "default COB-IDs collide for some node ID, or are not valid 11-bit identifiers", check: pdo::cob_id },
    Rule { id: "pdo-transmission-type", summary: "a transmission type is reserved or invalid for the PDO's direction", check: pdo::transmission_type },
    Rule { id: "serial-code-collision", summary: "two commands of one direction share a code (and length code)", check: serial::code_collision },
    Rule { id: "serial-length", summary: "a declared length disagrees with the sum of the fields", check: serial::length },
    Rule { id: "serial-field-layout", summary: "fields overlap, run past the frame, or a tail is not last", check: serial::field_layout },
    Rule { id: "serial-example", summary: "an example vector does not decode by the spec's own rules", check: serial::example },
    Rule { id: "serial-reply", summary: "a reply or ack names a command or field that does not exist", check: serial::reply },
    Rule { id: "serial-crc", summary: "the CRC parameters do not produce the stated check value", check: serial::crc },
    Rule { id: "emcy-example", summary: "an emergency's example frame disagrees with its code, register and bytes", check: emcy::example },
    Rule { id: "emcy-register", summary: "an emergency sets error-register bits without the generic error bit 0", check: emcy::register },
    Rule { id: "emcy-duplicate", summary: "two emergencies share a name, a stack event or the same frame", check: emcy::duplicate },
    Rule { id: "emcy-reference", summary: "an emergency is enabled by an object that does not exist", check: emcy::reference },
    Rule { id: "redundant-pair", summary: "a redundant pair's objects are missing or differ in structure", check: od::redundant_pair },
    Rule { id: "hardware-codes", summary: "a selector code does not fit its pins, repeats, or reads a missing object", check: hardware::codes },
    Rule { id: "mode-select", summary: "a mode is selected by a pin or command that does not exist", check: hardware::mode_select },
    Rule { id: "errata-complete", summary: "an erratum has an empty field or a repeated id", check: errata::complete },
];

pub fn run_all(device: &Device, diags: &mut Diagnostics) {
    for rule in RULES {
        (rule.check)(device, diags);
    }
}

/// Hex for diagnostics: `0x1018`.
pub(crate) fn hex4(v: u16) -> String {
    format!("0x{v:04X}")
}
