//! An EEPROM image in RAM, erased to 0xFF: the banks of emulated boards, and of tests.

use embedded_storage::{ReadStorage, Storage};

/// An access outside the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutOfBounds;

/// `N` bytes of byte-writable memory.
#[derive(Debug, Clone)]
pub struct RamEeprom<const N: usize> {
    bytes: [u8; N],
}

impl<const N: usize> Default for RamEeprom<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> RamEeprom<N> {
    /// Erased memory (every byte 0xFF), as a new EEPROM is delivered.
    pub const fn new() -> Self {
        RamEeprom { bytes: [0xFF; N] }
    }

    pub fn as_bytes(&self) -> &[u8; N] {
        &self.bytes
    }

    /// Direct access, for loading an image or injecting corruption.
    pub fn as_bytes_mut(&mut self) -> &mut [u8; N] {
        &mut self.bytes
    }

    fn range(offset: u32, len: usize) -> Result<core::ops::Range<usize>, OutOfBounds> {
        let start = usize::try_from(offset).map_err(|_| OutOfBounds)?;
        let end = start.checked_add(len).filter(|&e| e <= N).ok_or(OutOfBounds)?;
        Ok(start..end)
    }
}

impl<const N: usize> ReadStorage for RamEeprom<N> {
    type Error = OutOfBounds;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), OutOfBounds> {
        let src = self.bytes.get(Self::range(offset, bytes.len())?).ok_or(OutOfBounds)?;
        bytes.copy_from_slice(src);
        Ok(())
    }

    fn capacity(&self) -> usize {
        N
    }
}

impl<const N: usize> Storage for RamEeprom<N> {
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), OutOfBounds> {
        let dst = self.bytes.get_mut(Self::range(offset, bytes.len())?).ok_or(OutOfBounds)?;
        dst.copy_from_slice(bytes);
        Ok(())
    }
}

/// Byte-writable memory in a buffer the caller owns: an EEPROM image in a `static` that is
/// never moved (a board's RAM banks stay in `.bss` instead of being built on the stack).
#[derive(Debug)]
pub struct BorrowedEeprom<'a> {
    bytes: &'a mut [u8],
}

impl<'a> BorrowedEeprom<'a> {
    /// Erases `bytes` to 0xFF and uses them.
    pub fn erased(bytes: &'a mut [u8]) -> Self {
        bytes.fill(0xFF);
        BorrowedEeprom { bytes }
    }

    /// Uses `bytes` as they are: an image loaded from elsewhere.
    pub fn holding(bytes: &'a mut [u8]) -> Self {
        BorrowedEeprom { bytes }
    }

    fn range(&self, offset: u32, len: usize) -> Result<core::ops::Range<usize>, OutOfBounds> {
        let start = usize::try_from(offset).map_err(|_| OutOfBounds)?;
        let end = start.checked_add(len).filter(|&e| e <= self.bytes.len()).ok_or(OutOfBounds)?;
        Ok(start..end)
    }
}

impl ReadStorage for BorrowedEeprom<'_> {
    type Error = OutOfBounds;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), OutOfBounds> {
        let src = self.bytes.get(self.range(offset, bytes.len())?).ok_or(OutOfBounds)?;
        bytes.copy_from_slice(src);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.bytes.len()
    }
}

impl Storage for BorrowedEeprom<'_> {
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), OutOfBounds> {
        let range = self.range(offset, bytes.len())?;
        self.bytes.get_mut(range).ok_or(OutOfBounds)?.copy_from_slice(bytes);
        Ok(())
    }
}
