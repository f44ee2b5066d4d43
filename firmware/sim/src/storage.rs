//! Non-volatile memory of simulated devices: an EEPROM image in RAM, optionally mirrored to a
//! file so stored data survives restarting the simulator.

use coforge_storage::ram::RamEeprom;
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
pub struct Eeprom {
    ram: RamEeprom<Vec<u8>>,
    /// Written through at the same offsets, so a save costs what it writes, not the file.
    file: Option<File>,
}

impl Eeprom {
    pub fn new(capacity: usize) -> Self {
        Eeprom { ram: RamEeprom::erased(vec![0; capacity]), file: None }
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
        Ok(Eeprom { ram: RamEeprom::holding(bytes), file: Some(file) })
    }
}

impl embedded_storage::nor_flash::NorFlashError for StorageError {
    fn kind(&self) -> embedded_storage::nor_flash::NorFlashErrorKind {
        embedded_storage::nor_flash::NorFlashErrorKind::Other
    }
}

impl ReadStorage for Eeprom {
    type Error = StorageError;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), StorageError> {
        self.ram.read(offset, bytes).map_err(|_| StorageError::OutOfBounds)
    }

    fn capacity(&self) -> usize {
        self.ram.capacity()
    }
}

impl Storage for Eeprom {
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), StorageError> {
        self.ram.write(offset, bytes).map_err(|_| StorageError::OutOfBounds)?;
        if let Some(file) = &mut self.file {
            file.seek(SeekFrom::Start(u64::from(offset))).and_then(|_| file.write_all(bytes)).map_err(|e| StorageError::File(e.to_string()))?;
        }
        Ok(())
    }
}

/// CANopenIA's configuration files are read where they are stored.
impl canopenia::config::slots::ConfigMemory for Eeprom {
    fn mapped(&self) -> &[u8] {
        self.ram.as_bytes()
    }

    fn erase(&mut self, offset: u32, len: u32) -> Result<(), StorageError> {
        self.write(offset, &vec![0xFF; len as usize])
    }
}
