//! CR3101's logging: the card in the slot, the files on it, and what each file's operating
//! mode does with the values written to it. The dictionary's hooks ([`crate::objects`]) and
//! the device's RPDO input hand their reads and writes to [`Logger`].
//!
//! - [`pair`]: a redundant pair (2002h/2003h), a change taking effect when both halves agree;
//! - [`file_config`]: one file's configuration (3x00h..3x1ch) and its rules;
//! - [`file_run`]: one file's operating mode at run time: the record being filled, the
//!   autoincrement window, the cyclic timer, the end of the file.

pub mod file_config;
pub mod file_run;
pub mod pair;

use crate::card::fat_clock::FatClock;
use crate::card::files::{Card, CardError, FILES, SETTINGS_SLOT};
use crate::card::record::{Record, TimeStamp};
use crate::card::settings::{self, Settings};
use crate::clock::Clock;
use coforge_stack::od::SdoAbort;
use embedded_sdmmc::BlockDevice;
use file_config::{FileConfig, Mode};
use file_run::{Commit, FileRun};
use pair::RedundantPair;

/// How long pointers that moved wait before they are saved to the card (erratum CR-48):
/// a record every millisecond must not cost a configuration write every millisecond.
const SAVE_DELAY_US: u64 = 1_000_000;
/// How far past its saved write pointer a file is searched for records written after the
/// save: more than a second of records at the manual's one per millisecond.
const RECOVER_RECORDS: u32 = 2048;
/// A card block: the configuration file is written one at a time.
const BLOCK: usize = 512;

/// What the card slot shows (2001h, 1002h).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CardStatus {
    pub inserted: bool,
    pub write_protected: bool,
    /// Bytes; 0 when no card or a write-protected one (2001h.4).
    pub capacity: u32,
    /// A card is in the slot, but it holds no FAT volume the device can use.
    pub unusable: bool,
}

/// Conditions the device mirrors into emergencies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Conditions {
    /// Bit n: file n + 1 reached its end in linear mode (6200h, active until reset).
    pub file_full: u8,
    /// Bit n: file n + 1 wrapped in ring mode since the device last looked (6200h, an event).
    pub file_wrapped: u8,
    /// Card data was accessed with no usable card since the device last looked (5001h).
    pub no_card_access: bool,
}

/// The logger.
pub struct Logger<D: BlockDevice> {
    card: Option<Card<D, FatClock>>,
    status: CardStatus,
    settings: Settings,
    allocation: [RedundantPair<u32>; FILES],
    runs: [FileRun; FILES],
    clock: Clock,
    now_us: u64,
    /// RPDO and cyclic logging run in operational state only.
    operational: bool,
    conditions: Conditions,
    /// When moved pointers are saved to the card.
    save_at_us: Option<u64>,
    /// Accesses to the card in the slot that failed (pulled or broken mid-write, full).
    pub card_errors: u32,
    /// Records written to the card.
    card_writes: u32,
    /// An RPDO's communication parameters were written: the device reads their identifiers
    /// again.
    pub(crate) rpdo_parameters_written: bool,
}

impl<D: BlockDevice> core::fmt::Debug for Logger<D> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Logger").field("status", &self.status).field("settings", &self.settings).finish_non_exhaustive()
    }
}

/// The abort an SDO access to card data gets when the card refuses.
pub fn abort(e: CardError) -> SdoAbort {
    match e {
        CardError::Device => SdoAbort::Hardware,
        CardError::NoVolume | CardError::Full | CardError::Name => SdoAbort::DataTransfer,
        CardError::Range => SdoAbort::ValueTooHigh,
    }
}

impl<D: BlockDevice> Logger<D> {
    /// No card yet; the clock shows `time` at `now_us`.
    pub fn new(time: &TimeStamp, now_us: u64) -> Self {
        let settings = Settings::factory();
        Logger {
            card: None,
            status: CardStatus::default(),
            settings,
            allocation: [RedundantPair::new(0); FILES],
            runs: core::array::from_fn(|n| FileRun::new(settings.files.get(n).map(FileConfig::layout).unwrap_or_default())),
            clock: Clock::new(time, now_us),
            now_us,
            operational: false,
            conditions: Conditions::default(),
            save_at_us: None,
            card_errors: 0,
            card_writes: 0,
            rpdo_parameters_written: false,
        }
    }

