//! The CiA 301 vocabulary shared by the spec tools (std) and the firmware (no_std): data
//! types, access types, object kinds, storage classes, NMT states.
#![no_std]
#![forbid(unsafe_code)]

use core::fmt;

/// The CiA 301 basic data types a spec may use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum DataType {
    Boolean,
    Integer8,
    Integer16,
    Integer24,
    Integer32,
    Integer40,
    Integer48,
    Integer56,
    Integer64,
    Unsigned8,
    Unsigned16,
    Unsigned24,
    Unsigned32,
    Unsigned40,
    Unsigned48,
    Unsigned56,
    Unsigned64,
    Real32,
    Real64,
    VisibleString,
    OctetString,
    UnicodeString,
    TimeOfDay,
    TimeDifference,
    Domain,
}

impl DataType {
    pub const ALL: [DataType; 25] = [
        DataType::Boolean,
        DataType::Integer8,
        DataType::Integer16,
        DataType::Integer24,
        DataType::Integer32,
        DataType::Integer40,
        DataType::Integer48,
        DataType::Integer56,
        DataType::Integer64,
        DataType::Unsigned8,
        DataType::Unsigned16,
        DataType::Unsigned24,
        DataType::Unsigned32,
        DataType::Unsigned40,
        DataType::Unsigned48,
        DataType::Unsigned56,
        DataType::Unsigned64,
        DataType::Real32,
        DataType::Real64,
        DataType::VisibleString,
        DataType::OctetString,
        DataType::UnicodeString,
        DataType::TimeOfDay,
        DataType::TimeDifference,
        DataType::Domain,
    ];

    /// The spec spelling, e.g. `UNSIGNED32`.
    pub fn name(self) -> &'static str {
        match self {
            DataType::Boolean => "BOOLEAN",
            DataType::Integer8 => "INTEGER8",
            DataType::Integer16 => "INTEGER16",
            DataType::Integer24 => "INTEGER24",
            DataType::Integer32 => "INTEGER32",
            DataType::Integer40 => "INTEGER40",
            DataType::Integer48 => "INTEGER48",
            DataType::Integer56 => "INTEGER56",
            DataType::Integer64 => "INTEGER64",
            DataType::Unsigned8 => "UNSIGNED8",
            DataType::Unsigned16 => "UNSIGNED16",
            DataType::Unsigned24 => "UNSIGNED24",
            DataType::Unsigned32 => "UNSIGNED32",
            DataType::Unsigned40 => "UNSIGNED40",
            DataType::Unsigned48 => "UNSIGNED48",
            DataType::Unsigned56 => "UNSIGNED56",
            DataType::Unsigned64 => "UNSIGNED64",
            DataType::Real32 => "REAL32",
            DataType::Real64 => "REAL64",
            DataType::VisibleString => "VISIBLE_STRING",
            DataType::OctetString => "OCTET_STRING",
            DataType::UnicodeString => "UNICODE_STRING",
            DataType::TimeOfDay => "TIME_OF_DAY",
            DataType::TimeDifference => "TIME_DIFFERENCE",
            DataType::Domain => "DOMAIN",
        }
    }

    pub fn from_name(s: &str) -> Option<DataType> {
        DataType::ALL.into_iter().find(|t| t.name() == s)
    }

    /// The data type index of CiA 301 table 44, used as `DataType=` in an EDS.
    pub fn code(self) -> u16 {
        match self {
            DataType::Boolean => 0x0001,
            DataType::Integer8 => 0x0002,
            DataType::Integer16 => 0x0003,
            DataType::Integer32 => 0x0004,
            DataType::Unsigned8 => 0x0005,
            DataType::Unsigned16 => 0x0006,
            DataType::Unsigned32 => 0x0007,
            DataType::Real32 => 0x0008,
            DataType::VisibleString => 0x0009,
            DataType::OctetString => 0x000A,
            DataType::UnicodeString => 0x000B,
            DataType::TimeOfDay => 0x000C,
            DataType::TimeDifference => 0x000D,
            DataType::Domain => 0x000F,
            DataType::Integer24 => 0x0010,
            DataType::Real64 => 0x0011,
            DataType::Integer40 => 0x0012,
            DataType::Integer48 => 0x0013,
            DataType::Integer56 => 0x0014,
            DataType::Integer64 => 0x0015,
            DataType::Unsigned24 => 0x0016,
            DataType::Unsigned40 => 0x0018,
            DataType::Unsigned48 => 0x0019,
            DataType::Unsigned56 => 0x001A,
            DataType::Unsigned64 => 0x001B,
        }
    }

    /// Size in bits for fixed-size types; `None` for strings and domains.
    pub fn bits(self) -> Option<u32> {
        Some(match self {
            DataType::Boolean => 1,
            DataType::Integer8 | DataType::Unsigned8 => 8,
            DataType::Integer16 | DataType::Unsigned16 => 16,
            DataType::Integer24 | DataType::Unsigned24 => 24,
            DataType::Integer32 | DataType::Unsigned32 | DataType::Real32 => 32,
            DataType::Integer40 | DataType::Unsigned40 => 40,
            DataType::Integer48 | DataType::Unsigned48 | DataType::TimeOfDay | DataType::TimeDifference => 48,
            DataType::Integer56 | DataType::Unsigned56 => 56,
            DataType::Integer64 | DataType::Unsigned64 | DataType::Real64 => 64,
            DataType::VisibleString | DataType::OctetString | DataType::UnicodeString | DataType::Domain => return None,
        })
    }

    pub fn is_string(self) -> bool {
        matches!(self, DataType::VisibleString | DataType::OctetString | DataType::UnicodeString)
    }

    pub fn is_real(self) -> bool {
        matches!(self, DataType::Real32 | DataType::Real64)
    }

    /// The inclusive integer range of an integer type (BOOLEAN is 0..=1).
    pub fn int_range(self) -> Option<(i128, i128)> {
        use DataType::*;
        // Computed from the width rather than matched per type: 17 pairs of 128-bit constants
        // cost more flash on a Cortex-M0 than the two shifts.
        let signed = matches!(self, Integer8 | Integer16 | Integer24 | Integer32 | Integer40 | Integer48 | Integer56 | Integer64);
        let unsigned = matches!(self, Boolean | Unsigned8 | Unsigned16 | Unsigned24 | Unsigned32 | Unsigned40 | Unsigned48 | Unsigned56 | Unsigned64);
        let bits = self.bits().filter(|_| signed || unsigned)?;
        Some(if signed { (-(1_i128 << (bits - 1)), (1_i128 << (bits - 1)) - 1) } else { (0, (1_i128 << bits) - 1) })
    }
}

