//! Default PDO rules. Mappings are checked in every mode the PDO exists in.

use super::hex4;
use crate::diag::{Diagnostic, Diagnostics};
use crate::model::{Device, Entry, Mapping, Pdo, PdoDir, in_mode, modes_overlap};

/// Calls `f` for each mapping of each PDO, with the mapped entry as seen in each mode.
fn each_mapping(d: &Device, mut f: impl FnMut(&Pdo, &Mapping, Option<&Entry>, Option<&str>)) {
    for pdo in &d.pdo.pdos {
        for mode in d.mode_names().into_iter().filter(|m| in_mode(&pdo.modes, *m)) {
            for m in &pdo.map {
                let entry = d.object(m.index, mode).and_then(|o| o.entry(m.sub)).filter(|e| in_mode(&e.modes, mode));
                f(pdo, m, entry, mode);
            }
        }
    }
}

/// Dummy entries (CiA 301 data type indices 0x0002-0x0007) may be mapped to fill space.
fn is_dummy(m: &Mapping) -> bool {
    (0x0001..=0x0007).contains(&m.index) && m.sub == 0
}

/// "RPDO1 maps 0x6200.1": how every mapping diagnostic starts.
fn mapped(pdo: &Pdo, m: &Mapping) -> String {
    format!("{}{} maps {}.{}", pdo.dir.name(), pdo.number, hex4(m.index), m.sub)
}

fn in_mode_text(mode: Option<&str>) -> String {
    mode.map(|m| format!(" in mode `{m}`")).unwrap_or_default()
}

pub fn duplicate(d: &Device, diags: &mut Diagnostics) {
    for (i, a) in d.pdo.pdos.iter().enumerate() {
        for b in &d.pdo.pdos[i + 1..] {
            if a.dir == b.dir && a.number == b.number && modes_overlap(&a.modes, &b.modes) {
                diags.push(
                    Diagnostic::error("pdo-duplicate", b.span, format!("{}{} is defined twice", b.dir.name(), b.number)).note_at(a.span, "first defined here"),
                );
            }
        }
    }
}

pub fn mapping_target(d: &Device, diags: &mut Diagnostics) {
    each_mapping(d, |pdo, m, entry, mode| {
        if entry.is_none() && !is_dummy(m) {
            diags.push(Diagnostic::error("pdo-mapping-target", m.span, format!("{}, which does not exist{}", mapped(pdo, m), in_mode_text(mode))));
        }
    });
}

pub fn mapping_mappable(d: &Device, diags: &mut Diagnostics) {
    each_mapping(d, |pdo, m, entry, _| {
        if let Some(e) = entry.filter(|e| !e.pdo_mapping) {
            diags.push(
                Diagnostic::error("pdo-mapping-mappable", m.span, format!("{} ({}), which is not PDO-mappable", mapped(pdo, m), e.name))
                    .note_at(e.spans.at, "set `pdo_mapping: true` here if the datasheet allows it"),
            );
        }
    });
}

pub fn mapping_length(d: &Device, diags: &mut Diagnostics) {
    each_mapping(d, |pdo, m, entry, _| {
        let want = match entry {
            Some(e) => e.bits(),
            None if is_dummy(m) => crate::types::DataType::ALL.iter().find(|t| t.code() == m.index).and_then(|t| t.bits()),
            None => None,
        };
        // A string or domain maps any whole number of bytes up to its length (the stack's
        // `EntryInfo::takes_len`): CR3101's components take their configured type's size.
        let variable = entry.is_some_and(|e| e.data_type.bits().is_none());
        let fits = |bits: u32| if variable { m.bits % 8 == 0 && m.bits > 0 && u32::from(m.bits) <= bits } else { u32::from(m.bits) == bits };
        if let Some(bits) = want.filter(|&b| !fits(b)) {
            let is = if variable { "takes whole bytes up to" } else { "is" };
            diags.push(Diagnostic::error("pdo-mapping-length", m.span, format!("{} with {} bits, but the entry {is} {bits} bits", mapped(pdo, m), m.bits)));
        }
    });
}

pub fn mapping_access(d: &Device, diags: &mut Diagnostics) {
    each_mapping(d, |pdo, m, entry, _| {
        let Some(e) = entry else { return };
        let bad = match pdo.dir {
            PdoDir::Rx => (!e.access.writable()).then_some("an RPDO writes what it maps, but the entry is not writable"),
            PdoDir::Tx => (!e.access.readable()).then_some("a TPDO reads what it maps, but the entry is not readable"),
        };
        if let Some(why) = bad {
            diags.push(
                Diagnostic::error("pdo-mapping-access", m.span, format!("{} with access {}: {why}", mapped(pdo, m), e.access))
                    .note_at(e.spans.access, "access declared here"),
            );
        }
    });
}

