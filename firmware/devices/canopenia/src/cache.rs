//! Remote reads answered from the manager's scan cache (5F01h.04 bit 4, "use scanned
//! entries", manual section 9.5): what a scan read of a node, by index and sub-index.

use coforge_stack::manager::scan::Scanned;

/// The cached value of `index`/`sub` in a node's scan, little-endian, and its length.
pub fn value<const PDOS: usize>(scan: &Scanned<PDOS>, index: u16, sub: u8) -> Option<([u8; 4], usize)> {
    let u32_of = |v: u32| Some((v.to_le_bytes(), 4));
    let u8_of = |v: u8| Some(([v, 0, 0, 0], 1));
    let pdo = |base: u16, pdos: &[_]| index.checked_sub(base).map(usize::from).and_then(|n| pdos.get(n).copied());
    match (index, sub) {
        (0x1000, 0) => u32_of(scan.device_type),
        (0x1018, 1..=4) => u32_of(*scan.identity.get(usize::from(sub) - 1)?),
        (0x1400..=0x15FF, _) | (0x1800..=0x19FF, _) => {
            let p = if index < 0x1800 { pdo(0x1400, &scan.rpdos)? } else { pdo(0x1800, &scan.tpdos)? };
            // A PDO the scan found not valid may not have been read at all: ask the node.
            match sub {
                1 if p.is_valid() => u32_of(p.cob_id),
                2 if p.is_valid() => u8_of(p.transmission),
                _ => None,
            }
        }
        (0x1600..=0x17FF, _) | (0x1A00..=0x1BFF, _) => {
            let p = if index < 0x1A00 { pdo(0x1600, &scan.rpdos)? } else { pdo(0x1A00, &scan.tpdos)? };
            if !p.is_valid() {
                return None;
            }
            match sub {
                0 => u8_of(p.mapping().len() as u8),
                n => u32_of(*p.mapping().get(usize::from(n) - 1)?),
            }
        }
        _ => None,
    }
}
