//! Parameter storage for simulated devices: an EEPROM image in memory, optionally mirrored
//! to a file so stored parameters survive restarting the simulator.

use embedded_storage::{ReadStorage, Storage};
use std::fs::File;
use std::io::{Seek, SeekFrom, Write};
use std::path::Path;

/// Why a storage access failed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum StorageError {
    OutOfBounds,
    File(String),
}

/// A byte-addressable store of `capacity` bytes, erased to 0xFF like an EEPROM.
#[derive(Debug)]
pub struct MemStorage {
    bytes: Vec<u8>,
    /// Written through at the same offsets, so a save costs what it writes, not the file.
    file: Option<File>,
}

impl MemStorage {
    pub fn new(capacity: usize) -> Self {
        MemStorage { bytes: vec![0xFF; capacity], file: None }
    }

    /// Backed by `path`: loaded from it if it exists, written through on every write.
    pub fn with_file(capacity: usize, path: &Path) -> std::io::Result<Self> {
        let mut bytes = match std::fs::read(path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
            Err(e) => return Err(e),
        };
        bytes.resize(capacity, 0xFF);
        let mut file = std::fs::OpenOptions::new().create(true).truncate(false).write(true).open(path)?;
        file.write_all(&bytes)?;
        Ok(MemStorage { bytes, file: Some(file) })
    }

    fn range(&self, offset: u32, len: usize) -> Result<std::ops::Range<usize>, StorageError> {
        let start = usize::try_from(offset).map_err(|_| StorageError::OutOfBounds)?;
        let end = start.checked_add(len).ok_or(StorageError::OutOfBounds)?;
        if end > self.bytes.len() { Err(StorageError::OutOfBounds) } else { Ok(start..end) }
    }
}

impl embedded_storage::nor_flash::NorFlashError for StorageError {
    fn kind(&self) -> embedded_storage::nor_flash::NorFlashErrorKind {
        embedded_storage::nor_flash::NorFlashErrorKind::Other
    }
}

impl ReadStorage for MemStorage {
    type Error = StorageError;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), StorageError> {
        let r = self.range(offset, bytes.len())?;
        bytes.copy_from_slice(self.bytes.get(r).ok_or(StorageError::OutOfBounds)?);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.bytes.len()
    }
}

impl Storage for MemStorage {
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), StorageError> {
        let r = self.range(offset, bytes.len())?;
        self.bytes.get_mut(r).ok_or(StorageError::OutOfBounds)?.copy_from_slice(bytes);
        if let Some(file) = &mut self.file {
            file.seek(SeekFrom::Start(u64::from(offset))).and_then(|_| file.write_all(bytes)).map_err(|e| StorageError::File(e.to_string()))?;
        }
        Ok(())
    }
}
