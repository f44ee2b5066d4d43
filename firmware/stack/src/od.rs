//! Object dictionary interface: entry metadata, access checks per side, SDO abort codes.
//!
//! Generated code keeps the data in typed fields and dispatches with a `match`; everything
//! that decides *whether* an access is allowed lives here, once, so every device and both
//! sides (bus and host) refuse the same things with the same CiA 301 abort code.

pub use coforge_types::{Access, DataType, HostAccess, NmtState, Storage};

use crate::value::OdValue;

/// CiA 301 SDO abort codes (table 22).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum SdoAbort {
    ToggleBit = 0x0503_0000,
    Timeout = 0x0504_0000,
    UnknownCommand = 0x0504_0001,
    InvalidBlockSize = 0x0504_0002,
    InvalidSequence = 0x0504_0003,
    BlockCrc = 0x0504_0004,
    OutOfMemory = 0x0504_0005,
    UnsupportedAccess = 0x0601_0000,
    WriteOnly = 0x0601_0001,
    ReadOnly = 0x0601_0002,
    NoObject = 0x0602_0000,
    NotMappable = 0x0604_0041,
    PdoTooLong = 0x0604_0042,
    IncompatibleParameter = 0x0604_0043,
    IncompatibleInternal = 0x0604_0047,
    Hardware = 0x0606_0000,
    LengthMismatch = 0x0607_0010,
    LengthTooHigh = 0x0607_0012,
    LengthTooLow = 0x0607_0013,
    NoSubIndex = 0x0609_0011,
    InvalidValue = 0x0609_0030,
    ValueTooHigh = 0x0609_0031,
    ValueTooLow = 0x0609_0032,
    MaxBelowMin = 0x0609_0036,
    NoResource = 0x060A_0023,
    General = 0x0800_0000,
    DataTransfer = 0x0800_0020,
    DataTransferLocal = 0x0800_0021,
    DataTransferState = 0x0800_0022,
    NoDictionary = 0x0800_0023,
    NoData = 0x0800_0024,
}

impl SdoAbort {
    pub const ALL: [SdoAbort; 31] = [
        SdoAbort::ToggleBit,
        SdoAbort::Timeout,
        SdoAbort::UnknownCommand,
        SdoAbort::InvalidBlockSize,
        SdoAbort::InvalidSequence,
        SdoAbort::BlockCrc,
        SdoAbort::OutOfMemory,
        SdoAbort::UnsupportedAccess,
        SdoAbort::WriteOnly,
        SdoAbort::ReadOnly,
        SdoAbort::NoObject,
        SdoAbort::NotMappable,
        SdoAbort::PdoTooLong,
        SdoAbort::IncompatibleParameter,
        SdoAbort::IncompatibleInternal,
        SdoAbort::Hardware,
        SdoAbort::LengthMismatch,
        SdoAbort::LengthTooHigh,
        SdoAbort::LengthTooLow,
        SdoAbort::NoSubIndex,
        SdoAbort::InvalidValue,
        SdoAbort::ValueTooHigh,
        SdoAbort::ValueTooLow,
        SdoAbort::MaxBelowMin,
        SdoAbort::NoResource,
        SdoAbort::General,
        SdoAbort::DataTransfer,
        SdoAbort::DataTransferLocal,
        SdoAbort::DataTransferState,
        SdoAbort::NoDictionary,
        SdoAbort::NoData,
    ];

    /// The 32-bit code sent in an SDO abort frame.
    pub const fn code(self) -> u32 {
        self as u32
    }

    pub fn from_code(code: u32) -> Option<SdoAbort> {
        SdoAbort::ALL.into_iter().find(|a| a.code() == code)
    }
}

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
}

