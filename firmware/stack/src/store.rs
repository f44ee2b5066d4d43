//! The parameter block of 1010h/1011h on any `embedded-storage` device (EEPROM, flash
//! emulation, a file on a PC).
//!
//! Layout at `base`: magic "CFG1", block length (u32 LE), CRC-16/XMODEM of the data (u16 LE),
//! two reserved bytes, then the data as [`Dictionary::save_area`] lays it out. A block whose
//! magic, length or CRC does not match is ignored, so a torn or corrupt store falls back to
//! the spec defaults instead of loading garbage. Saving invalidates the header first and
//! writes it last.

use crate::od::{Area, Dictionary};
use coforge_link::crc::{Crc16, XMODEM};
use embedded_storage::Storage;

const MAGIC: [u8; 4] = *b"CFG1";
const HEADER: u32 = 12;
static CRC: Crc16 = Crc16::new(XMODEM);

/// Why the parameter store failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StoreError {
    /// The storage device reported an error.
    Device,
    /// The block does not fit the storage.
    TooSmall,
}

/// Parameter storage as the node uses it.
pub trait ParamStore {
    /// Saves the persistent entries of `area`; the rest of a valid stored block is kept.
    fn save(&mut self, od: &dyn DictionaryImage, area: Area) -> Result<(), StoreError>;
    /// Loads the stored entries of `area` into `od`; `Ok(false)` if nothing valid is stored.
    fn load(&mut self, od: &mut dyn DictionaryImage, area: Area) -> Result<bool, StoreError>;
    /// Invalidates the stored block, so the next reset uses the spec defaults (1011h).
    fn erase(&mut self) -> Result<(), StoreError>;
}

/// The object-safe part of [`Dictionary`] that storing needs.
pub trait DictionaryImage {
    fn size(&self) -> usize;
    fn save_area(&self, area: Area, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool;
    fn load_area(&mut self, area: Area, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool;
}

impl<D: Dictionary> DictionaryImage for D {
    fn size(&self) -> usize {
        D::PERSISTENT_SIZE
    }
    fn save_area(&self, area: Area, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
        Dictionary::save_area(self, area, sink)
    }
    fn load_area(&mut self, area: Area, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
        Dictionary::load_area(self, area, source)
    }
}

/// No parameter storage: saving fails with a hardware abort, nothing is ever loaded.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoStore;

impl ParamStore for NoStore {
    fn save(&mut self, _: &dyn DictionaryImage, _: Area) -> Result<(), StoreError> {
        Err(StoreError::Device)
    }
    fn load(&mut self, _: &mut dyn DictionaryImage, _: Area) -> Result<bool, StoreError> {
        Ok(false)
    }
    fn erase(&mut self) -> Result<(), StoreError> {
        Ok(())
    }
}

/// The parameter block on an `embedded-storage` device, from byte `base` on.
#[derive(Debug)]
pub struct BlockStore<S> {
    storage: S,
    base: u32,
}

impl<S: Storage> BlockStore<S> {
    pub const fn new(storage: S, base: u32) -> Self {
        BlockStore { storage, base }
    }

    pub fn storage(&self) -> &S {
        &self.storage
    }

    pub fn into_inner(self) -> S {
        self.storage
    }

    fn data_at(&self, offset: usize) -> Option<u32> {
        self.base.checked_add(HEADER)?.checked_add(u32::try_from(offset).ok()?)
    }

    /// Magic, length and CRC; a header whose reserved bytes are not zero reads as no magic.
    fn header(&mut self) -> Result<([u8; 4], u32, u16), StoreError> {
        let mut h = [0_u8; HEADER as usize];
        self.storage.read(self.base, &mut h).map_err(|_| StoreError::Device)?;
        let [m0, m1, m2, m3, l0, l1, l2, l3, c0, c1, r0, r1] = h;
        let magic = if [r0, r1] == [0, 0] { [m0, m1, m2, m3] } else { [0; 4] };
        Ok((magic, u32::from_le_bytes([l0, l1, l2, l3]), u16::from_le_bytes([c0, c1])))
    }

    /// CRC of `len` data bytes, read back in small chunks.
    fn data_crc(&mut self, len: usize) -> Result<u16, StoreError> {
        let mut crc = CRC.start();
        let mut chunk = [0_u8; 32];
        let mut at = 0;
        while at < len {
            let n = (len - at).min(chunk.len());
            let buf = chunk.get_mut(..n).ok_or(StoreError::TooSmall)?;
            self.storage.read(self.data_at(at).ok_or(StoreError::TooSmall)?, buf).map_err(|_| StoreError::Device)?;
            crc = CRC.update(crc, buf);
            at += n;
        }
        Ok(CRC.finish(crc))
    }

    /// Whether a block of `len` bytes with a matching CRC is stored.
    pub fn is_valid(&mut self, len: usize) -> Result<bool, StoreError> {
        let (magic, stored_len, crc) = self.header()?;
        if magic != MAGIC || usize::try_from(stored_len).ok() != Some(len) {
            return Ok(false);
        }
        Ok(self.data_crc(len)? == crc)
    }

    fn write_header(&mut self, magic: [u8; 4], len: usize, crc: u16) -> Result<(), StoreError> {
        let [l0, l1, l2, l3] = u32::try_from(len).map_err(|_| StoreError::TooSmall)?.to_le_bytes();
        let [c0, c1] = crc.to_le_bytes();
        let [m0, m1, m2, m3] = magic;
        self.storage.write(self.base, &[m0, m1, m2, m3, l0, l1, l2, l3, c0, c1, 0, 0]).map_err(|_| StoreError::Device)
    }
}

impl<S: Storage> ParamStore for BlockStore<S> {
    fn save(&mut self, od: &dyn DictionaryImage, area: Area) -> Result<(), StoreError> {
        let len = od.size();
        let end = self.data_at(len).ok_or(StoreError::TooSmall)?;
        if usize::try_from(end).map_err(|_| StoreError::TooSmall)? > self.storage.capacity() {
            return Err(StoreError::TooSmall);
        }
        // Without a valid block there is nothing to keep: store every area.
        let area = if self.is_valid(len)? { area } else { Area::ALL };
        self.write_header([0; 4], len, 0)?;
        let mut failed = false;
        let written = od.save_area(area, &mut |offset, image| {
            let ok = self.data_at(offset).is_some_and(|at| self.storage.write(at, image).is_ok());
            failed |= !ok;
            ok
        });
        if !written || failed {
            return Err(StoreError::Device);
        }
        let crc = self.data_crc(len)?;
        self.write_header(MAGIC, len, crc)
    }

    fn load(&mut self, od: &mut dyn DictionaryImage, area: Area) -> Result<bool, StoreError> {
        let len = od.size();
        if !self.is_valid(len)? {
            return Ok(false);
        }
        let loaded = od.load_area(area, &mut |offset, buf| self.data_at(offset).is_some_and(|at| self.storage.read(at, buf).is_ok()));
        if loaded { Ok(true) } else { Err(StoreError::Device) }
    }

    fn erase(&mut self) -> Result<(), StoreError> {
        self.write_header([0; 4], 0, 0)
    }
}
