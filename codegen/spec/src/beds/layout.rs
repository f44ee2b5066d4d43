//! Lowers a [`Dictionary`] into the tables of a binary EDS, by the rules the CANopenIA
//! vendor's tool follows (derived from its files in `tests/vendor-data/canopenia/`, which
//! this reproduces byte for byte):
//!
//! - **SDO replies:** every `const` entry of up to 4 bytes and every entry of the PDO parameter objects
//!   1400h..1BFFh (communication and mapping), in index order, the value resolved for the
//!   node-ID. The dummy data types 0001h..0007h (`[DummyUsage]`) come first, as constants.
//! - **Process image:** every other entry (a longer constant, such as a device name, read-only),
//!   and the PDO communication entries again (they are writable at run time). Entries mapped by the default PDOs come first, in mapping order
//!   (RPDO mappings 1600h.., then TPDO mappings 1A00h..), each PDO's data contiguous, and the
//!   TPDO block and the rest each starting at a multiple of 4; an entry mapped by several PDOs keeps its first
//!   place and is listed again. Then the rest in index order, packed without alignment.
//!   Entries of up to 4 bytes go to the OD entry table, longer ones to the generic table.
//! - **DSAT:** readable unless `wo`; writable for `rw`/`wo`/`rwr`/`rww`; the TPDO bit for
//!   `rwr`, the RPDO bit for `rww` (the vendor's tool sets them from the access type alone, so a
//!   `ro` input mapped into a TPDO has neither).
//! - **Image blocks:** each entry's default, high and low limit at its offset (zeros where
//!   the EDS has none); a value relative to the node-ID is stored as 0 there (the SDO reply
//!   carries the resolved one).
//! - **PDO records:** one per communication object present, numbered from its index (1400h
//!   is 1): transmission type (sub 2), COB-ID (sub 1, resolved), length (the sum of the
//!   default mapping), the image offset of the first mapped entry, and for a TPDO the event
//!   timer (sub 5, ms) and the inhibit time (sub 3, converted from 100 us to ms).

use super::dictionary::{Dictionary, Item, fixed_size};
use crate::eds::ExportError;
use crate::types::Access;
use coforge_beds::{Dsat, GenericEntry, OdEntry, PdoRecord, SdoReply};
use std::collections::BTreeMap;

/// What the vendor's tool knows that its EDS files do not say. Empty for a coforge spec.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Conventions {
    /// Objects listed in the OD entry table at offset 0 with no process-image space (the
    /// firmware serves them itself): CANopenIA's 5FF5h.
    pub served_by_firmware: Vec<u16>,
    /// Sizes of entries whose EDS gives none: CANopenIA's chip ID 5F00h.05 (a DOMAIN) is the
    /// 12-byte unique ID of its microcontroller.
    pub sizes: Vec<((u16, u8), usize)>,
}

impl Conventions {
    /// CANopenIA's, as its vendor's tool applies them (`coforge beds --vendor-conventions`).
    pub fn canopenia() -> Self {
        Conventions { served_by_firmware: vec![0x5FF5], sizes: vec![((0x5F00, 5), 12)] }
    }
}

/// The tables, before they are written out.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Tables {
    pub replies: Vec<SdoReply>,
    pub od: Vec<OdEntry>,
    pub generic: Vec<GenericEntry>,
    pub defaults: Vec<u8>,
    pub maximums: Vec<u8>,
    pub minimums: Vec<u8>,
    pub rpdos: Vec<PdoRecord>,
    pub tpdos: Vec<PdoRecord>,
}

fn is_pdo_parameter(index: u16) -> bool {
    (0x1400..=0x1BFF).contains(&index)
}

/// The dummy data-type entries 0001h..0007h: constant, whatever a spec declares.
fn is_data_type(index: u16) -> bool {
    index <= 0x0007
}

/// A constant the SDO reply table can hold (longer ones live in the image, read-only).
fn is_short_constant(item: &Item) -> bool {
    item.access == Access::Const && (1..=4).contains(&item.size)
}

/// An entry answered from the SDO reply table.
fn is_reply(item: &Item) -> bool {
    is_short_constant(item) || is_pdo_parameter(item.index) || is_data_type(item.index)
}