/// What a write is judged against besides the entry itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AccessContext {
    pub nmt: NmtState,
    /// The host has enabled the CANopen interface (CO401GW1's command 0x02).
    pub can_enabled: bool,
}

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
/// table stays small in flash.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EntryInfo {
    pub index: u16,
    /// The number of the object in the generated dictionary, dense from 0 and the same in
    /// every mode: what its field dispatch switches on, so the switch is a jump table.
    pub object: u16,
    /// First sub-index this description covers.
    pub sub: u8,
    /// Last sub-index this description covers (equal to `sub` for a single entry).
    pub last_sub: u8,
    /// How many further objects, `index + 1 ..= index + copies`, this run also describes:
    /// objects that repeat alike (CO401Memory1's 64 memory blocks) share their runs. Only
    /// app-backed objects repeat, so the field dispatch never sees a copy. At most
    /// [`MAX_COPIES`](crate::pdo::mapping::MAX_COPIES).
    pub copies: u8,
    pub data_type: DataType,
    /// CAN-side access.
    pub access: Access,
    /// Serial-host access.
    pub host_access: HostAccess,
    /// Host writes are accepted only until the CANopen interface is enabled.
    pub host_write_before_can_enabled: bool,
    pub pdo_mappable: bool,
    pub storage: Storage,
    /// NMT states in which a bus write is accepted.
    pub writable_in: NmtStates,
    /// Size in bytes; for strings and domains the maximum.
    pub size: u16,
    pub limits: Option<&'static Limits>,
}

/// How much of a value a read copied, and how long the value is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReadLen {
    pub copied: usize,
    pub total: usize,
}

impl EntryInfo {
    /// Whether `side` may read this entry, with the abort code if not.
    pub fn check_read(&self, side: Side) -> Result<(), SdoAbort> {
        match side {
            Side::Device => Ok(()),
            Side::Bus if self.access == Access::None => Err(SdoAbort::NoObject),
            Side::Bus if !self.access.readable() => Err(SdoAbort::WriteOnly),
            Side::Host if self.host_access == HostAccess::None => Err(SdoAbort::UnsupportedAccess),
            Side::Host if !self.host_access.readable() => Err(SdoAbort::WriteOnly),
            Side::Bus | Side::Host => Ok(()),
        }
    }

    /// Whether `side` may write `data` to this entry: access, state, length and value.
    pub fn check_write(&self, side: Side, ctx: &AccessContext, data: &[u8]) -> Result<(), SdoAbort> {
        self.check_write_access(side, ctx)?;
        self.check_data(data)
    }

    /// Whether `data` fits this entry: length and value, whoever writes it.
    pub fn check_data(&self, data: &[u8]) -> Result<(), SdoAbort> {
        // The common case first: full length, no limits, not a BOOLEAN.
        if data.len() == usize::from(self.size) && self.limits.is_none() && self.data_type != DataType::Boolean {
            return Ok(());
        }
        self.check_length(data.len())?;
        self.check_value(data)
    }

