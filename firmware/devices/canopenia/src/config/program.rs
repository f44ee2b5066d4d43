//! 1F50h (program data) and 1F51h (program control) as the manual's section 4.2 uses them:
//!
//! 1. the device's serial number (1018h.4) written to 1F50h.1 is the key; another value is
//!    refused (0609 0030h);
//! 2. 0 written to 1F51h.1 with the key given stops the application: the device resets into
//!    bootloader mode as node 70h; without the key the write is refused (0800 0022h);
//! 3. in bootloader mode a binary EDS written to 1F50h.2 (segmented or block SDO) streams into
//!    the free slot; at its last segment the whole file is read back and checked
//!    ([`check`](super::check)), and only a file that passes becomes the active one, otherwise
//!    the download ends in the refusal's abort and nothing changes;
//! 4. 1 written to 1F51h.1 starts the application again, with the active file.
//!
//! 1F51h.1 = 2 restarts the running program, 3 (in bootloader mode) clears the stored files, so
//! the firmware's own dictionary applies again (CiA 302's values; erratum COIA-51). Outside
//! bootloader mode 1F50h.2 answers 0800 0022h.

use super::check::check;
use super::slots::{ConfigMemory, ConfigSlots, SlotError};
use coforge_beds::BinaryEds;
use coforge_stack::od::{SdoAbort, Table};

/// What the device has to do after the input that asked for it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProgramRequest {
    /// Reset into bootloader mode (node 70h).
    EnterBootloader,
    /// Reset into the application with the active file.
    StartApplication,
    /// Reset the running program (application or bootloader).
    Restart,
}

/// 1F51h.1's values (CiA 302).
const STOP: u8 = 0;
const START: u8 = 1;
const RESET: u8 = 2;
const CLEAR: u8 = 3;

/// The program state behind 1F50h/1F51h, on configuration memory `M`.
#[derive(Debug)]
pub struct Program<M> {
    /// The files; lent to the device while it writes a file's values into the dictionary.
    slots: Option<ConfigSlots<M>>,
    bootloader: bool,
    /// 1F50h.1 held the serial number when it was last written.
    key: bool,
    /// The device's serial number (1018h.4), set by the device.
    pub serial: u32,
    request: Option<ProgramRequest>,
    /// The dictionary a file is checked against.
    entries: Table<'static>,
}

fn storage_abort(e: SlotError) -> SdoAbort {
    match e {
        SlotError::TooLong => SdoAbort::LengthTooHigh,
        SlotError::Device => SdoAbort::Hardware,
        // The SDO server hands parts over in order; anything else is the server's fault.
        SlotError::OutOfOrder => SdoAbort::General,
    }
}

/// The active file of `slots`, checked again against `entries` (storage may have decayed since
/// it was stored): `None` if there is none or it no longer passes.
pub fn checked_active<'s, M: ConfigMemory>(slots: &'s ConfigSlots<M>, entries: Table<'_>) -> Option<BinaryEds<'s>> {
    let file = BinaryEds::parse(slots.active()?).ok()?;
    check(&file, entries).ok().map(|()| file)
}

impl<M: ConfigMemory> Program<M> {
    pub fn new(memory: M, entries: Table<'static>) -> Self {
        Program { slots: Some(ConfigSlots::new(memory)), bootloader: false, key: false, serial: 0, request: None, entries }
    }

    pub fn in_bootloader(&self) -> bool {
        self.bootloader
    }

    /// Taken by the device after each input.
    pub fn take_request(&mut self) -> Option<ProgramRequest> {
        self.request.take()
    }

    /// The device has reset into the mode it asked for.
    pub fn entered(&mut self, bootloader: bool) {
        self.bootloader = bootloader;
        self.key = false;
        if let Some(slots) = self.slots.as_mut() {
            slots.discard();
        }
    }

