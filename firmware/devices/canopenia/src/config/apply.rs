//! A checked binary EDS as writes into the dictionary: the values of its entries, then its
//! PDO configuration, for the entries of one reset area. Not configuration, and not written:
//! sub-index 0 of arrays and records, the loading interface, what the chip owns or the
//! firmware serves, and the command entries the device acts on (5F01h.1, 5F01h.0A, 5F0Ah.1).
//! The device writes them with its own rights after every initialisation, before what 1010h
//! saved is loaded over them.

use super::check::{PDO_TABLES, SERVED_BY_FIRMWARE, mapped};
use coforge_beds::{BinaryEds, PdoRecord, Table};
use coforge_stack::od::{Area, Table as Entries, find};
use coforge_stack::pdo::{COB_INVALID, Dir};

/// Entries a file lists that are not configuration: what the firmware serves itself
/// (erratum COIA-39), and the loading interface 1F50h/1F51h (a key and a stop command written
/// as "defaults" would send the device back into bootloader mode).
const NOT_CONFIGURATION: [u16; 3] = [SERVED_BY_FIRMWARE, 0x1F50, 0x1F51];
/// Entries that belong to the chip, not to a configuration: its serial number (1018h.4, the
/// activation key) and its chip ID (5F00h.5).
const CHIP_OWN: [(u16, u8); 2] = [(0x1018, 4), (0x5F00, 5)];

/// Writes each entry's value (`write` says whether the dictionary took it).
pub type Write<'w> = dyn FnMut(u16, u8, &[u8]) -> bool + 'w;

/// Calls `write` with every value of `file` for the entries of `area`, in an order the
/// dictionary's PDO rules accept; the number of values the dictionary refused.
///
/// The format stores 0 in the process image where a default depends on the node-ID or is
/// absent (erratum COIA-39): a zero the dictionary refuses is that, not a refused value.
pub fn apply(file: &BinaryEds<'_>, entries: Entries<'_>, area: Area, node_id: u8, write: &mut Write<'_>) -> u32 {
    let mut refused = 0;
    let mut value = |index: u16, sub: u8, data: &[u8]| {
        if !write(index, sub, data) && data.iter().any(|&b| b != 0) {
            refused += 1;
        }
    };
    // PDO parameters are written in the PDO step, in the order CiA 301 accepts (and the
    // file's image holds node-relative COB-IDs as 0: the PDO records have them absolute).
    let wanted = |index: u16, sub: u8| {
        area.contains(index)
            && Dir::of_index(index).is_none()
            && !NOT_CONFIGURATION.contains(&index)
            && !CHIP_OWN.contains(&(index, sub))
            && !crate::objects::is_command_entry(index, sub)
            && !is_structure(entries, index, sub)
    };
    for r in file.sdo_replies().filter(|r| wanted(r.index, r.sub)) {
        value(r.index, r.sub, r.value());
    }
    for e in file.od_entries().filter(|e| wanted(e.index, e.sub)) {
        value(e.index, e.sub, file.image_value(Table::Defaults, e.offset, e.size()));
    }
    for e in file.generic_entries().filter(|e| wanted(e.index, e.sub)) {
        value(e.index, e.sub, file.image_value(Table::Defaults, e.offset, e.size));
    }
    if area.contains(Dir::Rx.comm_base()) {
        let mut counted = |index: u16, sub: u8, data: &[u8]| {
            if !write(index, sub, data) {
                refused += 1;
            }
        };
        for (table, dir) in PDO_TABLES {
            pdos(file, entries, table, dir, node_id, &mut counted);
        }
    }
    refused
}

/// Sub-index 0 of an array or record: the dictionary's structure, not a value to take.
fn is_structure(entries: Entries<'_>, index: u16, sub: u8) -> bool {
    sub == 0 && find(entries, index, 1).is_ok()
}

/// The file's PDOs of one direction; the dictionary's PDOs the file does not configure are
/// made invalid.
fn pdos(file: &BinaryEds<'_>, entries: Entries<'_>, table: Table, dir: Dir, node_id: u8, write: &mut dyn FnMut(u16, u8, &[u8])) {
    let base = dir.comm_base();
    let mut configured = 0_u64;
    for pdo in file.pdos(table) {
        let Some(n) = pdo.number.checked_sub(1) else { continue };
        configured |= 1_u64.checked_shl(u32::from(n)).unwrap_or(0);
        pdo_writes(file, &pdo, base + u16::from(n), dir, write);
    }
    for n in 0..64_u16 {
        let comm = base + n;
        if find(entries, comm, 1).is_err() {
            break;
        }
        if configured & (1 << n) == 0 {
            write(comm, 1, &default_cob(dir, n, node_id).to_le_bytes());
        }
    }
}

/// The COB-ID a PDO the file leaves out gets: CiA 301's default identifier, marked invalid.
fn default_cob(dir: Dir, n: u16, node_id: u8) -> u32 {
    let function = if dir == Dir::Rx { 0x200 } else { 0x180 };
    COB_INVALID | (function + 0x100 * u32::from(n % 4) + u32::from(node_id))
}

/// One PDO: invalid while it is remapped (CiA 301's order), then its parameters.
fn pdo_writes(file: &BinaryEds<'_>, pdo: &PdoRecord, comm: u16, dir: Dir, write: &mut dyn FnMut(u16, u8, &[u8])) {
    let map = Dir::mapping_of(comm);
    write(comm, 1, &(pdo.cob_id | COB_INVALID).to_le_bytes());
    write(map, 0, &[0]);
    let mut count = 0_u8;
    for e in mapped(file, pdo) {
        count += 1;
        let entry = (u32::from(e.index) << 16) | (u32::from(e.sub) << 8) | (u32::from(e.size()) * 8);
        write(map, count, &entry.to_le_bytes());
    }
    write(map, 0, &[count]);
    write(comm, 2, &[pdo.transmission_type]);
    if dir == Dir::Tx {
        // The file holds the inhibit time in ms, 1800h.3 counts 100 us (erratum COIA-38).
        write(comm, 3, &pdo.inhibit_time.saturating_mul(10).to_le_bytes());
        write(comm, 5, &pdo.event_time.to_le_bytes());
    }
    write(comm, 1, &pdo.cob_id.to_le_bytes());
}