/// An entry with a place in the process image.
fn is_imaged(item: &Item) -> bool {
    !is_short_constant(item) && !is_data_type(item.index)
}

fn dsat_flags(access: Access) -> u8 {
    let mut flags = 0;
    if access.readable() {
        flags |= Dsat::READ;
    }
    if access.writable() {
        flags |= Dsat::WRITE;
    }
    match access {
        Access::Rwr => flags | Dsat::TPDO,
        Access::Rww => flags | Dsat::RPDO,
        _ => flags,
    }
}

/// One default PDO mapping: the mapping object's index and its (index, sub, bits) entries.
type PdoMap = (u16, Vec<(u16, u8, u8)>);

fn mappings(dict: &Dictionary, base: u16) -> Vec<PdoMap> {
    let objects: Vec<u16> = dict.items.iter().filter(|i| i.sub == 0 && (base..base + 0x200).contains(&i.index)).map(|i| i.index).collect();
    objects
        .into_iter()
        .map(|index| {
            let count = dict.default_u64(index, 0).unwrap_or(0).min(64) as u8;
            let entries = (1..=count).filter_map(|sub| dict.default_u64(index, sub)).map(|v| ((v >> 16) as u16, (v >> 8) as u8, v as u8)).collect();
            (index, entries)
        })
        .collect()
}

fn u16_of(dict: &Dictionary, index: u16, sub: u8) -> u16 {
    dict.default_u64(index, sub).unwrap_or(0) as u16
}

/// An entry's default in the image block: 0 where it depends on the node-ID.
fn default_in_image(item: &Item) -> Option<&Vec<u8>> {
    if item.node_relative { None } else { item.default.as_ref() }
}

/// A value padded or cut to `size` bytes.
fn sized(value: Option<&Vec<u8>>, size: usize) -> Vec<u8> {
    let mut bytes = value.cloned().unwrap_or_default();
    bytes.resize(size, 0);
    bytes
}

struct Image<'a> {
    conventions: &'a Conventions,
    /// Placed entries: (index, sub) -> (offset, size).
    placed: BTreeMap<(u16, u8), (usize, usize)>,
    end: usize,
    tables: Tables,
}

impl Image<'_> {
    fn size_of(&self, item: &Item) -> usize {
        self.conventions.sizes.iter().find(|(k, _)| *k == (item.index, item.sub)).map_or(item.size, |(_, s)| *s)
    }

    /// Gives `item` its place (once) and lists it in its table.
    fn place(&mut self, item: &Item) -> Result<usize, ExportError> {
        self.place_sized(item, self.size_of(item))
    }

    /// Gives `item` its place (once) at `size` bytes and lists it in its table.
    fn place_sized(&mut self, item: &Item, size: usize) -> Result<usize, ExportError> {
        let at = match self.placed.get(&(item.index, item.sub)) {
            Some(&(at, _)) => at,
            None => {
                let at = self.end;
                self.placed.insert((item.index, item.sub), (at, size));
                self.end += size;
                at
            }
        };
        let offset = u16::try_from(at).map_err(|_| ExportError(format!("the process image is larger than 64 KiB at {:04X}h.{:02X}h", item.index, item.sub)))?;
        let flags = dsat_flags(item.access);
        if size <= 4 {
            self.tables.od.push(OdEntry { index: item.index, sub: item.sub, dsat: Dsat::new(size as u8, flags), offset });
        } else {
            let size = u16::try_from(size).map_err(|_| ExportError(format!("{:04X}h.{:02X}h is larger than 64 KiB", item.index, item.sub)))?;
            self.tables.generic.push(GenericEntry { index: item.index, sub: item.sub, access: Dsat(flags), size, offset });
        }
        Ok(at)
    }
}

