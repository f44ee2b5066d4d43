//! Process data objects (CiA 301 7.2.2): the spec defaults, mapping checks, and the runtime
//! state of each RPDO and TPDO.

mod defaults;
pub mod mapping;
pub mod slot;

pub use defaults::{CobIdDefault, PdoDefault};
pub use mapping::{Mapped, Mapping};
pub use slot::{Comm, Rpdo, Tpdo};

/// Which way a PDO goes, seen from the node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dir {
    /// Received (RPDO): communication at 1400h + n, mapping at 1600h + n.
    Rx,
    /// Transmitted (TPDO): 1800h + n, mapping 1A00h + n.
    Tx,
}

impl Dir {
    pub const fn comm_base(self) -> u16 {
        match self {
            Dir::Rx => 0x1400,
            Dir::Tx => 0x1800,
        }
    }

    /// The mapping object that belongs to a communication object.
    pub const fn mapping_of(comm_index: u16) -> u16 {
        comm_index + 0x200
    }

    /// The direction and slot offset of a PDO communication or mapping object.
    pub const fn of_index(index: u16) -> Option<(Dir, bool, u16)> {
        match index {
            0x1400..=0x15FF => Some((Dir::Rx, false, index - 0x1400)),
            0x1600..=0x17FF => Some((Dir::Rx, true, index - 0x1600)),
            0x1800..=0x19FF => Some((Dir::Tx, false, index - 0x1800)),
            0x1A00..=0x1BFF => Some((Dir::Tx, true, index - 0x1A00)),
            _ => None,
        }
    }
}

/// COB-ID bit 31: the PDO does not exist (is not valid).
pub const COB_INVALID: u32 = 1 << 31;
/// COB-ID bit 30: no RTR allowed on this PDO.
pub const COB_NO_RTR: u32 = 1 << 30;
/// COB-ID bit 29: 29-bit identifier (not supported: CiA 301 predefined set is 11-bit).
pub const COB_EXTENDED: u32 = 1 << 29;

/// Identifiers CiA 301 (7.3.5) reserves for other services; a valid PDO may not use them.
pub const fn restricted_cob_id(id: u16) -> bool {
    matches!(id, 0x000 | 0x001..=0x07F | 0x101..=0x180 | 0x581..=0x5FF | 0x601..=0x67F | 0x6E0..=0x6FF | 0x701..=0x77F | 0x780..=0x7FF)
}
