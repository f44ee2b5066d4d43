//! The app-backed objects: memory bytes (5000h..503Fh), bank checksums (5C00h), bank status
//! (6000h) and bank commands (6200h), all over the mirrored banks.

use coforge_stack::od::{AppObjects, EntryInfo, ReadLen, SdoAbort, read_slice};
use coforge_storage::{BankStatus, Error, MirroredBanks};
use embedded_storage::Storage;

/// Memory blocks (objects 5000h..503Fh).
pub const BLOCKS: usize = 64;
/// Bytes per block (sub-indices 1..=0x80).
pub const BLOCK: usize = 128;
/// Bytes each bank's EEPROM needs: data plus one commit record per block.
pub const BANK_SIZE: usize = coforge_storage::bank_size(BLOCKS, BLOCK);

/// The two banks on the datasheet's geometry.
pub type Banks<S> = MirroredBanks<S, BLOCKS, BLOCK>;

/// 6200h command: clear all error flags and status information of the bank's channel.
pub const CLEAR_STATUS: u8 = 0x91;

const MEMORY: core::ops::RangeInclusive<u16> = 0x5000..=0x503F;

/// The memory module's application objects.
#[derive(Debug)]
pub struct MemoryApp<S> {
    banks: Banks<S>,
    /// The last command byte written to each bank's 6200h entry.
    commands: [u8; 2],
    /// Cleared by the supply guard: memory writes are refused, nothing stored changes.
    writes_allowed: bool,
}

impl<S: Storage> MemoryApp<S> {
    /// Mounts the banks (checking and repairing every block).
    pub fn new(banks: [S; 2]) -> Self {
        MemoryApp { banks: Banks::mount(banks), commands: [0; 2], writes_allowed: true }
    }

    pub fn banks(&self) -> &Banks<S> {
        &self.banks
    }

    pub fn banks_mut(&mut self) -> &mut Banks<S> {
        &mut self.banks
    }

    pub fn set_writes_allowed(&mut self, allowed: bool) {
        self.writes_allowed = allowed;
    }

    pub fn status(&self, bank: usize) -> BankStatus {
        self.banks.status(bank)
    }

    /// Memory address of `index`/`sub` (sub 1 of 5000h is address 0).
    fn address(index: u16, sub: u8) -> Option<usize> {
        if !MEMORY.contains(&index) || !(1..=BLOCK).contains(&usize::from(sub)) {
            return None;
        }
        Some(usize::from(index - 0x5000) * BLOCK + usize::from(sub) - 1)
    }

    /// Bank 0 or 1 for sub-index 1 or 2.
    fn bank(sub: u8) -> Result<usize, SdoAbort> {
        match sub {
            1 | 2 => Ok(usize::from(sub) - 1),
            _ => Err(SdoAbort::NoSubIndex),
        }
    }
}

/// A bank fault seen by the bus: the hardware could not deliver valid data.
fn abort(e: Error) -> SdoAbort {
    match e {
        Error::OutOfRange => SdoAbort::NoSubIndex,
        Error::Lost { .. } | Error::Access => SdoAbort::Hardware,
    }
}

impl<S: Storage> AppObjects for MemoryApp<S> {
    fn read(&mut self, _: &EntryInfo, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        match index {
            0x5C00 => read_slice(&self.banks.checksum(Self::bank(sub)?).to_le_bytes(), offset, buf),
            0x6000 => read_slice(&[self.banks.status(Self::bank(sub)?).bits()], offset, buf),
            0x6200 => read_slice(&[self.commands.get(Self::bank(sub)?).copied().unwrap_or(0)], offset, buf),
            // Sub 0: the number of bytes in the block.
            index if MEMORY.contains(&index) && sub == 0 => read_slice(&[BLOCK as u8], offset, buf),
            index => {
                let addr = Self::address(index, sub).ok_or(SdoAbort::NoObject)?;
                let mut byte = [0];
                self.banks.read(addr, &mut byte).map_err(abort)?;
                read_slice(&byte, offset, buf)
            }
        }
    }

    fn write(&mut self, _: &EntryInfo, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        match index {
            0x6200 => {
                let bank = Self::bank(sub)?;
                let &[command] = data else { return Err(SdoAbort::LengthMismatch) };
                if let Some(c) = self.commands.get_mut(bank) {
                    *c = command;
                }
                // Only 0x91 is defined; other command bytes are kept and do nothing.
                if command == CLEAR_STATUS {
                    self.banks.clear_status(bank);
                }
                Ok(())
            }
            index => {
                let addr = Self::address(index, sub).ok_or(SdoAbort::NoObject)?;
                if !self.writes_allowed {
                    return Err(SdoAbort::DataTransferState);
                }
                self.banks.write(addr, data).map_err(abort)
            }
        }
    }
}
