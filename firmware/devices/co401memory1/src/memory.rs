//! The app-backed objects: memory bytes (5000h..503Fh), bank checksums (5C00h), bank status
//! (6000h) and bank commands (6200h), all over the mirrored banks, each through its generated
//! hook.

use crate::app::Hooks;
use coforge_stack::od::SdoAbort;
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

/// Each app-backed object's reads and writes, as the generated hooks name them.
impl<S: Storage> Hooks for MemoryApp<S> {
    fn read_memory_block_byte_access(&mut self, block: u16, sub: u8) -> Result<u8, SdoAbort> {
        // Sub 0: the number of bytes in the block.
        let Some(offset) = usize::from(sub).checked_sub(1) else { return Ok(BLOCK as u8) };
        let mut byte = [0];
        self.banks.read(usize::from(block) * BLOCK + offset, &mut byte).map_err(abort)?;
        Ok(byte[0])
    }

    fn write_memory_block_byte_access(&mut self, block: u16, sub: u8, value: u8) -> Result<(), SdoAbort> {
        let offset = usize::from(sub).checked_sub(1).ok_or(SdoAbort::ReadOnly)?;
        if !self.writes_allowed {
            return Err(SdoAbort::DataTransferState);
        }
        self.banks.write(usize::from(block) * BLOCK + offset, &[value]).map_err(abort)
    }

    fn read_memory_bank_checksum(&mut self, sub: u8) -> Result<u32, SdoAbort> {
        Ok(self.banks.checksum(Self::bank(sub)?))
    }

    fn read_memory_bank_status(&mut self, sub: u8) -> Result<u8, SdoAbort> {
        Ok(self.banks.status(Self::bank(sub)?).bits())
    }

    fn read_write_memory_bank_command(&mut self, sub: u8) -> Result<u8, SdoAbort> {
        Ok(self.commands.get(Self::bank(sub)?).copied().unwrap_or(0))
    }

    fn write_write_memory_bank_command(&mut self, sub: u8, command: u8) -> Result<(), SdoAbort> {
        let bank = Self::bank(sub)?;
        if let Some(c) = self.commands.get_mut(bank) {
            *c = command;
        }
        // Only 0x91 is defined; other command bytes are kept and do nothing.
        if command == CLEAR_STATUS {
            self.banks.clear_status(bank);
        }
        Ok(())
    }
}
