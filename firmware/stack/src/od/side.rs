//! Who accesses the dictionary, and the node state a write is judged against.

use coforge_types::NmtState;

/// Who accesses the dictionary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// A CANopen master (SDO) or a received PDO.
    Bus,
    /// The serial host, through the device's protocol.
    Host,
    /// The device's own behaviour code: no access rule applies, only lengths and limits.
    Device,
}

/// Where a write came from, as [`AppObjects::written`](super::AppObjects::written) reports
/// it: the [`Side`] whose access rules it followed, with the bus split into its two services
/// (SDO and RPDO follow the same rules, so `Side` does not tell them apart).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WriteSource {
    /// An SDO download (expedited, segmented or block).
    Sdo,
    /// The serial host.
    Host,
    /// The device's own code.
    Device,
    /// A received PDO, one write per mapped entry.
    Rpdo,
}

impl WriteSource {
    /// The side whose access rules the write follows.
    pub const fn side(self) -> Side {
        match self {
            WriteSource::Sdo | WriteSource::Rpdo => Side::Bus,
            WriteSource::Host => Side::Host,
            WriteSource::Device => Side::Device,
        }
    }

    /// A write made on behalf of `side` through the node's own write: a bus write there
    /// stands for an SDO download (RPDOs are written by the node alone).
    pub const fn of_side(side: Side) -> WriteSource {
        match side {
            Side::Bus => WriteSource::Sdo,
            Side::Host => WriteSource::Host,
            Side::Device => WriteSource::Device,
        }
    }
}

/// A set of NMT states, for entries that may only be written in some of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NmtStates(u8);

impl NmtStates {
    pub const NONE: NmtStates = NmtStates(0);
    pub const ALL: NmtStates = NmtStates(0b111);

    const fn bit(state: NmtState) -> u8 {
        match state {
            NmtState::PreOperational => 0b001,
            NmtState::Operational => 0b010,
            NmtState::Stopped => 0b100,
        }
    }

    pub const fn with(self, state: NmtState) -> NmtStates {
        NmtStates(self.0 | Self::bit(state))
    }

    pub const fn contains(self, state: NmtState) -> bool {
        self.0 & Self::bit(state) != 0
    }

    /// The set as three bits, for [`EntryFlags`](super::entry::EntryFlags).
    pub(crate) const fn bits(self) -> u8 {
        self.0
    }

    /// The set in the low three bits of `bits`.
    pub(crate) const fn from_bits(bits: u8) -> NmtStates {
        NmtStates(bits & Self::ALL.0)
    }
}

/// What a write is judged against besides the entry itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AccessContext {
    pub nmt: NmtState,
    /// The host has enabled the CANopen interface (CO401GW1's command 0x02).
    pub can_enabled: bool,
}