    /// The time of the input being handled (the hooks have no clock of their own).
    pub fn set_now(&mut self, now_us: u64) {
        self.now_us = now_us;
    }

    /// Publishes the time `t` for the FAT directory entries of what is written next (a
    /// calendar conversion: only before a card write, not at every input).
    fn publish_fat_time(t: &TimeStamp) {
        FatClock::set(&crate::clock::fat_time_of(t));
    }

    pub fn set_operational(&mut self, operational: bool) {
        if operational && !self.operational {
            let now = self.now_us;
            self.runs.iter_mut().zip(&self.settings.files).for_each(|(r, f)| r.restart(f, now));
        }
        self.operational = operational;
    }

    pub fn status(&self) -> CardStatus {
        self.status
    }

    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    pub fn clock(&self) -> &Clock {
        &self.clock
    }

    pub fn clock_mut(&mut self) -> &mut Clock {
        &mut self.clock
    }

    /// The time of the input being handled.
    pub fn now_us(&self) -> u64 {
        self.now_us
    }

    pub fn now(&self) -> TimeStamp {
        self.clock.now(self.now_us)
    }

    /// Takes the conditions to mirror: events are handed out once.
    pub fn take_conditions(&mut self) -> Conditions {
        let c = self.conditions;
        self.conditions.file_wrapped = 0;
        self.conditions.no_card_access = false;
        c
    }

    /// A card was inserted: mounts it, reads its configuration (or gives a new card the
    /// factory one) and opens its files. A card without a usable volume is handed back and
    /// shows as unusable until it leaves the slot.
    ///
    /// Never inlined: the mounted card passes through its frame (a volume manager with its
    /// block cache, over a kilobyte), which would otherwise be reserved by every caller's
    /// frame on every call.
    #[inline(never)]
    pub fn insert(&mut self, device: D, write_protected: bool) -> Result<(), D> {
        if let Some(old) = self.remove() {
            // The slot holds one card: the old one's device goes with the new one's refusal.
            drop(old);
        }
        // CARD ERROR tells of this card's accesses.
        self.card_errors = 0;
        let mut card = match Card::mount(device, FatClock) {
            Ok(card) => card,
            Err((_, device)) => {
                self.status = CardStatus { inserted: true, write_protected, capacity: 0, unusable: true };
                return Err(device);
            }
        };
        let capacity = if write_protected { 0 } else { card.capacity().map_or(0, |c| u32::try_from(c).unwrap_or(u32::MAX)) };
        // Read a piece at a time into the settings themselves (factory ones if it fails).
        let stored = card.open_read_only(SETTINGS_SLOT, settings::FILE_NAME).is_ok()
            && self.settings.read_from(|at, buf| card.read_at(SETTINGS_SLOT, at as u32, buf).is_ok());
        if !stored {
            self.settings.reset();
        }
        let _ = card.close(SETTINGS_SLOT);
        if !write_protected {
            // A new card gets its configuration file now, so a PC sees what the device uses.
            if card.lay_out(SETTINGS_SLOT, settings::FILE_NAME, settings::LEN as u32, false).is_err() {
                self.card_errors = self.card_errors.wrapping_add(1);
            }
        }
        self.allocation = self.settings.allocation.map(RedundantPair::new);
        self.card = Some(card);
        self.status = CardStatus { inserted: true, write_protected, capacity, unusable: false };
        if !stored {
            let _ = self.save_settings();
        }
        let now = self.now_us;
        for n in 0..FILES {
            // A file that cannot be opened is counted, and its accesses refused.
            let _ = self.open_file(n, false);
            if let (Some(run), Some(file)) = (self.runs.get_mut(n), self.settings.files.get(n)) {
                *run = FileRun::new(file.layout());
                run.restart(file, now);
            }
            self.recover_pointers(n);
        }
        Ok(())
    }

