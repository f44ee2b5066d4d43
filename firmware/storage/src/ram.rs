//! An EEPROM image in RAM, erased to 0xFF: the banks of emulated boards, and of tests.

use embedded_storage::{ReadStorage, Storage};

/// An access outside the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutOfBounds;

/// Byte-writable memory in any buffer: an array it owns (`RamEeprom<[u8; N]>`), a `static`
/// it borrows and never moves (`RamEeprom<&mut [u8]>`: a board's banks stay in `.bss`
/// instead of being built on the stack), or a vector.
#[derive(Debug, Clone)]
pub struct RamEeprom<B> {
    bytes: B,
}

impl<const N: usize> RamEeprom<[u8; N]> {
    /// Erased memory (every byte 0xFF), as a new EEPROM is delivered.
    pub const fn new() -> Self {
        RamEeprom { bytes: [0xFF; N] }
    }
}

impl<const N: usize> Default for RamEeprom<[u8; N]> {
    fn default() -> Self {
        Self::new()
    }
}

impl<B: AsRef<[u8]> + AsMut<[u8]>> RamEeprom<B> {
    /// Erases `bytes` to 0xFF and uses them.
    pub fn erased(mut bytes: B) -> Self {
        bytes.as_mut().fill(0xFF);
        RamEeprom { bytes }
    }

    /// Uses `bytes` as they are: an image loaded from elsewhere.
    pub fn holding(bytes: B) -> Self {
        RamEeprom { bytes }
    }

    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.as_ref()
    }

    /// Direct access, for loading an image or injecting corruption.
    pub fn as_bytes_mut(&mut self) -> &mut [u8] {
        self.bytes.as_mut()
    }

    fn range(&self, offset: u32, len: usize) -> Result<core::ops::Range<usize>, OutOfBounds> {
        let start = usize::try_from(offset).map_err(|_| OutOfBounds)?;
        let end = start.checked_add(len).filter(|&e| e <= self.bytes.as_ref().len()).ok_or(OutOfBounds)?;
        Ok(start..end)
    }
}

impl<B: AsRef<[u8]> + AsMut<[u8]>> ReadStorage for RamEeprom<B> {
    type Error = OutOfBounds;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), OutOfBounds> {
        let range = self.range(offset, bytes.len())?;
        bytes.copy_from_slice(self.bytes.as_ref().get(range).ok_or(OutOfBounds)?);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.bytes.as_ref().len()
    }
}

impl<B: AsRef<[u8]> + AsMut<[u8]>> Storage for RamEeprom<B> {
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), OutOfBounds> {
        let range = self.range(offset, bytes.len())?;
        self.bytes.as_mut().get_mut(range).ok_or(OutOfBounds)?.copy_from_slice(bytes);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn owned_borrowed_and_held_images_behave_alike() {
        let mut owned = RamEeprom::<[u8; 4]>::new();
        let mut buffer = [0_u8; 4];
        let mut borrowed = RamEeprom::erased(&mut buffer[..]);
        for eeprom in [&mut owned as &mut dyn Storage<Error = OutOfBounds>, &mut borrowed] {
            assert_eq!(eeprom.capacity(), 4);
            eeprom.write(1, &[7, 8]).unwrap();
            let mut out = [0; 4];
            eeprom.read(0, &mut out).unwrap();
            assert_eq!(out, [0xFF, 7, 8, 0xFF]);
            assert_eq!(eeprom.write(3, &[1, 2]), Err(OutOfBounds), "past the end");
            assert_eq!(eeprom.read(u32::MAX, &mut out[..1]), Err(OutOfBounds));
        }
        assert_eq!(RamEeprom::holding([1_u8, 2]).as_bytes(), [1, 2], "held as it is");
    }
}