    /// Whether `side` may write this entry now, whatever the value: access and state.
    pub fn check_write_access(&self, side: Side, ctx: &AccessContext) -> Result<(), SdoAbort> {
        match side {
            Side::Device => {}
            Side::Bus => {
                if self.access == Access::None {
                    return Err(SdoAbort::NoObject);
                }
                if !self.access.writable() {
                    return Err(SdoAbort::ReadOnly);
                }
                if !self.writable_in.contains(ctx.nmt) {
                    return Err(SdoAbort::DataTransferState);
                }
            }
            Side::Host => {
                if !self.host_access.writable() {
                    return Err(if self.host_access == HostAccess::None { SdoAbort::UnsupportedAccess } else { SdoAbort::ReadOnly });
                }
                if self.host_write_before_can_enabled && ctx.can_enabled {
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
        index >= self.index && index - self.index <= u16::from(self.copies)
    }

    fn check_length(&self, len: usize) -> Result<(), SdoAbort> {
        let size = usize::from(self.size);
        let variable = matches!(self.data_type, DataType::VisibleString | DataType::OctetString | DataType::UnicodeString | DataType::Domain);
        if len > size {
            Err(SdoAbort::LengthTooHigh)
        } else if len < size && !variable {
            Err(SdoAbort::LengthTooLow)
        } else {
            Ok(())
        }
    }

    fn check_value(&self, data: &[u8]) -> Result<(), SdoAbort> {
        // Fast path for the common entry without limits: a value of the right length always
        // fits its integer type, except a BOOLEAN byte holding 2..255.
        if self.limits.is_none() {
            return match (self.data_type, data) {
                (DataType::Boolean, [b]) if *b > 1 => Err(SdoAbort::ValueTooHigh),
                _ => Ok(()),
            };
        }
        let Some(value) = decode_int(self.data_type, data) else { return Ok(()) };
        // Only BOOLEAN can carry bits its type does not allow (a byte holding 2..255).
        if self.data_type.int_range().is_some_and(|(_, hi)| value > hi) {
            return Err(SdoAbort::ValueTooHigh);
        }
        let Some(limits) = self.limits else { return Ok(()) };
        if !limits.values.is_empty() && !limits.values.iter().any(|&v| i128::from(v) == value) {
            return Err(SdoAbort::InvalidValue);
        }
        if limits.low.is_some_and(|low| value < i128::from(low)) {
            return Err(SdoAbort::ValueTooLow);
        }
        if limits.high.is_some_and(|high| value > i128::from(high)) {
            return Err(SdoAbort::ValueTooHigh);
        }
        Ok(())
    }
}

/// The value of a little-endian integer entry (BOOLEAN counts as 0/1); `None` for other types
/// or a length that does not match the type.
pub fn decode_int(data_type: DataType, data: &[u8]) -> Option<i128> {
    let (lo, _) = data_type.int_range()?;
    let bits = data_type.bits()?;
    let bytes = usize::try_from(bits.div_ceil(8)).ok()?;
    if data.len() != bytes {
        return None;
    }
    // At most 64 bits: assembled in a u64, widened once (128-bit shifts are costly on a
    // Cortex-M0).
    let raw = data.iter().rev().fold(0_u64, |acc, &b| acc << 8 | u64::from(b));
    // Signed types: sign-extend from the type's width by shifting its sign bit to bit 63.
    let unused = 64 - bits;
    if lo < 0 { Some(i128::from(((raw << unused) as i64) >> unused)) } else { Some(i128::from(raw)) }
}

/// Copies `value[offset..]` into `buf` (segmented and partial reads).
pub fn read_slice(value: &[u8], offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
    let rest = value.get(offset..).ok_or(SdoAbort::LengthTooHigh)?;
    let n = rest.len().min(buf.len());
    if let (Some(dst), Some(src)) = (buf.get_mut(..n), rest.get(..n)) {
        dst.copy_from_slice(src);
    }
    Ok(ReadLen { copied: n, total: value.len() })
}

/// Finds the description of `index`/`sub` in a table sorted by `(index, sub)` whose runs do
/// not overlap (the runs of repeated objects are listed once, under the first index):
/// `NoObject` if the index is absent, `NoSubIndex` if only the sub-index is.
pub fn find(entries: &[EntryInfo], index: u16, sub: u8) -> Result<&EntryInfo, SdoAbort> {
    find_run(entries, index, sub).and_then(|run| entries.get(run).ok_or(SdoAbort::NoObject))
}

/// Like [`find`], but the position of the run in the table (PDO mappings keep it).
pub fn find_run(entries: &[EntryInfo], index: u16, sub: u8) -> Result<usize, SdoAbort> {
    // The object: the last run listed at or before `index` must describe it.
    let listed = entries.partition_point(|e| e.index <= index);
    let last = listed.checked_sub(1).ok_or(SdoAbort::NoObject)?;
    let first = match entries.get(last) {
        Some(e) if e.covers_index(index) => e.index,
        _ => return Err(SdoAbort::NoObject),
    };
    // The sub-index: the object's runs end at `last` and are few, so a scan back is quicker
    // than a second search.
    let runs = entries.get(..listed).unwrap_or_default().iter().enumerate().rev().take_while(|(_, e)| e.index == first);
    runs.filter(|(_, e)| e.covers(sub)).map(|(i, _)| i).next().ok_or(SdoAbort::NoSubIndex)
}

/// The dictionary of one device: implemented by the code `device!` generates.
///
/// The generated code provides the table and the field of each stored entry (`field`);
/// reads, writes, lookups and access checks are the provided methods, so every device
/// refuses the same accesses with the same codes and the dispatch code exists once.
pub trait ObjectDictionary {
    /// Where app-backed entries (`storage: app`) are read and written.
    type App: AppObjects;

    /// Every entry description, sorted by index and sub-index (see [`find`]).
    fn entries(&self) -> &'static [EntryInfo];

    /// The field that stores `sub` of the entry `info` describes, `info` being the run
    /// [`find_run`] gave for it (so `info.covers(sub)`; single-entry objects do not look at
    /// `sub` again); `None` for an entry the dictionary does not store (app-backed ones).
    fn field(&mut self, info: &EntryInfo, sub: u8) -> Option<&mut dyn OdValue>;

    /// The device's app-backed objects.
    fn app(&mut self) -> &mut Self::App;

    /// Reads the value of `index`/`sub`, which `info` describes, from byte `offset` into
    /// `buf`: no lookup and no access check (the caller made both).
    fn read_entry(&mut self, info: &EntryInfo, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        if info.storage == Storage::App {
            return self.app().read(info, index, sub, offset, buf);
        }
        self.field(info, sub).ok_or(SdoAbort::NoSubIndex)?.read(info, offset, buf)
    }

    /// Writes `data` (the whole value, little-endian) after its length and value checks; no
    /// lookup and no access check. A refused write leaves the stored value unchanged.
    fn write_entry(&mut self, info: &EntryInfo, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        info.check_data(data)?;
        if info.storage == Storage::App {
            return self.app().write(info, index, sub, data);
        }
        self.field(info, sub).ok_or(SdoAbort::NoSubIndex)?.write(info, data)
    }

    /// The entry's metadata, or `NoObject` / `NoSubIndex`.
    fn entry(&self, index: u16, sub: u8) -> Result<&'static EntryInfo, SdoAbort> {
        find(self.entries(), index, sub)
    }

    /// Reads the value from byte `offset` into `buf`, after the access check for `side`.
    fn read(&mut self, index: u16, sub: u8, offset: usize, buf: &mut [u8], side: Side) -> Result<ReadLen, SdoAbort> {
        let info = self.entry(index, sub)?;
        info.check_read(side)?;
        self.read_entry(info, index, sub, offset, buf)
    }

    /// Writes `data` after the checks for `side`: access, state, length and value.
    fn write(&mut self, index: u16, sub: u8, data: &[u8], side: Side, ctx: &AccessContext) -> Result<(), SdoAbort> {
        let info = self.entry(index, sub)?;
        info.check_write_access(side, ctx)?;
        self.write_entry(info, index, sub, data)
    }
}

/// A range of object indices: what 1010h/1011h sub-indices and NMT resets act on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Area {
    // Private: every area is one of the constants below, a union of whole index classes
    // (0000h..0FFFh, communication, manufacturer, application, A000h..FFFFh). Generated resets
    // test one index per run of a class and rely on that.
    first: u16,
    last: u16,
}

impl Area {
    pub const ALL: Area = Area { first: 0x0000, last: 0xFFFF };
    /// 1000h..1FFFh: what "reset communication" and 1010h sub 2 act on.
    pub const COMMUNICATION: Area = Area { first: 0x1000, last: 0x1FFF };
    /// 6000h..9FFFh (1010h sub 3).
    pub const APPLICATION: Area = Area { first: 0x6000, last: 0x9FFF };
    /// 2000h..5FFFh (1010h sub 4).
    pub const MANUFACTURER: Area = Area { first: 0x2000, last: 0x5FFF };