    /// Finds the records written after the configuration file was last saved (the card was
    /// pulled, or the power lost, within the save delay; erratum CR-48): from the saved write
    /// pointer on, every record that holds a written component and is neither older than the
    /// save nor than the record before it, so that logging goes on after them instead of over
    /// them.
    fn recover_pointers(&mut self, n: usize) {
        let Ok(file) = self.file(n).copied() else { return };
        let records = file.records(self.settings.allocation.get(n).copied().unwrap_or(0));
        if !matches!(file.mode(), Mode::Cyclic | Mode::Autoincrement) || records == 0 {
            return;
        }
        let layout = file.layout();
        let len = layout.len() as u32;
        let mut bytes = [0; crate::card::record::MAX_RECORD];
        let Some(card) = self.card.as_mut() else { return };
        let mut read = |at: u32| {
            let buf = bytes.get_mut(..len as usize)?;
            card.read_at(n, at.checked_mul(len)?, buf).ok()?;
            Record::from_bytes(&layout, buf)
        };
        let (mut at, mut count) = (file.write_pointer(), file.count());
        let mut last = self.settings.saved_at.order_key();
        for _ in 0..RECOVER_RECORDS.min(records) {
            if at >= records {
                if !file.ring {
                    break;
                }
                at = 0;
            }
            let Some(record) = read(at).filter(|r| r.modified() != 0) else { break };
            let key = record.time_stamp().order_key();
            if key < last {
                break;
            }
            last = key;
            at += 1;
            count = count.max(at);
        }
        if (at, count) != (file.write_pointer(), file.count()) {
            self.advance(n, |f| f.set_progress(at, count));
        }
    }

    /// The card is to be removed, or was: moved pointers are saved while it still can be,
    /// its files closed, and its device handed back. Never inlined, as [`Logger::insert`].
    #[inline(never)]
    pub fn remove(&mut self) -> Option<D> {
        if self.save_at_us.is_some() {
            let _ = self.save_settings();
        }
        self.status = CardStatus::default();
        self.card.take().map(Card::unmount)
    }

    /// Opens data file `n` as the configuration says: laid out at its size on a writable
    /// card (with `erase`, emptied), as found on a write-protected one.
    fn open_file(&mut self, n: usize, erase: bool) -> Result<(), CardError> {
        let (size, file) = match (self.settings.allocation.get(n), self.settings.files.get(n)) {
            (Some(&size), Some(file)) => (size, *file),
            _ => return Err(CardError::Range),
        };
        let mut name = [0; 12];
        let len = file.file_name(&mut name);
        let name = core::str::from_utf8(name.get(..len).unwrap_or_default()).map_err(|_| CardError::Name)?;
        let protected = self.status.write_protected;
        Self::publish_fat_time(&self.clock.now(self.now_us));
        let card = self.card.as_mut().ok_or(CardError::NoVolume)?;
        let opened = match size {
            0 => card.close(n),
            _ if protected => card.open_read_only(n, name).map(|_| ()),
            _ => card.lay_out(n, name, size, erase),
        };
        // A card that is full or broken lights CARD ERROR.
        opened.inspect_err(|_| self.card_errors = self.card_errors.wrapping_add(1))
    }

    /// Card data needs a card: without one, the access is refused and counted for EMCY 5001h.
    pub fn require_card(&mut self) -> Result<(), SdoAbort> {
        self.card().map(|_| ())
    }

    fn card(&mut self) -> Result<&mut Card<D, FatClock>, SdoAbort> {
        if self.card.is_none() {
            self.conditions.no_card_access = true;
        }
        self.card.as_mut().ok_or(SdoAbort::DataTransfer)
    }

    /// The card for a write: a write-protected card refuses.
    fn writable_card(&mut self) -> Result<&mut Card<D, FatClock>, SdoAbort> {
        let protected = self.status.write_protected;
        let card = self.card()?;
        if protected { Err(SdoAbort::DataTransfer) } else { Ok(card) }
    }

    /// Saves the configuration now (a configuration write takes effect on the card at once).
    /// A write-protected card keeps what it holds: the change lasts until the card leaves.
    fn save_settings(&mut self) -> Result<(), CardError> {
        self.save_at_us = None;
        if self.status.write_protected {
            return Ok(());
        }
        self.settings.saved_at = self.now();
        Self::publish_fat_time(&self.settings.saved_at);
        let card = self.card.as_mut().ok_or(CardError::NoVolume)?;
        // A block of the file at a time: one card write each, and never the whole file on
        // the stack.
        let mut written = Ok(());
        for start in (0..settings::LEN).step_by(BLOCK) {
            let mut block = [0; BLOCK];
            self.settings.pieces(|at, bytes| {
                for (i, &b) in bytes.iter().enumerate() {
                    if let Some(dst) = (at + i).checked_sub(start).and_then(|o| block.get_mut(o)) {
                        *dst = b;
                    }
                }
            });
            written = written.and_then(|()| card.write_at(SETTINGS_SLOT, start as u32, &block));
        }
        written.inspect_err(|_| self.card_errors = self.card_errors.wrapping_add(1))
    }

