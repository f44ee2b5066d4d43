//! What the runtime knows about an entry, and the checks every access passes: one rule, one
//! abort code, one place, whichever side asks.

use super::{AccessContext, NmtStates, SdoAbort, Side};
use coforge_types::{Access, DataType, HostAccess, Storage};

/// Value limits of an entry, kept out of line: most entries have none.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    pub low: Option<i64>,
    pub high: Option<i64>,
    /// If not empty, the only values a write may store.
    pub values: &'static [i64],
}

/// What the runtime knows about an entry, or about a run of identical entries (the 128 bytes
/// of a memory block share one `EntryInfo` with `sub..=last_sub`), so that the generated
/// table stays small in flash: 12 bytes a run, the small properties packed into three bytes
/// and read through accessors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EntryInfo {
    pub index: u16,
    /// Where the value of sub-index `sub` starts in the dictionary's value image
    /// ([`image`](super::image)); the run's further sub-indices follow at
    /// [`image::stride`](super::image::stride). Unused (0) for app-backed entries.
    pub offset: u16,
    /// Size in bytes; for strings and domains the maximum.
    pub size: u16,
    /// First sub-index this description covers.
    pub sub: u8,
    /// Last sub-index this description covers (equal to `sub` for a single entry).
    pub last_sub: u8,
    /// Value limits: 0 for none, `n` for entry `n - 1` of the dictionary's limits table
    /// ([`EntryAccess::limits`](super::EntryAccess::limits)), which the value checks receive.
    pub limits: u8,
    /// The data type and the CAN-side access: [`data_type`](Self::data_type),
    /// [`access`](Self::access).
    pub kind: EntryKind,
    /// Everything else: [`host_access`](Self::host_access), [`storage`](Self::storage),
    /// [`pdo_mappable`](Self::pdo_mappable),
    /// [`host_write_before_can_enabled`](Self::host_write_before_can_enabled),
    /// [`writable_in`](Self::writable_in) and [`copies`](Self::copies).
    pub flags: EntryFlags,
}

/// An entry's data type (bits 0..=4) and CAN-side access (bits 5..=7), each as its enum's
/// discriminant.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EntryKind(u8);

impl EntryKind {
    pub const fn new(data_type: DataType, access: Access) -> EntryKind {
        EntryKind(data_type as u8 | (access as u8) << 5)
    }
}

/// The other properties of an entry, two bytes: bits 0..=2 the NMT states of bus writes, bit 3
/// PDO-mappable, bit 4 host writes only before the CAN interface is enabled, bits 5..=6 the
/// storage class, bits 7..=8 the host access, bits 9..=13 the copies. Built with [`new`]
/// and the `const` setters, which generated tables spell out.
///
/// [`new`]: EntryFlags::new
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EntryFlags(u16);

impl EntryFlags {
    const PDO_MAPPABLE: u16 = 1 << 3;
    const HOST_WRITE_BEFORE_CAN_ENABLED: u16 = 1 << 4;
    const STORAGE_SHIFT: u16 = 5;
    const HOST_SHIFT: u16 = 7;
    const COPIES_SHIFT: u16 = 9;

    /// Host access and storage; writable by the bus in every NMT state, not PDO-mappable, no
    /// host-write rule, no copies.
    pub const fn new(host_access: HostAccess, storage: Storage) -> EntryFlags {
        let storage = match storage {
            Storage::Ram => 0,
            Storage::Persistent => 1,
            Storage::App => 2,
        };
        let host = match host_access {
            HostAccess::None => 0,
            HostAccess::Ro => 1,
            HostAccess::Wo => 2,
            HostAccess::Rw => 3,
        };
        EntryFlags(NmtStates::ALL.bits() as u16 | storage << Self::STORAGE_SHIFT | host << Self::HOST_SHIFT)
    }

    pub const fn pdo_mappable(self) -> EntryFlags {
        EntryFlags(self.0 | Self::PDO_MAPPABLE)
    }

