//! A bank kept in a file on the host through semihosting, so that what the module stored
//! survives a restart of the image. QEMU must run with
//! `-semihosting-config enable=on,target=native`: without it a semihosting call is a fault.
//!
//! Reads come from the bank's image in RAM; every write changes the image and goes to the
//! file at once, at the same offset, so the file is always what the EEPROM would hold.

use coforge_storage::ram::RamEeprom;
use cortex_m_semihosting::{nr, syscall};
use embedded_storage::{ReadStorage, Storage};

/// A semihosting call failed, or an offset is outside the bank.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HostFileError;

/// One bank: its RAM image and the open host file behind it.
#[derive(Debug)]
pub struct HostFileEeprom<'a> {
    ram: RamEeprom<&'a mut [u8]>,
    handle: usize,
}

/// A semihosting operation with its parameter block.
fn call<const N: usize>(op: usize, args: [usize; N]) -> usize {
    // SAFETY: `args` is the parameter block this operation defines, and the buffers its
    // words point to outlive the call (the host reads or writes them before it returns).
    unsafe { syscall(op, &args) }
}

impl<'a> HostFileEeprom<'a> {
    /// Opens `path` (NUL-terminated) on the host. A file of exactly `image.len()` bytes is
    /// loaded into `image`; otherwise the file is created (or cut to nothing) and written
    /// erased (0xFF), as a new EEPROM is delivered.
    pub fn open(path: &'static str, image: &'a mut [u8]) -> Result<Self, HostFileError> {
        let name = path.strip_suffix('\0').ok_or(HostFileError)?;
        let open = |mode| call(nr::OPEN, [name.as_ptr() as usize, mode, name.len()]);
        let existing = open(nr::open::RW_BINARY);
        if existing != usize::MAX {
            let loaded = call(nr::FLEN, [existing]) == image.len() && call(nr::READ, [existing, image.as_mut_ptr() as usize, image.len()]) == 0;
            if loaded {
                return Ok(HostFileEeprom { ram: RamEeprom::holding(image), handle: existing });
            }
            call(nr::CLOSE, [existing]);
        }
        let handle = open(nr::open::RW_TRUNC_BINARY);
        if handle == usize::MAX {
            return Err(HostFileError);
        }
        let mut bank = HostFileEeprom { ram: RamEeprom::erased(image), handle };
        let len = bank.ram.capacity();
        bank.write_file(0, len)?;
        Ok(bank)
    }

    /// Writes `len` bytes of the RAM image from `offset` to the file.
    fn write_file(&mut self, offset: u32, len: usize) -> Result<(), HostFileError> {
        let mut chunk = [0_u8; 128];
        let mut at = offset;
        let end = offset as usize + len;
        while (at as usize) < end {
            let n = chunk.len().min(end - at as usize);
            let part = chunk.get_mut(..n).ok_or(HostFileError)?;
            self.ram.read(at, part).map_err(|_| HostFileError)?;
            if call(nr::SEEK, [self.handle, at as usize]) != 0 || call(nr::WRITE, [self.handle, part.as_ptr() as usize, n]) != 0 {
                return Err(HostFileError);
            }
            at += n as u32;
        }
        Ok(())
    }
}

impl ReadStorage for HostFileEeprom<'_> {
    type Error = HostFileError;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), HostFileError> {
        self.ram.read(offset, bytes).map_err(|_| HostFileError)
    }

    fn capacity(&self) -> usize {
        self.ram.capacity()
    }
}

impl Storage for HostFileEeprom<'_> {
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), HostFileError> {
        self.ram.write(offset, bytes).map_err(|_| HostFileError)?;
        self.write_file(offset, bytes.len())
    }
}

/// CANopenIA's configuration files are read where they are stored: in the RAM image.
impl canopenia::config::slots::ConfigMemory for HostFileEeprom<'_> {
    fn mapped(&self) -> &[u8] {
        self.ram.as_bytes()
    }

    /// An EEPROM has no erase: 0xFF is written, in the pieces one file write takes.
    fn erase(&mut self, offset: u32, len: u32) -> Result<(), HostFileError> {
        const PIECE: u32 = 256;
        let mut at = offset;
        while at < offset + len {
            let n = PIECE.min(offset + len - at);
            self.write(at, &[0xFF; PIECE as usize][..n as usize])?;
            at += n;
        }
        Ok(())
    }
}