    pub const fn contains(self, index: u16) -> bool {
        self.first <= index && index <= self.last
    }

    /// The area a 1010h/1011h sub-index names (CiA 301 7.5.2.13).
    pub const fn of_store_sub(sub: u8) -> Option<Area> {
        match sub {
            1 => Some(Area::ALL),
            2 => Some(Area::COMMUNICATION),
            3 => Some(Area::APPLICATION),
            4 => Some(Area::MANUFACTURER),
            _ => None,
        }
    }
}

/// Optional communication objects whose services cost code: a dictionary without one (in
/// every mode) leaves that code out of the image, since the stack tests these constants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CommObjects {
    /// 1003h, the pre-defined error field (error history).
    pub error_history: bool,
    /// 1006h, the communication cycle period (SYNC timeout monitoring).
    pub sync_cycle: bool,
    /// 1016h, the consumer heartbeat times.
    pub heartbeat_consumer: bool,
}

impl CommObjects {
    /// Every service, as for a dictionary that has every object.
    pub const ALL: CommObjects = CommObjects { error_history: true, sync_cycle: true, heartbeat_consumer: true };
}

/// What a node needs from a generated dictionary besides reads and writes: the spec
/// defaults, the persistent block and the emergencies.
pub trait Dictionary: ObjectDictionary {
    /// Bytes of the persistent block (every `storage: persistent` entry, index order).
    const PERSISTENT_SIZE: usize;