    /// The active file, checked again.
    pub fn active(&self) -> Option<BinaryEds<'_>> {
        checked_active(self.slots.as_ref()?, self.entries)
    }

    /// The files, lent to the device while it writes the active file's values into the
    /// dictionary (whose app part this is); [`Program::give_back`] returns them.
    pub fn lend(&mut self) -> Option<ConfigSlots<M>> {
        self.slots.take()
    }

    pub fn give_back(&mut self, slots: ConfigSlots<M>) {
        self.slots = Some(slots);
    }

    /// The files, unless they are lent.
    fn slots(&mut self) -> Result<&mut ConfigSlots<M>, SdoAbort> {
        self.slots.as_mut().ok_or(SdoAbort::DataTransferState)
    }

    /// 1F50h.1: the activation key.
    pub fn write_key(&mut self, data: &[u8]) -> Result<(), SdoAbort> {
        let mut key = [0_u8; 4];
        key.iter_mut().zip(data).for_each(|(k, d)| *k = *d);
        self.key = data.len() == 4 && u32::from_le_bytes(key) == self.serial;
        if self.key { Ok(()) } else { Err(SdoAbort::InvalidValue) }
    }

    /// 1F51h.1 reads 1 while the application runs, 0 in bootloader mode.
    pub fn control(&self) -> u8 {
        if self.bootloader { STOP } else { START }
    }

    /// 1F51h.1 written (the dictionary checked the range 0..=3).
    pub fn write_control(&mut self, value: u8) -> Result<(), SdoAbort> {
        let request = match (value, self.bootloader) {
            (STOP, false) if self.key => ProgramRequest::EnterBootloader,
            (STOP, false) => return Err(SdoAbort::DataTransferState),
            (START, true) => ProgramRequest::StartApplication,
            (STOP, true) | (START, false) => return Ok(()),
            (RESET, _) => ProgramRequest::Restart,
            (CLEAR, true) => return self.slots()?.clear().map_err(storage_abort),
            _ => return Err(SdoAbort::DataTransferState),
        };
        self.request = Some(request);
        Ok(())
    }

    /// The next part of a download into 1F50h.2.
    pub fn write_part(&mut self, offset: usize, data: &[u8], last: bool) -> Result<(), SdoAbort> {
        if !self.bootloader {
            return Err(SdoAbort::DataTransferState);
        }
        let slots = self.slots()?;
        if offset == 0 {
            slots.begin().map_err(storage_abort)?;
        }
        slots.write(offset, data).map_err(storage_abort)?;
        if last { self.finish() } else { Ok(()) }
    }

    /// A download that does not stream (4 bytes or less): never a whole file.
    pub fn write_whole(&mut self, data: &[u8]) -> Result<(), SdoAbort> {
        self.write_part(0, data, true)
    }

    /// The whole file is in its slot: checked where it is stored, and made active if it
    /// passes.
    fn finish(&mut self) -> Result<(), SdoAbort> {
        let entries = self.entries;
        let slots = self.slots()?;
        let (checked, len) = match slots.downloaded() {
            None => (Err(SdoAbort::Hardware), 0),
            Some(bytes) => {
                let checked = match BinaryEds::parse(bytes) {
                    Err(_) => Err(SdoAbort::NoDictionary),
                    Ok(file) => check(&file, entries).map(|()| crc_of(file.bytes())),
                };
                (checked, bytes.len())
            }
        };
        match checked {
            Ok(crc) => slots.commit(len, crc).map_err(storage_abort),
            Err(abort) => {
                slots.discard();
                Err(abort)
            }
        }
    }

    /// The download ended early (abort, timeout, reset): its slot stays without a header.
    pub fn abort_download(&mut self) {
        if let Some(slots) = self.slots.as_mut() {
            slots.discard();
        }
    }
}

/// The file's own CRC: its last two bytes.
fn crc_of(file: &[u8]) -> u16 {
    match file {
        [.., lo, hi] => u16::from_le_bytes([*lo, *hi]),
        _ => 0,
    }
}