    // ---- 2000h, 2002h/2003h ----

    /// 2000h: it needs a card, and is saved on it at once (erratum CR-48).
    pub fn set_card_name(&mut self, value: &[u8]) -> Result<(), SdoAbort> {
        let name = file_config::Text::new(value).ok_or(SdoAbort::LengthTooHigh)?;
        self.card()?;
        self.settings.name = name;
        self.save_settings().map_err(abort)
    }

    /// 2002h (`shadow` false) or 2003h sub `n + 1`.
    pub fn allocation(&mut self, n: usize, shadow: bool) -> Result<u32, SdoAbort> {
        self.card()?;
        let pair = self.allocation.get(n).ok_or(SdoAbort::NoSubIndex)?;
        Ok(if shadow { pair.second() } else { pair.first() })
    }

    /// Writes one half of file `n`'s size; when both halves agree on a new size, the file is
    /// laid out again at it, emptied, its pointers at record 0 (erratum CR-45).
    pub fn set_allocation(&mut self, n: usize, shadow: bool, size: u32) -> Result<(), SdoAbort> {
        self.writable_card()?;
        let pair = self.allocation.get_mut(n).ok_or(SdoAbort::NoSubIndex)?;
        let changed = if shadow { pair.write_second(size) } else { pair.write_first(size) };
        let Some(size) = changed else { return Ok(()) };
        if let (Some(s), Some(file)) = (self.settings.allocation.get_mut(n), self.settings.files.get_mut(n)) {
            *s = size;
            file.reset_pointers();
        }
        let laid_out = self.open_file(n, true);
        if let (Some(run), Some(file)) = (self.runs.get_mut(n), self.settings.files.get(n)) {
            *run = FileRun::new(file.layout());
            run.restart(file, self.now_us);
        }
        self.save_settings().map_err(abort)?;
        laid_out.map_err(abort)
    }

    // ---- 3x00h..3x1ch ----

    pub fn file(&self, n: usize) -> Result<&FileConfig, SdoAbort> {
        self.settings.files.get(n).ok_or(SdoAbort::NoObject)
    }

    /// Changes file `n`'s configuration, which needs a card and is saved on it at once
    /// (erratum CR-48); a change of its name opens (or lays out) the file of the new name, a
    /// change of its records' layout or mode starts its run afresh.
    pub fn configure_file(&mut self, n: usize, change: impl FnOnce(&mut FileConfig, u32) -> Result<(), SdoAbort>) -> Result<(), SdoAbort> {
        let before = *self.file(n)?;
        let size = self.settings.allocation.get(n).copied().unwrap_or(0);
        self.card()?;
        // A refused change leaves the file as it was.
        let mut after = before;
        change(&mut after, size)?;
        if let Some(file) = self.settings.files.get_mut(n) {
            *file = after;
        }
        self.save_settings().map_err(abort)?;
        if (before.name(), before.extension()) != (after.name(), after.extension()) {
            self.open_file(n, false).map_err(abort)?;
        }
        let restarts = before.layout() != after.layout() || before.mode() != after.mode() || before.interval() != after.interval();
        if restarts && let Some(run) = self.runs.get_mut(n) {
            *run = FileRun::new(after.layout());
            run.restart(&after, self.now_us);
        }
        if before.write_pointer() != after.write_pointer() || before.count() != after.count() {
            // A file at its end logs again once its pointers are set back.
            if let Some(run) = self.runs.get_mut(n) {
                run.reopen();
            }
            self.conditions.file_full &= !(1 << n);
        }
        Ok(())
    }

    /// 3x04h: in the direct modes, the record shown is read from the card.
    pub fn set_current(&mut self, n: usize, record: u32) -> Result<(), SdoAbort> {
        self.configure_file(n, |f, size| f.set_current(record, size))?;
        if matches!(self.file(n)?.mode(), Mode::DirectWriting | Mode::DirectReading) {
            self.load_shown(n)?;
        }
        Ok(())
    }