impl fmt::Display for DataType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// CAN-side access type (CiA 306 spelling).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Access {
    Ro,
    Wo,
    Rw,
    /// Read/write, mapped into TPDOs (process input).
    Rwr,
    /// Read/write, mapped into RPDOs (process output).
    Rww,
    Const,
    /// Not reachable from the CAN bus (an SDO gets "object does not exist"); the entry exists
    /// for the device and, where `host_access` allows, for the serial host. Not in the EDS.
    None,
}

impl Access {
    pub fn parse(s: &str) -> Option<Access> {
        Some(match s {
            "ro" => Access::Ro,
            "wo" => Access::Wo,
            "rw" => Access::Rw,
            "rwr" => Access::Rwr,
            "rww" => Access::Rww,
            "const" => Access::Const,
            "none" => Access::None,
            _ => return None,
        })
    }
    pub fn name(self) -> &'static str {
        match self {
            Access::None => "none",
            Access::Ro => "ro",
            Access::Wo => "wo",
            Access::Rw => "rw",
            Access::Rwr => "rwr",
            Access::Rww => "rww",
            Access::Const => "const",
        }
    }
    pub fn readable(self) -> bool {
        !matches!(self, Access::Wo | Access::None)
    }
    pub fn writable(self) -> bool {
        matches!(self, Access::Wo | Access::Rw | Access::Rwr | Access::Rww)
    }
}

impl fmt::Display for Access {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// NMT states (CiA 301) in which a CAN-side write may be restricted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum NmtState {
    PreOperational,
    Operational,
    Stopped,
}

impl NmtState {
    pub fn parse(s: &str) -> Option<NmtState> {
        Some(match s {
            "preoperational" => NmtState::PreOperational,
            "operational" => NmtState::Operational,
            "stopped" => NmtState::Stopped,
            _ => return None,
        })
    }
    pub fn name(self) -> &'static str {
        match self {
            NmtState::PreOperational => "preoperational",
            NmtState::Operational => "operational",
            NmtState::Stopped => "stopped",
        }
    }
}

