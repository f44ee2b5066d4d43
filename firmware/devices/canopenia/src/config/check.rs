//! Whether a binary EDS fits this firmware's dictionary: every entry it configures exists here
//! with the size the file gives it, every PDO it configures exists here, and each PDO's entries
//! can be mapped in its direction and fit 8 bytes. One rule per refusal, each with one abort
//! code (erratum COIA-50):
//!
//! | refusal | abort |
//! |---|---|
//! | the file breaks the format (size, CRC, tables, image bounds) | 0800 0023h no dictionary (file error) |
//! | an entry or a PDO the dictionary lacks | 0602 0000h object / 0609 0011h sub-index does not exist |
//! | an entry whose size differs (longer than a string or domain holds) | 0607 0010h length mismatch |
//! | a PDO entry not mappable in its direction | 0604 0041h cannot be mapped |
//! | a PDO longer than 8 bytes, or a record whose length is not its entries' | 0604 0042h PDO length exceeded |
//! | node-ID 0 without FUNC bit 5, LSS (not in this firmware), a bit rate CiA 301 lacks | 0604 0047h internal incompatibility |

use coforge_beds::layout::func;
use coforge_beds::{BinaryEds, OdEntry, PdoRecord, Table};
use coforge_stack::od::{SdoAbort, Table as Entries, find};
use coforge_stack::pdo::Dir;

/// The bit rates of CiA 301's bit timing table, in kbit/s.
const BIT_RATES: [u16; 9] = [10, 20, 50, 100, 125, 250, 500, 800, 1000];

/// Checks `file` against the dictionary `entries`.
pub fn check(file: &BinaryEds<'_>, entries: Entries<'_>) -> Result<(), SdoAbort> {
    check_settings(file)?;
    for r in file.sdo_replies() {
        check_entry(entries, r.index, r.sub, u16::from(r.size().unwrap_or(4)))?;
    }
    for e in file.od_entries() {
        check_entry(entries, e.index, e.sub, e.size())?;
    }
    for e in file.generic_entries() {
        check_entry(entries, e.index, e.sub, e.size)?;
    }
    for (table, dir) in PDO_TABLES {
        for pdo in file.pdos(table) {
            check_pdo(file, entries, &pdo, dir)?;
        }
    }
    Ok(())
}

fn check_settings(file: &BinaryEds<'_>) -> Result<(), SdoAbort> {
    let h = file.header();
    let from_hardware = h.func & func::SETTINGS_FROM_HARDWARE != 0;
    let node_ok = from_hardware || (1..=127).contains(&h.node_id);
    let rate_ok = from_hardware || BIT_RATES.contains(&h.bitrate_kbit);
    if !node_ok || !rate_ok || h.func & func::LSS != 0 {
        return Err(SdoAbort::IncompatibleInternal);
    }
    Ok(())
}

/// Sub-index 0 of an array or record tells its highest sub-index: the dictionary's structure
/// decides it, so a file may list fewer sub-entries, not more.
fn check_entry(entries: Entries<'_>, index: u16, sub: u8, size: u16) -> Result<(), SdoAbort> {
    let info = find(entries, index, sub)?;
    if info.takes_len(usize::from(size)) { Ok(()) } else { Err(SdoAbort::LengthMismatch) }
}

/// The dictionary must have the PDO's parameters, and its entries must be mappable.
fn check_pdo(file: &BinaryEds<'_>, entries: Entries<'_>, pdo: &PdoRecord, dir: Dir) -> Result<(), SdoAbort> {
    let comm = pdo.number.checked_sub(1).map(|n| dir.comm_base() + u16::from(n)).ok_or(SdoAbort::NoObject)?;
    find(entries, comm, 1)?;
    find(entries, Dir::mapping_of(comm), 0)?;
    let mut bytes = 0_u16;
    for e in mapped(file, pdo) {
        let info = find(entries, e.index, e.sub)?;
        if !info.pdo_mappable() {
            return Err(SdoAbort::NotMappable);
        }
        bytes += e.size();
    }
    if bytes > 8 || bytes != u16::from(pdo.length) {
        return Err(SdoAbort::PdoTooLong);
    }
    Ok(())
}

/// A file's PDO tables and the direction of each.
pub const PDO_TABLES: [(Table, Dir); 2] = [(Table::Rpdos, Dir::Rx), (Table::Tpdos, Dir::Tx)];

/// Entries the vendor's tool lists at process-image offset 0 with no room of their own: the
/// firmware serves them, the file holds no value for them (erratum COIA-39).
pub const SERVED_BY_FIRMWARE: u16 = 0x5FF5;

/// The entries a PDO record maps: the process-image entries that lie inside its bytes, in
/// the order of their offsets (the format has no mapping table; the DSAT's PDO bits are not
/// what decides, coforge's exporter leaves them to the mapping). At most 8: a PDO has 8
/// bytes.
pub fn mapped(file: &BinaryEds<'_>, pdo: &PdoRecord) -> impl Iterator<Item = OdEntry> {
    let start = pdo.offset;
    let end = start.saturating_add(u32::from(pdo.length));
    let mut inside: heapless::Vec<OdEntry, 8> =
        file.od_entries().filter(|e| e.size() > 0 && e.index != SERVED_BY_FIRMWARE && (start..end).contains(&u32::from(e.offset))).take(8).collect();
    inside.sort_unstable_by_key(|e| e.offset);
    inside.into_iter()
}