    /// Reads record 3x04h of file `n` from the card into what 5x00h shows.
    fn load_shown(&mut self, n: usize) -> Result<(), SdoAbort> {
        let file = *self.file(n)?;
        let layout = file.layout();
        let size = self.settings.allocation.get(n).copied().unwrap_or(0);
        if file.current() >= file.records(size) {
            // A file without records (not allocated) has no record to show.
            return Err(SdoAbort::NoData);
        }
        let mut bytes = [0; crate::card::record::MAX_RECORD];
        let len = layout.len();
        let at = file.current().checked_mul(len as u32).ok_or(SdoAbort::ValueTooHigh)?;
        let buf = bytes.get_mut(..len).ok_or(SdoAbort::General)?;
        self.card()?.read_at(n, at, buf).map_err(abort)?;
        let record = Record::from_bytes(&layout, buf).ok_or(SdoAbort::General)?;
        if let Some(run) = self.runs.get_mut(n) {
            run.show(record, file.current());
        }
        Ok(())
    }

    // ---- 5x00h ----

    /// The record 5x00h shows.
    pub fn shown(&mut self, n: usize) -> Result<Record, SdoAbort> {
        let file = *self.file(n)?;
        self.card()?;
        let direct = matches!(file.mode(), Mode::DirectWriting | Mode::DirectReading);
        let stale = self.runs.get(n).is_none_or(|r| r.shown_record() != Some(file.current()));
        if direct && stale {
            self.load_shown(n)?;
        }
        self.runs.get(n).map(FileRun::shown).ok_or(SdoAbort::NoObject)
    }

    /// Component `c` (0-based) of file `n` written with `value`, over SDO or from an RPDO.
    /// In autoincrement writing with a window of 0, the caller ends the input with
    /// [`Logger::end_input`], so that one frame is one record.
    pub fn write_component(&mut self, n: usize, c: usize, value: &[u8]) -> Result<(), SdoAbort> {
        let file = *self.file(n)?;
        let layout = file.layout();
        let size = layout.component(c).map(|r| r.len()).ok_or(SdoAbort::DataTransfer)?;
        if value.len() != size {
            return Err(SdoAbort::LengthMismatch);
        }
        self.writable_card()?;
        match file.mode() {
            Mode::DirectReading => Err(SdoAbort::DataTransferState),
            Mode::DirectWriting => {
                let mut record = self.shown(n)?;
                record.set(&layout, c, value);
                record.stamp(&self.now());
                self.write_record(n, file.current(), &record)?;
                if let Some(run) = self.runs.get_mut(n) {
                    run.show(record, file.current());
                }
                let count = file.count().max(file.current().saturating_add(1));
                if count != file.count() {
                    self.advance(n, |f| f.set_progress(f.write_pointer(), count));
                }
                Ok(())
            }
            Mode::Cyclic | Mode::Autoincrement => {
                let now = self.now_us;
                let run = self.runs.get_mut(n).ok_or(SdoAbort::NoObject)?;
                if run.is_stopped() {
                    return Err(SdoAbort::DataTransferState);
                }
                run.set(&layout, c, value, &file, now);
                Ok(())
            }
        }
    }

    /// The end of one input (an SDO write, an RPDO) to file `n`: in autoincrement writing
    /// with a window of 0 the record is written now.
    pub fn end_input(&mut self, n: usize) {
        let window_zero = self.file(n).is_ok_and(|f| f.mode() == Mode::Autoincrement && f.interval() == 0);
        if window_zero && self.runs.get(n).is_some_and(FileRun::has_input) {
            self.commit(n, self.now_us);
        }
    }

    /// Writes `record` at record address `at` of file `n`.
    fn write_record(&mut self, n: usize, at: u32, record: &Record) -> Result<(), SdoAbort> {
        Self::publish_fat_time(&record.time_stamp());
        let offset = at.saturating_mul(record.as_bytes().len() as u32);
        let written = self.writable_card()?.write_at(n, offset, record.as_bytes());
        match written {
            Ok(()) => {
                self.card_writes = self.card_writes.wrapping_add(1);
                Ok(())
            }
            Err(e) => {
                self.card_errors = self.card_errors.wrapping_add(1);
                Err(abort(e))
            }
        }
    }