/// The serial host's access to an entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HostAccess {
    None,
    Ro,
    Wo,
    Rw,
}

impl HostAccess {
    pub fn parse(s: &str) -> Option<HostAccess> {
        Some(match s {
            "none" => HostAccess::None,
            "ro" => HostAccess::Ro,
            "wo" => HostAccess::Wo,
            "rw" => HostAccess::Rw,
            _ => return None,
        })
    }
    pub fn from_flags(read: bool, write: bool) -> HostAccess {
        match (read, write) {
            (false, false) => HostAccess::None,
            (true, false) => HostAccess::Ro,
            (false, true) => HostAccess::Wo,
            (true, true) => HostAccess::Rw,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            HostAccess::None => "none",
            HostAccess::Ro => "ro",
            HostAccess::Wo => "wo",
            HostAccess::Rw => "rw",
        }
    }
    pub fn readable(self) -> bool {
        matches!(self, HostAccess::Ro | HostAccess::Rw)
    }
    pub fn writable(self) -> bool {
        matches!(self, HostAccess::Wo | HostAccess::Rw)
    }
}

/// When a host write is allowed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum WriteWhen {
    Always,
    /// Only before the host has enabled the CANopen interface (CO401GW1 100B).
    BeforeCanEnabled,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ObjectKind {
    Var,
    Array,
    Record,
    Domain,
}

impl ObjectKind {
    pub fn parse(s: &str) -> Option<ObjectKind> {
        Some(match s {
            "var" => ObjectKind::Var,
            "array" => ObjectKind::Array,
            "record" => ObjectKind::Record,
            "domain" => ObjectKind::Domain,
            _ => return None,
        })
    }
    /// CiA 306 `ObjectType=` value.
    pub fn code(self) -> u8 {
        match self {
            ObjectKind::Domain => 0x2,
            ObjectKind::Var => 0x7,
            ObjectKind::Array => 0x8,
            ObjectKind::Record => 0x9,
        }
    }
    pub fn has_subs(self) -> bool {
        matches!(self, ObjectKind::Array | ObjectKind::Record)
    }
    pub fn name(self) -> &'static str {
        match self {
            ObjectKind::Var => "VAR",
            ObjectKind::Array => "ARRAY",
            ObjectKind::Record => "RECORD",
            ObjectKind::Domain => "DOMAIN",
        }
    }
}

/// Where an entry's value lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Storage {
    /// In RAM, reset to the default at boot.
    Ram,
    /// Saved by 1010 and restored by 1011.
    Persistent,
    /// Owned by the device (EEPROM banks, a memory card): reads and writes go to device hooks.
    App,
}

impl Storage {
    pub fn parse(s: &str) -> Option<Storage> {
        Some(match s {
            "ram" => Storage::Ram,
            "persistent" => Storage::Persistent,
            "app" => Storage::App,
            _ => return None,
        })
    }
    pub fn name(self) -> &'static str {
        match self {
            Storage::Ram => "ram",
            Storage::Persistent => "persistent",
            Storage::App => "app",
        }
    }
}

/// What sub 0 of an ARRAY/RECORD means.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sub0 {
    /// Read-only, equal to the highest sub-index.
    Highest,
    /// The number of valid entries (1003, PDO mapping objects); may be writable.
    Count,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_type_names_round_trip_and_codes_are_unique() {
        for (i, t) in DataType::ALL.into_iter().enumerate() {
            assert_eq!(DataType::from_name(t.name()), Some(t));
            assert!(DataType::ALL[..i].iter().all(|o| o.code() != t.code()), "{t} code repeated");
        }
        assert_eq!(DataType::Unsigned32.int_range(), Some((0, 0xFFFF_FFFF)));
        assert_eq!(DataType::Integer8.int_range(), Some((-128, 127)));
    }

    #[test]
    fn integer_ranges_follow_the_width_and_only_integers_have_one() {
        use DataType::*;
        assert_eq!(Boolean.int_range(), Some((0, 1)));
        assert_eq!(Integer24.int_range(), Some((-0x80_0000, 0x7F_FFFF)));
        assert_eq!(Integer64.int_range(), Some((i128::from(i64::MIN), i128::from(i64::MAX))));
        assert_eq!(Unsigned56.int_range(), Some((0, 0xFF_FFFF_FFFF_FFFF)));
        assert_eq!(Unsigned64.int_range(), Some((0, i128::from(u64::MAX))));
        for t in [Real32, Real64, TimeOfDay, TimeDifference, VisibleString, OctetString, UnicodeString, Domain] {
            assert_eq!(t.int_range(), None, "{t}");
        }
    }
}