pub fn mapping_size(d: &Device, diags: &mut Diagnostics) {
    for pdo in &d.pdo.pdos {
        let total: u32 = pdo.map.iter().map(|m| u32::from(m.bits)).sum();
        if total > 64 {
            diags.push(Diagnostic::error(
                "pdo-mapping-size",
                pdo.span,
                format!("{}{} maps {total} bits; a CAN frame carries at most 64", pdo.dir.name(), pdo.number),
            ));
        }
        let max = match pdo.dir {
            PdoDir::Rx => d.pdo.rpdo.as_ref(),
            PdoDir::Tx => d.pdo.tpdo.as_ref(),
        }
        .map_or(0, |s| s.max_mapped);
        if pdo.map.len() > usize::from(max) {
            diags.push(Diagnostic::error(
                "pdo-mapping-size",
                pdo.span,
                format!("{}{} maps {} entries but `max_mapped` is {max}", pdo.dir.name(), pdo.number, pdo.map.len()),
            ));
        }
    }
}

/// CiA 301 restricted CAN-IDs: NMT, SYNC/EMCY base, TIME, SDO, heartbeat and LSS ranges.
fn restricted(id: i64) -> bool {
    matches!(id, 0x000 | 0x001..=0x07F | 0x101..=0x180 | 0x581..=0x5FF | 0x601..=0x67F | 0x6E0..=0x6FF | 0x701..=0x77F | 0x780..=0x7FF)
}

pub fn cob_id(d: &Device, diags: &mut Diagnostics) {
    const INVALID: i64 = 1 << 31;
    const EXTENDED: i64 = 1 << 29;
    for pdo in &d.pdo.pdos {
        let v = pdo.cob_id.eval(&Default::default(), Some(1)).unwrap_or(0);
        if !(0..=0xFFFF_FFFF).contains(&v) {
            diags.push(Diagnostic::error("pdo-cob-id", pdo.cob_id_span, format!("COB-ID of {}{} does not fit UNSIGNED32", pdo.dir.name(), pdo.number)));
            continue;
        }
        for node in [1_i64, 127] {
            let id = pdo.cob_id.eval(&Default::default(), Some(node)).unwrap_or(0);
            let can_id = id & 0x1FFF_FFFF;
            if id & INVALID == 0 && id & EXTENDED == 0 && (can_id > 0x7FF || restricted(can_id)) {
                diags.push(Diagnostic::error(
                    "pdo-cob-id",
                    pdo.cob_id_span,
                    format!(
                        "{}{} uses CAN-ID {can_id:#05X} for node ID {node}, which is {}",
                        pdo.dir.name(),
                        pdo.number,
                        if can_id > 0x7FF { "not an 11-bit identifier" } else { "restricted by CiA 301" }
                    ),
                ));
                break;
            }
        }
    }
    // Two valid PDOs must never share a CAN-ID, for any node ID.
    for (i, a) in d.pdo.pdos.iter().enumerate() {
        for b in &d.pdo.pdos[i + 1..] {
            if !modes_overlap(&a.modes, &b.modes) {
                continue;
            }
            let clash = (1..=127_i64).find(|&n| {
                let (x, y) = (a.cob_id.eval(&Default::default(), Some(n)).unwrap_or(0), b.cob_id.eval(&Default::default(), Some(n)).unwrap_or(1));
                x & INVALID == 0 && y & INVALID == 0 && x & 0x3FFF_FFFF == y & 0x3FFF_FFFF
            });
            if let Some(n) = clash {
                diags.push(
                    Diagnostic::error(
                        "pdo-cob-id",
                        b.cob_id_span,
                        format!(
                            "{}{} and {}{} both use COB-ID {:#X} for node ID {n}",
                            a.dir.name(),
                            a.number,
                            b.dir.name(),
                            b.number,
                            b.cob_id.eval(&Default::default(), Some(n)).unwrap_or(0)
                        ),
                    )
                    .note_at(a.cob_id_span, "the other PDO"),
                );
            }
        }
    }
}

pub fn transmission_type(d: &Device, diags: &mut Diagnostics) {
    for pdo in &d.pdo.pdos {
        let t = pdo.transmission_type;
        let why = match (pdo.dir, t) {
            (_, 241..=251) => Some("241..251 are reserved"),
            (PdoDir::Rx, 252 | 253) => Some("252 and 253 (RTR-only) are only valid for TPDOs"),
            _ => None,
        };
        if let Some(why) = why {
            diags.push(Diagnostic::error(
                "pdo-transmission-type",
                pdo.transmission_type_span,
                format!("{}{} has transmission type {t}: {why}", pdo.dir.name(), pdo.number),
            ));
        }
    }
}