/// The tables of `dict`. Refuses what the format cannot hold: a PDO parameter of more than 4
/// bytes, or a default PDO mapping an entry the dictionary lacks. Entries of no size are
/// left out.
pub fn lower(dict: &Dictionary, conventions: &Conventions) -> Result<Tables, ExportError> {
    let mut image = Image { conventions, placed: BTreeMap::new(), end: 0, tables: Tables::default() };
    for item in &dict.items {
        if is_reply(item) {
            let size = image.size_of(item);
            if !(1..=4).contains(&size) {
                return Err(ExportError(format!("{:04X}h.{:02X}h is a PDO parameter of {size} bytes; an SDO reply holds 1 to 4", item.index, item.sub)));
            }
            let value = sized(item.default.as_ref(), 4);
            let data = [value[0], value[1], value[2], value[3]];
            image.tables.replies.push(SdoReply::new(item.index, item.sub, data, size as u8));
        }
    }
    let (rpdo_maps, tpdo_maps) = (mappings(dict, 0x1600), mappings(dict, 0x1A00));
    let mut first_offsets: BTreeMap<u16, usize> = BTreeMap::new();
    for maps in [&rpdo_maps, &tpdo_maps] {
        for (mapping, entries) in maps {
            for (n, &(index, sub, bits)) in entries.iter().enumerate() {
                if index <= 0x0007 {
                    continue; // a dummy takes no process data
                }
                let item =
                    dict.item(index, sub).ok_or_else(|| ExportError(format!("{mapping:04X}h maps {index:04X}h.{sub:02X}h, which the dictionary lacks")))?;
                // A mapped string or domain takes what its PDO carries (an EDS cannot say its
                // length; CR3101's components are mapped at their default type's size).
                let size = if fixed_size(item.data_type).is_none() { usize::from(bits).div_ceil(8) } else { image.size_of(item) };
                let at = image.place_sized(item, size)?;
                if n == 0 {
                    first_offsets.insert(*mapping, at);
                }
            }
        }
        image.end = image.end.next_multiple_of(4);
    }
    for item in dict.items.iter().filter(|i| is_imaged(i)) {
        if image.placed.contains_key(&(item.index, item.sub)) {
            continue;
        }
        if conventions.served_by_firmware.contains(&item.index) {
            let flags = dsat_flags(item.access);
            image.tables.od.push(OdEntry { index: item.index, sub: item.sub, dsat: Dsat::new(item.size.min(15) as u8, flags), offset: 0 });
            continue;
        }
        let size = image.size_of(item);
        if size == 0 {
            // No size to reserve: a DOMAIN the firmware serves itself (program data, files),
            // or a string whose EDS has no default (an EDS cannot say a string's length).
            continue;
        }
        image.place(item)?;
    }
    let block = |value: fn(&Item) -> Option<&Vec<u8>>| {
        let mut bytes = vec![0; image.end];
        for (&(index, sub), &(at, size)) in &image.placed {
            if let Some(item) = dict.item(index, sub) {
                bytes[at..at + size].copy_from_slice(&sized(value(item), size));
            }
        }
        bytes
    };
    let (defaults, maximums, minimums) = (block(default_in_image), block(|i| i.high.as_ref()), block(|i| i.low.as_ref()));
    let pdo = |comm: u16, tx: bool| {
        let mapping = comm + 0x200;
        let map = rpdo_maps.iter().chain(&tpdo_maps).find(|(index, _)| *index == mapping);
        let bits: u32 = map.map_or(0, |(_, e)| e.iter().map(|&(_, _, b)| u32::from(b)).sum());
        PdoRecord {
            number: (comm & 0x1FF) as u8 + 1,
            transmission_type: u16_of(dict, comm, 2) as u8,
            length: (bits / 8) as u8,
            cob_id: dict.default_u64(comm, 1).unwrap_or(0) as u32,
            offset: first_offsets.get(&mapping).copied().unwrap_or(0) as u32,
            event_time: if tx { u16_of(dict, comm, 5) } else { 0 },
            inhibit_time: if tx { u16_of(dict, comm, 3) / 10 } else { 0 },
        }
    };
    let comm_objects = |base: u16| dict.items.iter().filter(move |i| i.sub == 0 && (base..base + 0x200).contains(&i.index)).map(|i| i.index);
    image.tables.rpdos = comm_objects(0x1400).map(|c| pdo(c, false)).collect();
    image.tables.tpdos = comm_objects(0x1800).map(|c| pdo(c, true)).collect();
    Ok(Tables { defaults, maximums, minimums, ..image.tables })
}