    pub const fn host_write_before_can_enabled(self) -> EntryFlags {
        EntryFlags(self.0 | Self::HOST_WRITE_BEFORE_CAN_ENABLED)
    }

    /// Bus writes only in `states`.
    pub const fn writable_in(self, states: NmtStates) -> EntryFlags {
        EntryFlags(self.0 & !(NmtStates::ALL.bits() as u16) | states.bits() as u16)
    }

    /// The run also describes the `copies` objects after its own (at most 31).
    pub const fn copies(self, copies: u8) -> EntryFlags {
        EntryFlags(self.0 & !(0x1F << Self::COPIES_SHIFT) | ((copies & 0x1F) as u16) << Self::COPIES_SHIFT)
    }
}

/// How much of a value a read copied, and how long the value is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReadLen {
    pub copied: usize,
    pub total: usize,
}

impl EntryInfo {
    pub const fn data_type(&self) -> DataType {
        use DataType::*;
        // The enum's own order, so the compiler reduces this to the byte itself.
        match self.kind.0 & 0x1F {
            0 => Boolean,
            1 => Integer8,
            2 => Integer16,
            3 => Integer24,
            4 => Integer32,
            5 => Integer40,
            6 => Integer48,
            7 => Integer56,
            8 => Integer64,
            9 => Unsigned8,
            10 => Unsigned16,
            11 => Unsigned24,
            12 => Unsigned32,
            13 => Unsigned40,
            14 => Unsigned48,
            15 => Unsigned56,
            16 => Unsigned64,
            17 => Real32,
            18 => Real64,
            19 => VisibleString,
            20 => OctetString,
            21 => UnicodeString,
            22 => TimeOfDay,
            23 => TimeDifference,
            _ => Domain,
        }
    }

    /// CAN-side access.
    pub const fn access(&self) -> Access {
        match self.kind.0 >> 5 {
            0 => Access::Ro,
            1 => Access::Wo,
            2 => Access::Rw,
            3 => Access::Rwr,
            4 => Access::Rww,
            5 => Access::Const,
            _ => Access::None,
        }
    }

    /// Serial-host access.
    pub const fn host_access(&self) -> HostAccess {
        match (self.flags.0 >> EntryFlags::HOST_SHIFT) & 3 {
            0 => HostAccess::None,
            1 => HostAccess::Ro,
            2 => HostAccess::Wo,
            _ => HostAccess::Rw,
        }
    }

    pub const fn storage(&self) -> Storage {
        match (self.flags.0 >> EntryFlags::STORAGE_SHIFT) & 3 {
            0 => Storage::Ram,
            1 => Storage::Persistent,
            _ => Storage::App,
        }
    }

    pub const fn pdo_mappable(&self) -> bool {
        self.flags.0 & EntryFlags::PDO_MAPPABLE != 0
    }

    /// Host writes are accepted only until the CANopen interface is enabled.
    pub const fn host_write_before_can_enabled(&self) -> bool {
        self.flags.0 & EntryFlags::HOST_WRITE_BEFORE_CAN_ENABLED != 0
    }

    /// NMT states in which a bus write is accepted.
    pub const fn writable_in(&self) -> NmtStates {
        NmtStates::from_bits(self.flags.0 as u8)
    }

    /// How many further objects, `index + 1 ..= index + copies`, this run also describes:
    /// objects that repeat alike (CO401Memory1's 64 memory blocks) share their runs. Only
    /// app-backed objects repeat, so the field dispatch never sees a copy. At most
    /// [`MAX_COPIES`](crate::pdo::mapping::MAX_COPIES).
    pub const fn copies(&self) -> u8 {
        (self.flags.0 >> EntryFlags::COPIES_SHIFT) as u8 & 0x1F
    }

