//! Two slots for binary EDS files on any `embedded-storage` device, so that a download never
//! overwrites the configuration in use.
//!
//! Each slot is a header (magic "BEDS", sequence number u32 LE, file length u32 LE, the file's
//! own CRC u16 LE, 2 bytes 0) and room for [`FILE_MAX`] bytes. A download first clears the
//! header of the slot not in use, then streams the file behind it, and writes the header only
//! once the whole file was checked: a download cut by a reset or a power loss leaves a slot
//! without a header, and the previous file stays the active one.
//!
//! The memory is read in place ([`MappedStorage`]: an MCU's flash, the RAM image of an EEPROM
//! or a host file): a file is checked and applied where it is stored, never copied, so loading
//! one costs no RAM.

use embedded_storage::Storage;

/// The largest binary EDS a slot holds (coforge's own export of this spec is about 6 KB, the
/// vendor's examples 2.4 KB).
pub const FILE_MAX: usize = 8 * 1024;
const MAGIC: [u8; 4] = *b"BEDS";
const HEADER: usize = 16;
const SLOT: usize = HEADER + FILE_MAX;

/// Why the configuration memory failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlotError {
    /// The storage device reported an error, or it is smaller than two slots.
    Device,
    /// The file is longer than a slot.
    TooLong,
}

/// Storage whose bytes can be read in place.
pub trait MappedStorage: Storage {
    /// Every byte of the storage.
    fn mapped(&self) -> &[u8];
}

/// A slot's header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Header {
    sequence: u32,
    len: u32,
    crc: u16,
}

impl Header {
    fn encode(self) -> [u8; HEADER] {
        let mut b = [0_u8; HEADER];
        b[..4].copy_from_slice(&MAGIC);
        b[4..8].copy_from_slice(&self.sequence.to_le_bytes());
        b[8..12].copy_from_slice(&self.len.to_le_bytes());
        b[12..14].copy_from_slice(&self.crc.to_le_bytes());
        b
    }

    fn decode(b: &[u8; HEADER]) -> Option<Header> {
        let [m0, m1, m2, m3, s0, s1, s2, s3, l0, l1, l2, l3, c0, c1, ..] = *b;
        let len = u32::from_le_bytes([l0, l1, l2, l3]);
        ([m0, m1, m2, m3] == MAGIC && len as usize <= FILE_MAX).then_some(Header {
            sequence: u32::from_le_bytes([s0, s1, s2, s3]),
            len,
            crc: u16::from_le_bytes([c0, c1]),
        })
    }
}

/// The two slots, on storage `M`.
#[derive(Debug)]
pub struct ConfigSlots<M> {
    storage: M,
    /// The slot a download is writing to.
    writing: Option<usize>,
}

impl<M: MappedStorage> ConfigSlots<M> {
    /// Bytes of storage two slots take.
    pub const CAPACITY: usize = 2 * SLOT;

    pub fn new(storage: M) -> Self {
        ConfigSlots { storage, writing: None }
    }

    pub fn storage(&self) -> &M {
        &self.storage
    }

    fn header(&self, slot: usize) -> Option<Header> {
        let at = slot * SLOT;
        Header::decode(self.storage.mapped().get(at..at + HEADER)?.try_into().ok()?)
    }

    /// The slot of the newest complete file, and its header.
    fn newest(&self) -> Option<(usize, Header)> {
        let a = self.header(0).map(|h| (0, h));
        let b = self.header(1).map(|h| (1, h));
        match (a, b) {
            (Some(a), Some(b)) => Some(if b.1.sequence.wrapping_sub(a.1.sequence) as i32 > 0 { b } else { a }),
            (a, b) => a.or(b),
        }
    }

    /// The active file, or `None` if no file was ever stored.
    pub fn active(&self) -> Option<&[u8]> {
        let (slot, header) = self.newest()?;
        self.file(slot, header.len as usize)
    }

    fn file(&self, slot: usize, len: usize) -> Option<&[u8]> {
        let at = slot * SLOT + HEADER;
        self.storage.mapped().get(at..at + len)
    }

    /// Starts a download into the slot not in use: its header is cleared first.
    pub fn begin(&mut self) -> Result<(), SlotError> {
        let slot = self.newest().map_or(0, |(slot, _)| 1 - slot);
        self.writing = None;
        self.storage.write((slot * SLOT) as u32, &[0; HEADER]).map_err(|_| SlotError::Device)?;
        self.writing = Some(slot);
        Ok(())
    }

    /// The bytes at `offset` of the file being downloaded.
    pub fn write(&mut self, offset: usize, data: &[u8]) -> Result<(), SlotError> {
        let slot = self.writing.ok_or(SlotError::Device)?;
        if offset.saturating_add(data.len()) > FILE_MAX {
            return Err(SlotError::TooLong);
        }
        self.storage.write((slot * SLOT + HEADER + offset) as u32, data).map_err(|_| SlotError::Device)
    }

    /// The downloaded file (`len` bytes) as stored, to be checked.
    pub fn downloaded(&self, len: usize) -> Option<&[u8]> {
        self.file(self.writing?, len)
    }

    /// The downloaded file of `len` bytes becomes the active one: its header is written.
    pub fn commit(&mut self, len: usize, crc: u16) -> Result<(), SlotError> {
        let slot = self.writing.take().ok_or(SlotError::Device)?;
        let sequence = self.newest().map_or(0, |(_, h)| h.sequence.wrapping_add(1));
        let header = Header { sequence, len: len as u32, crc };
        self.storage.write((slot * SLOT) as u32, &header.encode()).map_err(|_| SlotError::Device)
    }

    /// The download ended without a file: its slot keeps no header.
    pub fn discard(&mut self) {
        self.writing = None;
    }
}

impl<M: MappedStorage> ConfigSlots<M> {
    /// No file any more (1F51h.1 = 3, clear): both headers are cleared.
    pub fn clear(&mut self) -> Result<(), SlotError> {
        self.writing = None;
        for slot in 0..2 {
            self.storage.write((slot * SLOT) as u32, &[0; HEADER]).map_err(|_| SlotError::Device)?;
        }
        Ok(())
    }
}

/// No configuration memory: a coprocessor that cannot load files (every download fails
/// with a hardware abort), for runtimes that give it none.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoMemory;

impl embedded_storage::ReadStorage for NoMemory {
    type Error = SlotError;
    fn read(&mut self, _: u32, _: &mut [u8]) -> Result<(), SlotError> {
        Err(SlotError::Device)
    }
    fn capacity(&self) -> usize {
        0
    }
}

impl Storage for NoMemory {
    fn write(&mut self, _: u32, _: &[u8]) -> Result<(), SlotError> {
        Err(SlotError::Device)
    }
}

impl MappedStorage for NoMemory {
    fn mapped(&self) -> &[u8] {
        &[]
    }
}
