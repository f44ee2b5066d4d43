//! Where everything is in a binary EDS v2.00 file. All multi-byte values are little-endian.
//!
//! ```text
//! 0    header (128 bytes)
//! 128  eight u32 table offsets, from the start of the file, in `Table` order
//! 160  the tables, each where its offset says, up to 8 bytes of 0x00 between them
//! end  CRC-16/XMODEM of every byte before it, low byte first
//! ```

/// The format version this crate reads and writes.
pub const VERSION: (u16, u16) = (2, 0);
/// Header bytes 4..8.
pub const MAGIC: [u8; 4] = *b"POCM";
pub const HEADER_LEN: usize = 128;
/// Where the table offsets start, and where the first table may start.
pub const OFFSETS_AT: usize = HEADER_LEN;
pub const TABLES_AT: usize = OFFSETS_AT + 4 * Table::ALL.len();
pub const CRC_LEN: usize = 2;
/// Header fields: (offset, size).
pub mod header {
    pub const MAJOR: usize = 0;
    pub const MINOR: usize = 2;
    pub const MAGIC: usize = 4;
    pub const FUNC: usize = 8;
    pub const BITRATE_KBIT: usize = 12;
    pub const NODE_ID: usize = 14;
    pub const RPDOS: usize = 16;
    pub const TPDOS: usize = 18;
    pub const IMAGE_SIZE: usize = 20;
    pub const IDENT: usize = 32;
    pub const IDENT_LEN: usize = 96;
}

/// Bits of the header's FUNC word.
pub mod func {
    pub const LSS: u32 = 1 << 0;
    pub const AUTOSTART: u32 = 1 << 1;
    pub const BOOTUP_MANAGER: u32 = 1 << 2;
    pub const MANAGER: u32 = 1 << 3;
    /// The process-image maximum and minimum tables are present.
    pub const LIMIT_TABLES: u32 = 1 << 4;
    /// Node-ID and bit rate come from hardware, not from the header.
    pub const SETTINGS_FROM_HARDWARE: u32 = 1 << 5;
    pub const DEFINED: u32 = 0x3F;
}

/// Padding a writer may put before a table (alignment); a reader accepts up to this much.
pub const MAX_PADDING: usize = 8;
/// The byte of a table's end marker: a record of all 0xFF.
pub const SENTINEL: u8 = 0xFF;

/// The eight tables, in the order of their offsets at byte 128.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Table {
    SdoReplies,
    OdEntries,
    GenericEntries,
    Defaults,
    Maximums,
    Minimums,
    Rpdos,
    Tpdos,
}

impl Table {
    pub const ALL: [Table; 8] =
        [Table::SdoReplies, Table::OdEntries, Table::GenericEntries, Table::Defaults, Table::Maximums, Table::Minimums, Table::Rpdos, Table::Tpdos];

    /// The size of one record of a record table (ended by a sentinel); `None` for the
    /// process-image blocks, which are as long as the header's image size.
    pub const fn record_len(self) -> Option<usize> {
        match self {
            Table::SdoReplies | Table::GenericEntries => Some(8),
            Table::OdEntries => Some(6),
            Table::Rpdos => Some(12),
            Table::Tpdos => Some(16),
            Table::Defaults | Table::Maximums | Table::Minimums => None,
        }
    }

    pub const fn name(self) -> &'static str {
        match self {
            Table::SdoReplies => "SDO reply table",
            Table::OdEntries => "OD entry table",
            Table::GenericEntries => "generic OD entry table",
            Table::Defaults => "process-image defaults",
            Table::Maximums => "process-image maximums",
            Table::Minimums => "process-image minimums",
            Table::Rpdos => "RPDO configuration",
            Table::Tpdos => "TPDO configuration",
        }
    }
}

/// An entry's size and access: the DSAT byte of an OD entry record (bits 0..3 the size), and
/// bits 4..7 of a generic entry's ACC byte (its size is a field of its own).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Dsat(pub u8);

impl Dsat {
    pub const READ: u8 = 1 << 4;
    pub const WRITE: u8 = 1 << 5;
    /// Mappable into a TPDO.
    pub const TPDO: u8 = 1 << 6;
    /// Mappable into an RPDO.
    pub const RPDO: u8 = 1 << 7;

    pub const fn new(size: u8, flags: u8) -> Self {
        Dsat((size & 0x0F) | (flags & 0xF0))
    }
    pub const fn size(self) -> u8 {
        self.0 & 0x0F
    }
    pub const fn readable(self) -> bool {
        self.0 & Self::READ != 0
    }
    pub const fn writable(self) -> bool {
        self.0 & Self::WRITE != 0
    }
    pub const fn tpdo(self) -> bool {
        self.0 & Self::TPDO != 0
    }
    pub const fn rpdo(self) -> bool {
        self.0 & Self::RPDO != 0
    }
    pub const fn flags(self) -> u8 {
        self.0 & 0xF0
    }
}

/// The file's CRC: CRC-16/XMODEM, the SDO block-transfer CRC.
pub fn crc(bytes: &[u8]) -> u16 {
    coforge_link::crc::CCITT.checksum(bytes)
}