    /// The entry's value limits in `table`, the dictionary's limits table.
    pub fn limits_in(&self, table: &'static [Limits]) -> Option<&'static Limits> {
        table.get(usize::from(self.limits).checked_sub(1)?)
    }

    /// Whether `side` may read this entry, with the abort code if not.
    pub fn check_read(&self, side: Side) -> Result<(), SdoAbort> {
        match side {
            Side::Device => Ok(()),
            Side::Bus if self.access() == Access::None => Err(SdoAbort::NoObject),
            Side::Bus if !self.access().readable() => Err(SdoAbort::WriteOnly),
            Side::Host if self.host_access() == HostAccess::None => Err(SdoAbort::UnsupportedAccess),
            Side::Host if !self.host_access().readable() => Err(SdoAbort::WriteOnly),
            Side::Bus | Side::Host => Ok(()),
        }
    }

    /// Whether `side` may write `data` to this entry: access, state, length and value
    /// (`limits`: the dictionary's limits table).
    pub fn check_write(&self, side: Side, ctx: &AccessContext, data: &[u8], limits: &'static [Limits]) -> Result<(), SdoAbort> {
        self.check_write_access(side, ctx)?;
        self.check_data(data, limits)
    }

    /// Whether `data` fits this entry: length and value, whoever writes it (`limits`: the
    /// dictionary's limits table).
    #[inline]
    pub fn check_data(&self, data: &[u8], limits: &'static [Limits]) -> Result<(), SdoAbort> {
        // The common case inline (every RPDO entry): full length, no limits, not a BOOLEAN.
        if data.len() == usize::from(self.size) && self.limits == 0 && self.data_type() != DataType::Boolean {
            return Ok(());
        }
        self.check_length_and_value(data, limits)
    }

    fn check_length_and_value(&self, data: &[u8], limits: &'static [Limits]) -> Result<(), SdoAbort> {
        self.check_length(data.len())?;
        self.check_value(data, self.limits_in(limits))
    }

    /// Whether `side` may write this entry now, whatever the value: access and state.
    pub fn check_write_access(&self, side: Side, ctx: &AccessContext) -> Result<(), SdoAbort> {
        match side {
            Side::Device => {}
            Side::Bus => {
                if self.access() == Access::None {
                    return Err(SdoAbort::NoObject);
                }
                if !self.access().writable() {
                    return Err(SdoAbort::ReadOnly);
                }
                if !self.writable_in().contains(ctx.nmt) {
                    return Err(SdoAbort::DataTransferState);
                }
            }
            Side::Host => {
                if !self.host_access().writable() {
                    return Err(if self.host_access() == HostAccess::None { SdoAbort::UnsupportedAccess } else { SdoAbort::ReadOnly });
                }
                if self.host_write_before_can_enabled() && ctx.can_enabled {
                    return Err(SdoAbort::DataTransferState);
                }
            }
        }
        Ok(())
    }

    /// Whether this description covers `sub`.
    pub fn covers(&self, sub: u8) -> bool {
        (self.sub..=self.last_sub).contains(&sub)
    }

    /// Whether this run describes object `index` (its own, or one of its copies).
    pub fn covers_index(&self, index: u16) -> bool {
        index >= self.index && index - self.index <= u16::from(self.copies())
    }

    /// Strings and domains: a value shorter than `size` is whole.
    pub const fn is_variable_length(&self) -> bool {
        matches!(self.data_type(), DataType::VisibleString | DataType::OctetString | DataType::UnicodeString | DataType::Domain)
    }

    /// Whether a value of `len` bytes has this entry's length: its size, or up to it for
    /// strings and domains (what an SDO write, a PDO mapping and a loaded file must give).
    pub const fn takes_len(&self, len: usize) -> bool {
        let size = self.size as usize;
        len == size || (len < size && self.is_variable_length())
    }

    fn check_length(&self, len: usize) -> Result<(), SdoAbort> {
        let size = usize::from(self.size);
        if len > size {
            Err(SdoAbort::LengthTooHigh)
        } else if len < size && !self.is_variable_length() {
            Err(SdoAbort::LengthTooLow)
        } else {
            Ok(())
        }
    }

    fn check_value(&self, data: &[u8], limits: Option<&Limits>) -> Result<(), SdoAbort> {
        // Fast path for the common entry without limits: a value of the right length always
        // fits its integer type, except a BOOLEAN byte holding 2..255.
        let Some(limits) = limits else {
            return match (self.data_type(), data) {
                (DataType::Boolean, [b]) if *b > 1 => Err(SdoAbort::ValueTooHigh),
                _ => Ok(()),
            };
        };
        let Some(value) = Int::decode(self.data_type(), data) else { return Ok(()) };
        // Only BOOLEAN can carry bits its type does not allow (a byte holding 2..255): a value
        // of any other integer type fits it once its length is right.
        if self.data_type() == DataType::Boolean && value.above(1) {
            return Err(SdoAbort::ValueTooHigh);
        }
        if !limits.values.is_empty() && !limits.values.iter().any(|&v| value.is(v)) {
            return Err(SdoAbort::InvalidValue);
        }
        if limits.low.is_some_and(|low| value.below(low)) {
            return Err(SdoAbort::ValueTooLow);
        }
        if limits.high.is_some_and(|high| value.above(high)) {
            return Err(SdoAbort::ValueTooHigh);
        }
        Ok(())
    }
}

/// The unsigned value of up to 8 little-endian bytes; `None` for more. Through a fixed
/// 8-byte buffer rather than a fold over the slice: Kani (CBMC) cannot bound a loop over a
/// slice whose length is symbolic, such as data for an entry chosen by a symbolic index.
pub(crate) fn le_u64(data: &[u8]) -> Option<u64> {
    let mut bytes = [0; 8];
    bytes.get_mut(..data.len())?.copy_from_slice(data);
    Some(u64::from_le_bytes(bytes))
}

/// The value of a little-endian integer entry, as its type's signedness says: compared with
/// the `i64` limits without 128-bit arithmetic, which is costly on a Cortex-M0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Int {
    Signed(i64),
    /// Unsigned types and BOOLEAN (0/1).
    Unsigned(u64),
}

