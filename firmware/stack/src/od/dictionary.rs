//! The traits generated dictionaries implement: entry access (`EntryAccess`), what a node
//! needs beyond it (`NodeDictionary`), and the owner of app-backed objects (`AppObjects`).

use super::{AccessContext, EntryInfo, Limits, ReadLen, SdoAbort, Side, Table, WriteSource, find, image};
use coforge_types::Storage;

/// The dictionary of one device: implemented by the code `device!` generates.
///
/// The generated code provides the table and the value image its entries point into
/// (`image`, `image_mut`); reads, writes, lookups and access checks are the provided
/// methods, so every device refuses the same accesses with the same codes and the access
/// code exists once.
pub trait EntryAccess {
    /// Where app-backed entries (`storage: app`) are read and written.
    type App: AppObjects;

    /// The entry descriptions of the dictionary's mode, sorted by index and sub-index (see
    /// [`find`]).
    fn entries(&self) -> Table<'static>;

    /// The value limits the entries' `limits` indices refer to.
    fn limits(&self) -> &'static [Limits];

    /// The values of every stored (RAM and persistent) entry, as [`image`] lays them out:
    /// each entry's `offset` points in here.
    fn image(&self) -> &[u8];

    /// [`EntryAccess::image`], to write.
    fn image_mut(&mut self) -> &mut [u8];

    /// The device's app-backed objects.
    fn app(&mut self) -> &mut Self::App;

    /// Reads the value of `index`/`sub`, which `info` describes, from byte `offset` into
    /// `buf`: no lookup and no access check (the caller made both).
    fn read_entry(&mut self, info: &EntryInfo, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        if info.storage() == Storage::App {
            return self.app().read(info, index, sub, offset, buf);
        }
        image::read(self.image(), info, sub, offset, buf)
    }

