//! [`BinaryEds::parse`]: the whole file is checked once, up front; afterwards every table
//! accessor only walks ranges that were proven to be inside the file.

use crate::layout::{self, Table, func, header};
use crate::records::{GenericEntry, OdEntry, PdoRecord, SdoReply};
use core::fmt;

/// Why a file is not a valid binary EDS v2.00.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error {
    /// Shorter than a header, the table offsets and a CRC.
    TooShort {
        len: usize,
    },
    Crc {
        stored: u16,
        computed: u16,
    },
    Magic,
    Version {
        major: u16,
        minor: u16,
    },
    /// FUNC bits the format reserves (6..31) are set.
    ReservedFunc {
        func: u32,
    },
    /// A table starts outside the file, or runs past its end (or has no sentinel).
    TableOutOfFile {
        table: Table,
        offset: u32,
    },
    /// An SDO reply whose command byte is not an expedited upload response with a size.
    BadReply {
        index: u16,
        sub: u8,
        command: u8,
    },
    /// An entry of no size, more than 4 bytes in the OD entry table, or reaching past the
    /// process image.
    BadEntry {
        index: u16,
        sub: u8,
    },
    /// The header's PDO count differs from the records in its table.
    PdoCount {
        table: Table,
        header: u16,
        records: usize,
    },
    /// A PDO of more than 8 bytes, or whose data is not inside the process image.
    BadPdo {
        table: Table,
        number: u8,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::TooShort { len } => write!(f, "{len} bytes is too short for a binary EDS (at least {})", layout::TABLES_AT + layout::CRC_LEN),
            Error::Crc { stored, computed } => write!(f, "CRC mismatch: the file says {stored:04X}h, its bytes give {computed:04X}h"),
            Error::Magic => f.write_str("no `POCM` at header byte 4: not a binary EDS"),
            Error::Version { major, minor } => write!(f, "format version {major}.{minor:02}; only 2.00 is supported"),
            Error::ReservedFunc { func } => write!(f, "FUNC {func:08X}h sets reserved bits 6..31"),
            Error::TableOutOfFile { table, offset } => write!(f, "the {} at offset {offset} is not inside the file (or has no end marker)", table.name()),
            Error::BadReply { index, sub, command } => {
                write!(f, "SDO reply of {index:04X}h.{sub:02X}h has command byte {command:02X}h, not an expedited upload response")
            }
            Error::BadEntry { index, sub } => write!(f, "entry {index:04X}h.{sub:02X}h has a bad size or lies outside the process image"),
            Error::PdoCount { table, header, records } => write!(f, "the header counts {header} PDOs, the {} has {records}", table.name()),
            Error::BadPdo { table, number } => write!(f, "PDO {number} of the {} is longer than 8 bytes or outside the process image", table.name()),
        }
    }
}

/// The header's fields.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header<'a> {
    pub func: u32,
    pub bitrate_kbit: u16,
    pub node_id: u8,
    pub rpdos: u16,
    pub tpdos: u16,
    pub image_size: u32,
    /// The identification string, without its 0x00 padding (ISO-8859-1).
    pub ident: &'a [u8],
}

/// A checked binary EDS file, borrowed.
#[derive(Debug, Clone, Copy)]
pub struct BinaryEds<'a> {
    bytes: &'a [u8],
    header: Header<'a>,
    /// Each table's start and end (for record tables: the sentinel's start), in `Table` order.
    ranges: [(usize, usize); 8],
}

fn u16_at(b: &[u8], at: usize) -> u16 {
    b.get(at..at + 2).and_then(|s| s.try_into().ok()).map_or(0, u16::from_le_bytes)
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    b.get(at..at + 4).and_then(|s| s.try_into().ok()).map_or(0, u32::from_le_bytes)
}

/// The records of a table before its sentinel; `None` if the sentinel is not inside `body`.
fn record_table_end(body: &[u8], start: usize, len: usize) -> Option<usize> {
    let mut at = start;
    loop {
        let record = body.get(at..at.checked_add(len)?)?;
        if record.iter().all(|&b| b == layout::SENTINEL) {
            return Some(at);
        }
        at += len;
    }
}