/// A condition the CANopen stack detects by itself, tied to the spec emergency it sends
/// (`event:` in the spec). Events without a spec emergency use the CiA 301 code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EmcyEvent {
    /// No guarding remote frame within the node life time (100C x 100D).
    LifeGuarding,
    /// No guarding remote frame within the guard time (frenzel+berg 2103).
    GuardingWarning,
    /// A consumed heartbeat (1016) was not received in time.
    HeartbeatTimeout,
    /// The CAN controller reached its error-warning limit.
    CanWarning,
    /// The CAN controller went error-passive.
    CanPassive,
    /// Received frames were lost (controller overrun).
    CanOverrun,
    /// The CAN controller went bus-off.
    BusOff,
    /// The CAN controller returned from bus-off.
    BusOffRecovered,
    /// A received PDO was shorter than its mapping.
    RpdoLength,
    /// No SYNC within 1.5 times the communication cycle period (1006h).
    SyncTimeout,
    /// An RPDO did not arrive within its event timer (CiA 301 RPDO deadline monitoring).
    RpdoTimeout,
}

impl EmcyEvent {
    pub const ALL: [EmcyEvent; 11] = [
        EmcyEvent::LifeGuarding,
        EmcyEvent::GuardingWarning,
        EmcyEvent::HeartbeatTimeout,
        EmcyEvent::CanWarning,
        EmcyEvent::CanPassive,
        EmcyEvent::CanOverrun,
        EmcyEvent::BusOff,
        EmcyEvent::BusOffRecovered,
        EmcyEvent::RpdoLength,
        EmcyEvent::SyncTimeout,
        EmcyEvent::RpdoTimeout,
    ];

    /// The spec keyword.
    pub const fn name(self) -> &'static str {
        match self {
            EmcyEvent::LifeGuarding => "life_guarding",
            EmcyEvent::GuardingWarning => "guarding_warning",
            EmcyEvent::HeartbeatTimeout => "heartbeat_timeout",
            EmcyEvent::CanWarning => "can_warning",
            EmcyEvent::CanPassive => "can_passive",
            EmcyEvent::CanOverrun => "can_overrun",
            EmcyEvent::BusOff => "bus_off",
            EmcyEvent::BusOffRecovered => "bus_off_recovered",
            EmcyEvent::RpdoLength => "rpdo_length",
            EmcyEvent::SyncTimeout => "sync_timeout",
            EmcyEvent::RpdoTimeout => "rpdo_timeout",
        }
    }

    pub fn parse(s: &str) -> Option<EmcyEvent> {
        EmcyEvent::ALL.into_iter().find(|e| e.name() == s)
    }

    /// The CiA 301 error code (table 21) when the spec lists no emergency for the event.
    pub const fn default_code(self) -> u16 {
        match self {
            EmcyEvent::LifeGuarding | EmcyEvent::GuardingWarning | EmcyEvent::HeartbeatTimeout => 0x8130,
            EmcyEvent::CanWarning => 0x8100,
            EmcyEvent::CanOverrun => 0x8110,
            EmcyEvent::CanPassive => 0x8120,
            EmcyEvent::BusOff | EmcyEvent::BusOffRecovered => 0x8140,
            EmcyEvent::RpdoLength => 0x8210,
            EmcyEvent::SyncTimeout => 0x8100,
            EmcyEvent::RpdoTimeout => 0x8250,
        }
    }

    /// Whether the event counts as a communication error for 1029h sub 1.
    pub const fn is_communication_error(self) -> bool {
        matches!(self, EmcyEvent::LifeGuarding | EmcyEvent::HeartbeatTimeout | EmcyEvent::BusOff)
    }
}