impl Int {
    /// The value of `data` as `data_type`; `None` for other types or a length that does not
    /// match the type.
    pub(crate) fn decode(data_type: DataType, data: &[u8]) -> Option<Int> {
        use DataType::*;
        let signed = match data_type {
            Integer8 | Integer16 | Integer24 | Integer32 | Integer40 | Integer48 | Integer56 | Integer64 => true,
            Boolean | Unsigned8 | Unsigned16 | Unsigned24 | Unsigned32 | Unsigned40 | Unsigned48 | Unsigned56 | Unsigned64 => false,
            _ => return None,
        };
        let bits = data_type.bits()?;
        let bytes = usize::try_from(bits.div_ceil(8)).ok()?;
        if data.len() != bytes {
            return None;
        }
        let raw = le_u64(data)?;
        // Signed types: sign-extend from the type's width by shifting its sign bit to bit 63.
        let unused = 64 - bits;
        Some(if signed { Int::Signed(((raw << unused) as i64) >> unused) } else { Int::Unsigned(raw) })
    }

    /// Whether the value is `v`.
    pub(crate) fn is(self, v: i64) -> bool {
        match self {
            Int::Signed(x) => x == v,
            Int::Unsigned(x) => u64::try_from(v).is_ok_and(|v| x == v),
        }
    }

    /// Whether the value is below `low`.
    fn below(self, low: i64) -> bool {
        match self {
            Int::Signed(x) => x < low,
            Int::Unsigned(x) => u64::try_from(low).is_ok_and(|low| x < low),
        }
    }

    /// Whether the value is above `high`.
    fn above(self, high: i64) -> bool {
        match self {
            Int::Signed(x) => x > high,
            Int::Unsigned(x) => u64::try_from(high).map_or(true, |high| x > high),
        }
    }
}