    /// Records written so far (the CARD ACCESS LED flashes with them).
    pub fn card_writes(&self) -> u32 {
        self.card_writes
    }

    /// Moves file `n`'s pointers; they reach the card with the next save.
    fn advance(&mut self, n: usize, f: impl FnOnce(&mut FileConfig)) {
        if let Some(file) = self.settings.files.get_mut(n) {
            f(file);
        }
        let now = self.now_us;
        self.save_at_us.get_or_insert(now.saturating_add(SAVE_DELAY_US));
    }

    /// Writes file `n`'s pending record, stamped with the time it was due, at its write
    /// pointer and moves on (cyclic writing at each interval, autoincrement writing when its
    /// window closes).
    fn commit(&mut self, n: usize, due_us: u64) {
        let Ok(file) = self.file(n).copied() else { return };
        let size = self.settings.allocation.get(n).copied().unwrap_or(0);
        let records = file.records(size);
        let stamp = self.clock.now(due_us);
        let Some(run) = self.runs.get_mut(n) else { return };
        let now = self.now_us;
        let Commit { record, at } = match run.commit(&file, records, &stamp, now) {
            Some(c) => c,
            None => return,
        };
        if self.write_record(n, at, &record).is_err() {
            return;
        }
        let next = at + 1;
        let count = file.count().max(next);
        let bit = 1_u8 << n;
        if next < records {
            self.advance(n, |f| f.set_progress(next, count));
        } else if file.ring {
            self.advance(n, |f| f.set_progress(0, count));
            self.conditions.file_wrapped |= bit;
        } else {
            // Linear: the file is full. Autoincrement writing goes over to direct reading.
            self.advance(n, |f| f.set_progress(next, count));
            self.conditions.file_full |= bit;
            if let Some(run) = self.runs.get_mut(n) {
                run.stop();
            }
            if file.mode() == Mode::Autoincrement
                && let Some(f) = self.settings.files.get_mut(n)
            {
                f.switch_to_reading(at);
            }
        }
    }

    /// Runs the timers at `now_us`: cyclic records, autoincrement windows that closed, the
    /// delayed save. The earliest time something is due, for the runtime's sleep.
    pub fn check(&mut self, now_us: u64) -> Option<u64> {
        self.set_now(now_us);
        let mut next: Option<u64> = None;
        for n in 0..FILES {
            if let Some(t) = self.due(n).filter(|&t| t <= now_us) {
                self.commit(n, t);
            }
            let after = self.due(n);
            next = match (next, after) {
                (Some(a), Some(b)) => Some(a.min(b)),
                (a, b) => a.or(b),
            };
        }
        if self.save_at_us.is_some_and(|t| t <= now_us) {
            let _ = self.save_settings();
        }
        match (next, self.save_at_us) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }

    /// When file `n` next writes a record by itself (a cyclic record, a window closing).
    fn due(&self, n: usize) -> Option<u64> {
        let (run, file) = (self.runs.get(n)?, self.settings.files.get(n)?);
        run.due(file, self.operational)
    }

    /// PDO read mode: the answer to a request for `part` (0 values, 1 time stamp) of `record`
    /// of file `n` (erratum CR-31: the milliseconds most significant byte first); `None` for
    /// a request the card cannot answer.
    pub fn read_part(&mut self, n: usize, record: u32, part: u8) -> Option<[u8; 8]> {
        let file = *self.settings.files.get(n)?;
        let size = self.settings.allocation.get(n).copied().unwrap_or(0);
        if record >= file.records(size) || part > 1 {
            return None;
        }
        let layout = file.layout();
        let mut bytes = [0; crate::card::record::MAX_RECORD];
        let buf = bytes.get_mut(..layout.len())?;
        self.card().ok()?.read_at(n, record * layout.len() as u32, buf).ok()?;
        let record = Record::from_bytes(&layout, buf)?;
        let mut out = [0; 8];
        if part == 0 {
            let data = record.as_bytes().get(crate::card::record::TIME_STAMP + 1..).unwrap_or_default();
            out.iter_mut().zip(data).for_each(|(d, s)| *d = *s);
        } else {
            let t = record.time_stamp();
            let [ms_hi, ms_lo] = t.millisecond.to_be_bytes();
            out = [ms_hi, ms_lo, t.second, t.minute, t.hour, t.day, t.month, t.year];
        }
        Some(out)
    }
}