    /// Writes `data` (the whole value, little-endian) after its length and value checks; no
    /// lookup and no access check. A refused write leaves the stored value unchanged.
    fn write_entry(&mut self, info: &EntryInfo, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        info.check_data(data, self.limits())?;
        if info.storage() == Storage::App {
            return self.app().write(info, index, sub, data);
        }
        image::write(self.image_mut(), info, sub, data)
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
/// defaults, the operating mode, the node settings, the persistent block and the
/// emergencies.
pub trait NodeDictionary: EntryAccess {
    /// The device's operating modes (the generated `Mode`).
    type Mode: Copy + PartialEq + core::fmt::Debug + 'static;

    /// Every mode, the spec's first (the default) first.
    const MODES: &'static [Self::Mode];

    /// The persistent block: the spans of the value image that hold `storage: persistent`
    /// entries, in index order, whatever the mode (a block saved in one mode loads in another).
    /// (Functions rather than constants: a constant referring to a static is beyond Kani 0.63.)
    fn persistent() -> &'static [image::Span]
    where
        Self: Sized;

    /// Bytes of the persistent block ([`image::block_len`] of [`NodeDictionary::persistent`]).
    const PERSISTENT_SIZE: usize;

    /// The spans of the value image a reset of an area sets back to the defaults: every
    /// stored entry, split where the index class changes.
    fn stored() -> &'static [image::Span]
    where
        Self: Sized;

    /// The defaults that depend on the node-ID, in every mode.
    fn node_id_defaults() -> &'static [image::Patch]
    where
        Self: Sized;

    /// Whether the SDO server does block transfer (the spec's `sdo_block_transfer`).
    const SDO_BLOCK_TRANSFER: bool;

    /// The optional communication objects the dictionary has in any mode.
    const COMM: CommObjects;

    /// The value image of the spec's defaults (the first mode's where they differ), before
    /// [`NodeDictionary::node_id_defaults`] and [`NodeDictionary::mode_defaults`], in the
    /// sparse form of [`image::sparse`].
    fn defaults() -> &'static [u8]
    where
        Self: Sized;

    /// The defaults of the dictionary's mode that differ from [`NodeDictionary::defaults`].
    fn mode_defaults(&self) -> &'static [image::Patch];

    /// Hands the image of every persistent entry of `area` to `sink` with its offset in the
    /// block, so the block is written without a buffer of its size; `false` if `sink` failed.
    fn save_area(&self, area: Area, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool
    where
        Self: Sized,
    {
        image::save(self.image(), Self::persistent(), area, sink)
    }

    /// Loads every persistent entry of `area` from `source` (offset, buffer to fill); a piece
    /// `source` cannot give keeps its bytes, and the result is `false`.
    fn load_area(&mut self, area: Area, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool
    where
        Self: Sized,
    {
        image::load(self.image_mut(), Self::persistent(), area, source)
    }

    /// Sets every stored entry (RAM and persistent) of `area` back to its spec default,
    /// `$NODEID` resolved for `node_id`. App-backed entries are the device's business.
    fn reset_area(&mut self, area: Area, node_id: u8)
    where
        Self: Sized,
    {
        let patches = self.mode_defaults();
        let image = self.image_mut();
        image::reset(image, Self::defaults(), Self::stored(), area);
        image::patch(image, Self::node_id_defaults(), area, node_id);
        image::patch(image, patches, area, node_id);
    }

    /// The spec's emergencies in the dictionary's mode.
    fn emergencies(&self) -> &'static [crate::emcy::EmcyDefault];

    /// The spec emergency of the dictionary's mode called `name` (hosts: fault injection;
    /// firmware that never asks leaves the names out of its image).
    fn emergency_named(&self, name: &str) -> Option<crate::emcy::EmcyDefault>;

    /// The dictionary with the spec's defaults of `mode`, `$NODEID` resolved for `node_id`.
    fn new(mode: Self::Mode, node_id: u8, app: Self::App) -> Self
    where
        Self: Sized;

    /// The mode the dictionary is in: its entry table and emergencies.
    fn mode(&self) -> Self::Mode;

    /// Switches to `mode`. Entries whose spec default differs between modes take `mode`'s
    /// default; every other value is kept (what a host configured before the CAN side was
    /// enabled survives the mode chosen at enable).
    fn set_mode(&mut self, mode: Self::Mode, node_id: u8);

    /// The mode's name in the spec.
    fn mode_name(mode: Self::Mode) -> &'static str
    where
        Self: Sized;

    /// The node settings of the spec's `node:` section, for `node_id`.
    fn node_config(node_id: u8) -> crate::config::NodeConfig
    where
        Self: Sized;
}

/// The mode a host tool names (`None`: the spec's first), or the list of known names.
pub fn mode_named<D: NodeDictionary>(name: Option<&str>) -> Result<D::Mode, &'static [D::Mode]> {
    match name {
        None => D::MODES.first().copied().ok_or(D::MODES),
        Some(name) => D::MODES.iter().copied().find(|&m| D::mode_name(m) == name).ok_or(D::MODES),
    }
}

/// Objects whose data the device keeps outside the dictionary (EEPROM banks, a memory card):
/// the generated dictionary routes their reads and writes here, after its access checks.
/// `entry` may describe a run of sub-indices and of repeated objects; `index`/`sub` is the one
/// accessed.
///
/// The owner of the objects also hears about writes (CANopenNode's OD extension idea): the
/// provided hooks do nothing and inline to nothing, so a device that does not override them
/// carries no code for them.
pub trait AppObjects {
    fn read(&mut self, entry: &EntryInfo, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort>;
    fn write(&mut self, entry: &EntryInfo, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort>;

    /// A write of the local entry `index`/`sub` took effect, any entry (not only app-backed
    /// ones): `data` as written, `by` whoever wrote it. The node calls it once per successful
    /// write, after the write's side effects (TPDO triggers, reloaded services, auto-save),
    /// and never for a refused or failed one; see [`crate::node`] for which writes count. A
    /// streamed download is indicated once complete, with empty `data`: its bytes went to
    /// [`AppObjects::write_part`].
    fn written(&mut self, _index: u16, _sub: u8, _data: &[u8], _by: WriteSource) {}

    /// Whether any entry streams (below). If not, the constant being false, the SDO server's
    /// streaming code is not in the image.
    const STREAMING: bool = false;

    /// Whether a segmented or block SDO download of the app-backed entry `index`/`sub`,
    /// initiated and checked (access, indicated size against the entry's maximum), is taken
    /// in parts ([`AppObjects::write_part`]) rather than collected in the SDO server's buffer,
    /// which may then be much smaller than the value. Expedited downloads and host or device
    /// writes always come whole through [`AppObjects::write`]; a block download streams only
    /// with its size indicated. Asked only if [`AppObjects::STREAMING`].
    fn streams(&mut self, _entry: &EntryInfo, _index: u16, _sub: u8) -> bool {
        false
    }

    /// The next part of a streamed download: `data` belongs at byte `offset`; parts come in
    /// order without gaps and never past the entry's maximum. `last`: the download is
    /// complete and checked (block download: length and CRC), so the value may take effect;
    /// the last part may be empty. An error aborts the transfer with that code.
    fn write_part(&mut self, _entry: &EntryInfo, _index: u16, _sub: u8, _offset: usize, _data: &[u8], _last: bool) -> Result<(), SdoAbort> {
        Err(SdoAbort::UnsupportedAccess)
    }

    /// A streamed download ended without success (client abort, timeout, toggle, length or
    /// CRC error, NMT reset or stop, a new initiate, an error of `write_part` itself): what
    /// its parts wrote is void. Called exactly once for every streamed download that does
    /// not end with `write_part(.., last = true)` succeeding.
    fn abort_stream(&mut self, _entry: &EntryInfo, _index: u16, _sub: u8) {}
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