/// The value of a little-endian integer entry (BOOLEAN counts as 0/1); `None` for other types
/// or a length that does not match the type.
pub fn decode_int(data_type: DataType, data: &[u8]) -> Option<i128> {
    Int::decode(data_type, data).map(|v| match v {
        Int::Signed(v) => i128::from(v),
        Int::Unsigned(v) => i128::from(v),
    })
}

/// An entry at 2000h.0 with no limits, for unit tests.
#[cfg(test)]
pub(crate) const fn test_entry(data_type: DataType, access: Access, host_access: HostAccess, size: u16) -> EntryInfo {
    EntryInfo {
        index: 0x2000,
        offset: 0,
        size,
        sub: 0,
        last_sub: 0,
        limits: 0,
        kind: EntryKind::new(data_type, access),
        flags: EntryFlags::new(host_access, Storage::Ram),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coforge_types::NmtState;

    /// The limits table of these tests' entries: `limits: n` is entry `n - 1`.
    static LIMITS: [Limits; 3] = [
        Limits { low: Some(1), high: Some(127), values: &[] },
        Limits { low: None, high: None, values: &[1, 2, 3, 0x10] },
        Limits { low: Some(-100), high: Some(100), values: &[] },
    ];
    const NODE_ID: u8 = 1;
    const MODES: u8 = 2;
    const SIGNED: u8 = 3;

    /// An entry under test, checked against [`LIMITS`] as a dictionary checks against its own.
    struct Entry(EntryInfo);

    impl core::ops::Deref for Entry {
        type Target = EntryInfo;
        fn deref(&self) -> &EntryInfo {
            &self.0
        }
    }

    impl Entry {
        fn check_write(&self, side: Side, ctx: &AccessContext, data: &[u8]) -> Result<(), SdoAbort> {
            self.0.check_write(side, ctx, data, &LIMITS)
        }
    }

    const fn info(data_type: DataType, access: Access, host_access: HostAccess, size: u16) -> Entry {
        Entry(test_entry(data_type, access, host_access, size))
    }

    const OP: AccessContext = AccessContext { nmt: NmtState::Operational, can_enabled: true };
    const PREOP: AccessContext = AccessContext { nmt: NmtState::PreOperational, can_enabled: false };

    #[test]
    fn access_differs_by_side() {
        // CO401GW1 2E00: read-only from CAN, writable by the host.
        let e = info(DataType::Unsigned8, Access::Ro, HostAccess::Rw, 1);
        assert_eq!(e.check_write(Side::Bus, &OP, &[1]), Err(SdoAbort::ReadOnly));
        assert_eq!(e.check_write(Side::Host, &OP, &[1]), Ok(()));
        assert_eq!(e.check_write(Side::Device, &OP, &[1]), Ok(()));
        // A write-only CAN entry (CO401Memory1 5E00): readable by the host only.
        let m = info(DataType::Unsigned8, Access::Wo, HostAccess::Ro, 1);
        assert_eq!(m.check_read(Side::Bus), Err(SdoAbort::WriteOnly));
        assert_eq!(m.check_read(Side::Host), Ok(()));
        assert_eq!(m.check_write(Side::Host, &OP, &[1]), Err(SdoAbort::ReadOnly));
        // Not reachable from CAN at all (CO401GW1 100B).
        let n = Entry(EntryInfo {
            flags: EntryFlags::new(HostAccess::Rw, Storage::Ram).host_write_before_can_enabled(),
            ..info(DataType::Unsigned8, Access::None, HostAccess::Rw, 1).0
        });
        assert_eq!(n.check_read(Side::Bus), Err(SdoAbort::NoObject));
        assert_eq!(n.check_write(Side::Bus, &PREOP, &[5]), Err(SdoAbort::NoObject));
        assert_eq!(n.check_write(Side::Host, &PREOP, &[5]), Ok(()));
        assert_eq!(n.check_write(Side::Host, &OP, &[5]), Err(SdoAbort::DataTransferState), "only before the CAN interface is enabled");
        let h = info(DataType::Unsigned8, Access::Rw, HostAccess::None, 1);
        assert_eq!(h.check_read(Side::Host), Err(SdoAbort::UnsupportedAccess));
    }

    #[test]
    fn writes_restricted_to_nmt_states() {
        let writable_in = NmtStates::NONE.with(NmtState::PreOperational);
        let e = Entry(EntryInfo {
            flags: EntryFlags::new(HostAccess::None, Storage::Ram).writable_in(writable_in),
            ..info(DataType::Unsigned32, Access::Rw, HostAccess::None, 4).0
        });
        assert_eq!(e.check_write(Side::Bus, &PREOP, &[0; 4]), Ok(()));
        assert_eq!(e.check_write(Side::Bus, &OP, &[0; 4]), Err(SdoAbort::DataTransferState));
    }

    #[test]
    fn lengths_and_values_are_checked() {
        let e = Entry(EntryInfo { limits: NODE_ID, ..info(DataType::Unsigned8, Access::Rw, HostAccess::None, 1).0 });
        assert_eq!(e.check_write(Side::Bus, &OP, &[]), Err(SdoAbort::LengthTooLow));
        assert_eq!(e.check_write(Side::Bus, &OP, &[1, 2]), Err(SdoAbort::LengthTooHigh));
        assert_eq!(e.check_write(Side::Bus, &OP, &[0]), Err(SdoAbort::ValueTooLow));
        assert_eq!(e.check_write(Side::Bus, &OP, &[128]), Err(SdoAbort::ValueTooHigh));
        assert_eq!(e.check_write(Side::Device, &OP, &[128]), Err(SdoAbort::ValueTooHigh), "limits bind the device too");
        let v = Entry(EntryInfo { limits: MODES, ..info(DataType::Unsigned8, Access::Rw, HostAccess::None, 1).0 });
        assert_eq!(v.check_write(Side::Bus, &OP, &[0x10]), Ok(()));
        assert_eq!(v.check_write(Side::Bus, &OP, &[4]), Err(SdoAbort::InvalidValue));
        let b = info(DataType::Boolean, Access::Rw, HostAccess::None, 1);
        assert_eq!(b.check_write(Side::Bus, &OP, &[1]), Ok(()));
        assert_eq!(b.check_write(Side::Bus, &OP, &[2]), Err(SdoAbort::ValueTooHigh));
        let s = info(DataType::VisibleString, Access::Rw, HostAccess::None, 8);
        assert_eq!(s.check_write(Side::Bus, &OP, b"Datei1"), Ok(()), "strings may be shorter than their maximum");
        assert_eq!(s.check_write(Side::Bus, &OP, b"123456789"), Err(SdoAbort::LengthTooHigh));
        let i = Entry(EntryInfo { limits: SIGNED, ..info(DataType::Integer16, Access::Rw, HostAccess::None, 2).0 });
        assert_eq!(i.check_write(Side::Bus, &OP, &(-100_i16).to_le_bytes()), Ok(()));
        assert_eq!(i.check_write(Side::Bus, &OP, &(-101_i16).to_le_bytes()), Err(SdoAbort::ValueTooLow));
    }

    #[test]
    fn integers_decode_little_endian_with_sign() {
        assert_eq!(decode_int(DataType::Unsigned16, &[0x34, 0x12]), Some(0x1234));
        assert_eq!(decode_int(DataType::Integer8, &[0xFF]), Some(-1));
        assert_eq!(decode_int(DataType::Integer24, &[0x00, 0x00, 0x80]), Some(-0x80_0000));
        assert_eq!(decode_int(DataType::Unsigned64, &[0xFF; 8]), Some(i128::from(u64::MAX)));
        assert_eq!(decode_int(DataType::Integer64, &[0xFF; 8]), Some(-1));
        assert_eq!(decode_int(DataType::Unsigned32, &[1, 2]), None);
        assert_eq!(decode_int(DataType::VisibleString, b"x"), None);
    }

    #[test]
    fn comparisons_without_128_bits_agree_with_the_exact_ones() {
        let limits = [i64::MIN, i64::MIN + 1, -0x8000_0001, -129, -128, -1, 0, 1, 2, 127, 128, 255, 0xFFFF_FFFF, i64::MAX - 1, i64::MAX];
        let mut x = 7_u64;
        for t in DataType::ALL {
            let Some(bits) = t.bits() else { continue };
            let len = bits.div_ceil(8) as usize;
            for n in 0..2000 {
                // Edge patterns first (all zero, all ones, sign bit only), then a fixed LCG.
                x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
                let raw = match n {
                    0 => 0,
                    1 => u64::MAX,
                    2 => 1 << (len * 8 - 1),
                    3 => (1 << (len * 8 - 1)) - 1,
                    _ => x,
                };
                let data = &raw.to_le_bytes()[..len];
                let (Some(value), Some(exact)) = (Int::decode(t, data), decode_int(t, data)) else {
                    assert_eq!(Int::decode(t, data).is_some(), decode_int(t, data).is_some(), "{t}");
                    continue;
                };
                for l in limits {
                    assert_eq!(value.is(l), exact == i128::from(l), "{t} {exact} == {l}");
                    assert_eq!(value.below(l), exact < i128::from(l), "{t} {exact} < {l}");
                    assert_eq!(value.above(l), exact > i128::from(l), "{t} {exact} > {l}");
                }
            }
        }
    }

    #[test]
    fn packed_properties_read_back_as_built() {
        let accesses = [Access::Ro, Access::Wo, Access::Rw, Access::Rwr, Access::Rww, Access::Const, Access::None];
        for (data_type, access) in DataType::ALL.into_iter().flat_map(|t| accesses.map(|a| (t, a))) {
            let e = EntryInfo { kind: EntryKind::new(data_type, access), ..test_entry(DataType::Boolean, Access::Ro, HostAccess::None, 1) };
            assert_eq!((e.data_type(), e.access()), (data_type, access));
        }
        let states = [NmtStates::NONE, NmtStates::ALL, NmtStates::NONE.with(NmtState::PreOperational), NmtStates::NONE.with(NmtState::Stopped)];
        for host in [HostAccess::None, HostAccess::Ro, HostAccess::Wo, HostAccess::Rw] {
            for storage in [Storage::Ram, Storage::Persistent, Storage::App] {
                for (pdo, before, writable_in, copies) in (0..32_u8).flat_map(|c| states.map(|s| (c % 2 == 0, c % 3 == 0, s, c))) {
                    let mut flags = EntryFlags::new(host, storage).writable_in(writable_in).copies(copies);
                    if pdo {
                        flags = flags.pdo_mappable();
                    }
                    if before {
                        flags = flags.host_write_before_can_enabled();
                    }
                    let e = EntryInfo { flags, ..test_entry(DataType::Boolean, Access::Ro, HostAccess::None, 1) };
                    assert_eq!((e.host_access(), e.storage(), e.pdo_mappable(), e.host_write_before_can_enabled()), (host, storage, pdo, before));
                    assert_eq!((e.writable_in(), e.copies()), (writable_in, copies));
                }
            }
        }
        assert_eq!(test_entry(DataType::Boolean, Access::Ro, HostAccess::None, 1).writable_in(), NmtStates::ALL, "writable in every state by default");
    }

    #[test]
    fn entry_info_is_small_enough_for_flash_tables() {
        // Most of a dictionary's flash is this table: 12 bytes per run on any target (was 20
        // on Cortex-M), the small properties packed and the limits an index into the
        // dictionary's table.
        let most = 12;
        assert!(core::mem::size_of::<EntryInfo>() <= most, "{}", core::mem::size_of::<EntryInfo>());
    }
}