    /// Whether the SDO server does block transfer (the spec's `sdo_block_transfer`).
    const SDO_BLOCK_TRANSFER: bool;

    /// The optional communication objects the dictionary has in any mode.
    const COMM: CommObjects;

    /// Hands the image of every persistent entry of `area` to `sink` with its offset in the
    /// block, so the block is written without a buffer of its size; `false` if `sink` failed.
    fn save_area(&self, area: Area, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool;

    /// Loads every persistent entry of `area` from `source` (offset, buffer to fill); an entry
    /// whose image `source` cannot give keeps its value, and the result is `false`.
    fn load_area(&mut self, area: Area, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool;

    /// Sets every stored entry (RAM and persistent) of `area` back to its spec default,
    /// `$NODEID` resolved for `node_id`. App-backed entries are the device's business.
    fn reset_area(&mut self, area: Area, node_id: u8);

    /// The spec's emergencies in the dictionary's mode.
    fn emergencies(&self) -> &'static [crate::emcy::EmcyDefault];
}

/// Objects whose data the device keeps outside the dictionary (EEPROM banks, a memory card):
/// the generated dictionary routes their reads and writes here, after its access checks.
/// `entry` may describe a run of sub-indices and of repeated objects; `index`/`sub` is the one
/// accessed.
pub trait AppObjects {
    fn read(&mut self, entry: &EntryInfo, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort>;
    fn write(&mut self, entry: &EntryInfo, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort>;
}

/// For devices without app-backed objects: nothing is routed here.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoAppObjects;

impl AppObjects for NoAppObjects {
    fn read(&mut self, _: &EntryInfo, _: u16, _: u8, _: usize, _: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        Err(SdoAbort::NoObject)
    }
    fn write(&mut self, _: &EntryInfo, _: u16, _: u8, _: &[u8]) -> Result<(), SdoAbort> {
        Err(SdoAbort::NoObject)
    }
}

/// An entry at 2000h.0 with no limits, for unit tests.
#[cfg(test)]
pub(crate) const fn test_entry(data_type: DataType, access: Access, host_access: HostAccess, size: u16) -> EntryInfo {
    EntryInfo {
        index: 0x2000,
        object: 0,
        sub: 0,
        last_sub: 0,
        copies: 0,
        data_type,
        access,
        host_access,
        host_write_before_can_enabled: false,
        pdo_mappable: false,
        storage: Storage::Ram,
        writable_in: NmtStates::ALL,
        size,
        limits: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const fn info(data_type: DataType, access: Access, host_access: HostAccess, size: u16) -> EntryInfo {
        test_entry(data_type, access, host_access, size)
    }

    const OP: AccessContext = AccessContext { nmt: NmtState::Operational, can_enabled: true };
    const PREOP: AccessContext = AccessContext { nmt: NmtState::PreOperational, can_enabled: false };

    #[test]
    fn abort_codes_are_the_cia_301_values() {
        assert_eq!(SdoAbort::WriteOnly.code(), 0x0601_0001);
        assert_eq!(SdoAbort::ReadOnly.code(), 0x0601_0002);
        assert_eq!(SdoAbort::NoObject.code(), 0x0602_0000);
        assert_eq!(SdoAbort::NoSubIndex.code(), 0x0609_0011);
        assert_eq!(SdoAbort::LengthMismatch.code(), 0x0607_0010);
        assert_eq!(SdoAbort::LengthTooHigh.code(), 0x0607_0012);
        assert_eq!(SdoAbort::LengthTooLow.code(), 0x0607_0013);
        assert_eq!(SdoAbort::InvalidValue.code(), 0x0609_0030);
        assert_eq!(SdoAbort::ValueTooHigh.code(), 0x0609_0031);
        assert_eq!(SdoAbort::ValueTooLow.code(), 0x0609_0032);
        assert_eq!(SdoAbort::NotMappable.code(), 0x0604_0041);
        assert_eq!(SdoAbort::DataTransfer.code(), 0x0800_0020);
        assert_eq!(SdoAbort::DataTransferState.code(), 0x0800_0022);
        for a in SdoAbort::ALL {
            assert_eq!(SdoAbort::from_code(a.code()), Some(a));
        }
        assert_eq!(SdoAbort::from_code(0x1234_5678), None);
    }

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
        let n = EntryInfo { host_write_before_can_enabled: true, ..info(DataType::Unsigned8, Access::None, HostAccess::Rw, 1) };
        assert_eq!(n.check_read(Side::Bus), Err(SdoAbort::NoObject));
        assert_eq!(n.check_write(Side::Bus, &PREOP, &[5]), Err(SdoAbort::NoObject));
        assert_eq!(n.check_write(Side::Host, &PREOP, &[5]), Ok(()));
        assert_eq!(n.check_write(Side::Host, &OP, &[5]), Err(SdoAbort::DataTransferState), "only before the CAN interface is enabled");
        let h = info(DataType::Unsigned8, Access::Rw, HostAccess::None, 1);
        assert_eq!(h.check_read(Side::Host), Err(SdoAbort::UnsupportedAccess));
    }

    #[test]
    fn writes_restricted_to_nmt_states() {
        let e = EntryInfo { writable_in: NmtStates::NONE.with(NmtState::PreOperational), ..info(DataType::Unsigned32, Access::Rw, HostAccess::None, 4) };
        assert_eq!(e.check_write(Side::Bus, &PREOP, &[0; 4]), Ok(()));
        assert_eq!(e.check_write(Side::Bus, &OP, &[0; 4]), Err(SdoAbort::DataTransferState));
    }

    #[test]
    fn lengths_and_values_are_checked() {
        static NODE_ID: Limits = Limits { low: Some(1), high: Some(127), values: &[] };
        let e = EntryInfo { limits: Some(&NODE_ID), ..info(DataType::Unsigned8, Access::Rw, HostAccess::None, 1) };
        assert_eq!(e.check_write(Side::Bus, &OP, &[]), Err(SdoAbort::LengthTooLow));
        assert_eq!(e.check_write(Side::Bus, &OP, &[1, 2]), Err(SdoAbort::LengthTooHigh));
        assert_eq!(e.check_write(Side::Bus, &OP, &[0]), Err(SdoAbort::ValueTooLow));
        assert_eq!(e.check_write(Side::Bus, &OP, &[128]), Err(SdoAbort::ValueTooHigh));
        assert_eq!(e.check_write(Side::Device, &OP, &[128]), Err(SdoAbort::ValueTooHigh), "limits bind the device too");
        static MODES: Limits = Limits { low: None, high: None, values: &[1, 2, 3, 0x10] };
        let v = EntryInfo { limits: Some(&MODES), ..info(DataType::Unsigned8, Access::Rw, HostAccess::None, 1) };
        assert_eq!(v.check_write(Side::Bus, &OP, &[0x10]), Ok(()));
        assert_eq!(v.check_write(Side::Bus, &OP, &[4]), Err(SdoAbort::InvalidValue));
        let b = info(DataType::Boolean, Access::Rw, HostAccess::None, 1);
        assert_eq!(b.check_write(Side::Bus, &OP, &[1]), Ok(()));
        assert_eq!(b.check_write(Side::Bus, &OP, &[2]), Err(SdoAbort::ValueTooHigh));
        let s = info(DataType::VisibleString, Access::Rw, HostAccess::None, 8);
        assert_eq!(s.check_write(Side::Bus, &OP, b"Datei1"), Ok(()), "strings may be shorter than their maximum");
        assert_eq!(s.check_write(Side::Bus, &OP, b"123456789"), Err(SdoAbort::LengthTooHigh));
        static SIGNED: Limits = Limits { low: Some(-100), high: Some(100), values: &[] };
        let i = EntryInfo { limits: Some(&SIGNED), ..info(DataType::Integer16, Access::Rw, HostAccess::None, 2) };
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
    fn find_distinguishes_missing_objects_from_missing_subs() {
        let at = |index, sub, last_sub| EntryInfo { index, sub, last_sub, ..info(DataType::Unsigned8, Access::Ro, HostAccess::Ro, 1) };
        // 1000; 1018 subs 0, 1, 4; a memory block 5000 with sub 0 and the run 1..=128.
        let table = [at(0x1000, 0, 0), at(0x1018, 0, 0), at(0x1018, 1, 1), at(0x1018, 4, 4), at(0x5000, 0, 0), at(0x5000, 1, 128)];
        assert_eq!(find(&table, 0x1018, 4).map(|e| e.sub), Ok(4));
        assert_eq!(find(&table, 0x1018, 2), Err(SdoAbort::NoSubIndex));
        assert_eq!(find(&table, 0x1018, 9), Err(SdoAbort::NoSubIndex));
        assert_eq!(find(&table, 0x5000, 77).map(|e| (e.sub, e.last_sub)), Ok((1, 128)));
        assert_eq!(find(&table, 0x5000, 128).map(|e| e.sub), Ok(1));
        assert_eq!(find(&table, 0x5000, 129), Err(SdoAbort::NoSubIndex));
        assert_eq!(find(&table, 0x1001, 0), Err(SdoAbort::NoObject));
        assert_eq!(find(&table, 0x0FFF, 0), Err(SdoAbort::NoObject));
        assert_eq!(find(&table, 0x6000, 0), Err(SdoAbort::NoObject));
        let no_sub0 = [at(0x6000, 1, 8)];
        assert_eq!(find(&no_sub0, 0x6000, 0), Err(SdoAbort::NoSubIndex));
        // Every sub-index of every present index resolves as the table says.
        for index in [0x1000_u16, 0x1018, 0x5000] {
            for sub in 0..=255_u8 {
                let want = table.iter().find(|e| e.index == index && e.covers(sub));
                assert_eq!(find(&table, index, sub).ok(), want, "{index:04X}.{sub}");
            }
        }
    }

    #[test]
    fn repeated_objects_resolve_through_their_first_index() {
        let at = |index, sub, last_sub, copies| EntryInfo { index, sub, last_sub, copies, ..info(DataType::Unsigned8, Access::Ro, HostAccess::Ro, 1) };
        // 5000..5003 alike (sub 0 and 1..=128), then 5C00 with subs 0..=2.
        let table = [at(0x1000, 0, 0, 0), at(0x5000, 0, 0, 3), at(0x5000, 1, 128, 3), at(0x5C00, 0, 2, 0)];
        for index in 0x5000..=0x5003 {
            assert_eq!(find_run(&table, index, 0), Ok(1), "{index:04X}.0");
            assert_eq!(find_run(&table, index, 1), Ok(2), "{index:04X}.1");
            assert_eq!(find_run(&table, index, 128), Ok(2), "{index:04X}.128");
            assert_eq!(find_run(&table, index, 129), Err(SdoAbort::NoSubIndex), "{index:04X}.129");
        }
        assert_eq!(find_run(&table, 0x5004, 0), Err(SdoAbort::NoObject));
        assert_eq!(find_run(&table, 0x4FFF, 0), Err(SdoAbort::NoObject));
        assert_eq!(find_run(&table, 0x5C00, 2), Ok(3));
        assert_eq!(find_run(&table, 0x5C00, 3), Err(SdoAbort::NoSubIndex));
        assert_eq!(find_run(&table, 0x5BFF, 0), Err(SdoAbort::NoObject));
        assert!(at(0x5000, 0, 0, 3).covers_index(0x5003) && !at(0x5000, 0, 0, 3).covers_index(0x5004));
        assert!(!at(0xFFFF, 0, 0, 0).covers_index(0xFFFE));
    }

    #[test]
    fn entry_info_is_small_enough_for_flash_tables() {
        // Most of a dictionary's flash is this table: 16 bytes and the limits pointer per run
        // (20 bytes on Cortex-M).
        let most = 16 + core::mem::size_of::<Option<&Limits>>();
        assert!(core::mem::size_of::<EntryInfo>() <= most, "{}", core::mem::size_of::<EntryInfo>());
    }

    #[test]
    fn partial_reads_copy_what_fits() {
        let mut buf = [0_u8; 4];
        assert_eq!(read_slice(b"CO401Memory1", 0, &mut buf), Ok(ReadLen { copied: 4, total: 12 }));
        assert_eq!(&buf, b"CO40");
        assert_eq!(read_slice(b"CO401Memory1", 8, &mut buf), Ok(ReadLen { copied: 4, total: 12 }));
        assert_eq!(&buf, b"ory1");
        assert_eq!(read_slice(b"CO401Memory1", 12, &mut buf), Ok(ReadLen { copied: 0, total: 12 }));
        assert_eq!(read_slice(b"CO401Memory1", 13, &mut buf), Err(SdoAbort::LengthTooHigh));
    }
}