impl<'a> BinaryEds<'a> {
    /// Checks every rule of the format (see the crate docs) and returns the file's view.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, Error> {
        let min = layout::TABLES_AT + layout::CRC_LEN;
        if bytes.len() < min {
            return Err(Error::TooShort { len: bytes.len() });
        }
        let (body, crc) = bytes.split_at(bytes.len() - layout::CRC_LEN);
        let stored = u16_at(crc, 0);
        let computed = layout::crc(body);
        if stored != computed {
            return Err(Error::Crc { stored, computed });
        }
        if body.get(header::MAGIC..header::MAGIC + 4) != Some(&layout::MAGIC[..]) {
            return Err(Error::Magic);
        }
        let (major, minor) = (u16_at(body, header::MAJOR), u16_at(body, header::MINOR));
        if (major, minor) != layout::VERSION {
            return Err(Error::Version { major, minor });
        }
        let func = u32_at(body, header::FUNC);
        if func & !func::DEFINED != 0 {
            return Err(Error::ReservedFunc { func });
        }
        let ident = body.get(header::IDENT..header::IDENT + header::IDENT_LEN).unwrap_or(&[]);
        let ident_len = ident.iter().rposition(|&b| b != 0).map_or(0, |last| last + 1);
        let header = Header {
            func,
            bitrate_kbit: u16_at(body, header::BITRATE_KBIT),
            node_id: body.get(header::NODE_ID).copied().unwrap_or(0),
            rpdos: u16_at(body, header::RPDOS),
            tpdos: u16_at(body, header::TPDOS),
            image_size: u32_at(body, header::IMAGE_SIZE),
            ident: ident.get(..ident_len).unwrap_or(&[]),
        };
        let image = usize::try_from(header.image_size).unwrap_or(usize::MAX);
        let mut ranges = [(0, 0); 8];
        for ((n, table), range) in Table::ALL.iter().enumerate().zip(ranges.iter_mut()) {
            let offset = u32_at(body, layout::OFFSETS_AT + 4 * n);
            let start = usize::try_from(offset).unwrap_or(usize::MAX);
            let out = Error::TableOutOfFile { table: *table, offset };
            let limits = matches!(table, Table::Maximums | Table::Minimums);
            if limits && func & func::LIMIT_TABLES == 0 {
                // Absent: empty, whatever its offset says.
                continue;
            }
            if start < layout::TABLES_AT {
                return Err(out);
            }
            let end = match table.record_len() {
                Some(len) => record_table_end(body, start, len).ok_or(out)?,
                None => start.checked_add(image).filter(|&end| end <= body.len()).ok_or(out)?,
            };
            *range = (start, end);
        }
        let eds = BinaryEds { bytes, header, ranges };
        eds.check_records()?;
        Ok(eds)
    }

    fn check_records(&self) -> Result<(), Error> {
        let image = self.header.image_size;
        let inside = |offset: u16, size: u16| size > 0 && u32::from(offset) + u32::from(size) <= image;
        if let Some(r) = self.sdo_replies().find(|r| r.size().is_none()) {
            return Err(Error::BadReply { index: r.index, sub: r.sub, command: r.command });
        }
        if let Some(e) = self.od_entries().find(|e| e.size() > 4 || !inside(e.offset, e.size())) {
            return Err(Error::BadEntry { index: e.index, sub: e.sub });
        }
        if let Some(e) = self.generic_entries().find(|e| !inside(e.offset, e.size)) {
            return Err(Error::BadEntry { index: e.index, sub: e.sub });
        }
        for (table, header) in [(Table::Rpdos, self.header.rpdos), (Table::Tpdos, self.header.tpdos)] {
            let records = self.pdos(table).count();
            if records != usize::from(header) {
                return Err(Error::PdoCount { table, header, records });
            }
            let fits = |p: &PdoRecord| p.length <= 8 && p.offset.checked_add(u32::from(p.length)).is_some_and(|end| end <= image);
            if let Some(p) = self.pdos(table).find(|p| !fits(p)) {
                return Err(Error::BadPdo { table, number: p.number });
            }
        }
        Ok(())
    }

    pub fn header(&self) -> &Header<'a> {
        &self.header
    }

    /// The whole file, CRC included.
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// Where a table starts and ends in the file (a record table ends before its sentinel).
    pub fn range(&self, table: Table) -> (usize, usize) {
        Table::ALL.iter().position(|t| *t == table).and_then(|n| self.ranges.get(n)).copied().unwrap_or((0, 0))
    }

    fn table(&self, table: Table) -> &'a [u8] {
        let (start, end) = self.range(table);
        self.bytes.get(start..end).unwrap_or(&[])
    }

    fn records<const N: usize>(&self, table: Table) -> impl Iterator<Item = &'a [u8; N]> + 'a {
        self.table(table).chunks_exact(N).filter_map(|r| r.try_into().ok())
    }

    pub fn sdo_replies(&self) -> impl Iterator<Item = SdoReply> + 'a {
        self.records::<{ SdoReply::LEN }>(Table::SdoReplies).map(SdoReply::decode)
    }

    pub fn od_entries(&self) -> impl Iterator<Item = OdEntry> + 'a {
        self.records::<{ OdEntry::LEN }>(Table::OdEntries).map(OdEntry::decode)
    }

    pub fn generic_entries(&self) -> impl Iterator<Item = GenericEntry> + 'a {
        self.records::<{ GenericEntry::LEN }>(Table::GenericEntries).map(GenericEntry::decode)
    }

    /// The records of [`Table::Rpdos`] or [`Table::Tpdos`] (nothing for another table).
    pub fn pdos(&self, table: Table) -> impl Iterator<Item = PdoRecord> + 'a {
        let (bytes, len) = match table {
            Table::Rpdos => (self.table(table), PdoRecord::RPDO_LEN),
            Table::Tpdos => (self.table(table), PdoRecord::TPDO_LEN),
            _ => (&[][..], PdoRecord::RPDO_LEN),
        };
        bytes.chunks_exact(len).map(PdoRecord::decode)
    }

    /// A process-image block: [`Table::Defaults`], and with FUNC bit 4 the maximums and
    /// minimums (empty otherwise).
    pub fn image(&self, table: Table) -> &'a [u8] {
        match table {
            Table::Defaults | Table::Maximums | Table::Minimums => self.table(table),
            _ => &[],
        }
    }

    /// `size` bytes at `offset` of a process-image block (empty if outside it).
    pub fn image_value(&self, table: Table, offset: u16, size: u16) -> &'a [u8] {
        let start = usize::from(offset);
        self.image(table).get(start..start + usize::from(size)).unwrap_or(&[])
    }
}
