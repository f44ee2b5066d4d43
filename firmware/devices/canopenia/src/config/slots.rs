//! Two slots for binary EDS files on the coprocessor's configuration memory, so that a download
//! never overwrites the configuration in use.
//!
//! Each slot is [`SLOT`] bytes: a header (magic "BEDS", sequence number u32 LE, file length u32
//! LE, the file's own CRC u16 LE, 2 bytes 0xFF) and the file. A download first erases the slot
//! not in use, then streams the file behind its header, and writes the header only once the
//! whole file was checked: a download cut by a reset or a power loss leaves a slot without a
//! header, and the previous file stays the active one.
//!
//! The memory may be MCU flash ([`ConfigMemory`]): every byte is written once after an erase,
//! in aligned blocks of [`WRITE_BLOCK`] bytes, and is read in place, so a file is checked and
//! applied where it is stored, never copied into RAM.

use embedded_storage::Storage;

/// A slot: 8 KiB, whole erase pages of any STM32F0 (1 or 2 KiB).
pub const SLOT: usize = 8 * 1024;
const HEADER: usize = 16;
/// The largest binary EDS a slot holds (coforge's own export of this spec is 7.9 KB, the
/// vendor's examples 2.4 KB).
pub const FILE_MAX: usize = SLOT - HEADER;
/// Writes go out in aligned blocks of this many bytes (a multiple of any flash's program unit).
pub const WRITE_BLOCK: usize = 8;
const MAGIC: [u8; 4] = *b"BEDS";
const ERASED: u8 = 0xFF;

/// The memory configuration files live in.
pub trait ConfigMemory: Storage {
    /// Every byte, read in place.
    fn mapped(&self) -> &[u8];
    /// Sets `len` bytes from `offset` to 0xFF (a flash erase; both are multiples of [`SLOT`]).
    fn erase(&mut self, offset: u32, len: u32) -> Result<(), Self::Error>;
}

/// Why the configuration memory failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SlotError {
    /// The storage device reported an error, or it is smaller than two slots.
    Device,
    /// The file is longer than a slot holds.
    TooLong,
    /// A part that does not follow the previous one (a download streams in order).
    OutOfOrder,
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
        let [m0, m1, m2, m3] = MAGIC;
        let [s0, s1, s2, s3] = self.sequence.to_le_bytes();
        let [l0, l1, l2, l3] = self.len.to_le_bytes();
        let [c0, c1] = self.crc.to_le_bytes();
        [m0, m1, m2, m3, s0, s1, s2, s3, l0, l1, l2, l3, c0, c1, ERASED, ERASED]
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

/// The download being written: its slot, and the bytes not yet written as a whole block.
#[derive(Debug, Clone, Copy)]
struct Writing {
    slot: usize,
    /// File bytes received so far.
    len: usize,
    block: [u8; WRITE_BLOCK],
    /// The last, partial block was written: the file is complete.
    ended: bool,
}

/// The two slots, on memory `M`.
#[derive(Debug)]
pub struct ConfigSlots<M> {
    memory: M,
    writing: Option<Writing>,
}

impl<M: ConfigMemory> ConfigSlots<M> {
    /// Bytes of memory two slots take.
    pub const CAPACITY: usize = 2 * SLOT;

    pub fn new(memory: M) -> Self {
        ConfigSlots { memory, writing: None }
    }

    pub fn memory(&self) -> &M {
        &self.memory
    }

    pub fn into_memory(self) -> M {
        self.memory
    }

    fn header(&self, slot: usize) -> Option<Header> {
        let at = slot * SLOT;
        Header::decode(self.memory.mapped().get(at..at + HEADER)?.try_into().ok()?)
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
        self.memory.mapped().get(at..at + len)
    }

    /// Starts a download into the slot not in use, which is erased first.
    pub fn begin(&mut self) -> Result<(), SlotError> {
        let slot = self.newest().map_or(0, |(slot, _)| 1 - slot);
        self.writing = None;
        self.memory.erase((slot * SLOT) as u32, SLOT as u32).map_err(|_| SlotError::Device)?;
        self.writing = Some(Writing { slot, len: 0, block: [ERASED; WRITE_BLOCK], ended: false });
        Ok(())
    }

    /// The bytes at `offset` of the file being downloaded (right after the previous ones).
    pub fn write(&mut self, offset: usize, data: &[u8]) -> Result<(), SlotError> {
        let mut w = self.writing.ok_or(SlotError::Device)?;
        if offset != w.len || w.ended {
            return Err(SlotError::OutOfOrder);
        }
        if offset.saturating_add(data.len()) > FILE_MAX {
            return Err(SlotError::TooLong);
        }
        for &byte in data {
            if let Some(b) = w.block.get_mut(w.len % WRITE_BLOCK) {
                *b = byte;
            }
            w.len += 1;
            if w.len % WRITE_BLOCK == 0 {
                self.write_block(&mut w)?;
            }
        }
        self.writing = Some(w);
        Ok(())
    }

    /// The block the file's bytes up to `w.len` end in, written and started afresh.
    fn write_block(&mut self, w: &mut Writing) -> Result<(), SlotError> {
        let start = (w.len - 1) / WRITE_BLOCK * WRITE_BLOCK;
        let at = w.slot * SLOT + HEADER + start;
        let block = core::mem::replace(&mut w.block, [ERASED; WRITE_BLOCK]);
        self.memory.write(at as u32, &block).map_err(|_| SlotError::Device)
    }

    /// The downloaded file, its last block written out, as stored: to be checked.
    pub fn downloaded(&mut self) -> Option<&[u8]> {
        let mut w = self.writing?;
        if w.len % WRITE_BLOCK != 0 && !w.ended {
            // The block's rest stays erased.
            self.write_block(&mut w).ok()?;
        }
        w.ended = true;
        self.writing = Some(w);
        self.file(w.slot, w.len)
    }

    /// The downloaded file of `len` bytes becomes the active one: its header is written.
    pub fn commit(&mut self, len: usize, crc: u16) -> Result<(), SlotError> {
        let w = self.writing.take().ok_or(SlotError::Device)?;
        let sequence = self.newest().map_or(0, |(_, h)| h.sequence.wrapping_add(1));
        let header = Header { sequence, len: len as u32, crc };
        self.memory.write((w.slot * SLOT) as u32, &header.encode()).map_err(|_| SlotError::Device)
    }

    /// The download ended without a file: its slot keeps no header.
    pub fn discard(&mut self) {
        self.writing = None;
    }

    /// No file any more (1F51h.1 = 3, clear): both slots are erased.
    pub fn clear(&mut self) -> Result<(), SlotError> {
        self.writing = None;
        self.memory.erase(0, Self::CAPACITY as u32).map_err(|_| SlotError::Device)
    }
}

/// A RAM image (an EEPROM's, a test's) as configuration memory.
impl<B: AsRef<[u8]> + AsMut<[u8]>> ConfigMemory for coforge_storage::ram::RamEeprom<B> {
    fn mapped(&self) -> &[u8] {
        self.as_bytes()
    }

    fn erase(&mut self, offset: u32, len: u32) -> Result<(), Self::Error> {
        let start = offset as usize;
        self.as_bytes_mut().get_mut(start..start + len as usize).ok_or(coforge_storage::ram::OutOfBounds)?.fill(ERASED);
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

impl ConfigMemory for NoMemory {
    fn mapped(&self) -> &[u8] {
        &[]
    }
    fn erase(&mut self, _: u32, _: u32) -> Result<(), SlotError> {
        Err(SlotError::Device)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec;

    /// Flash as an MCU has it: erase sets 0xFF, a write may only program erased bytes, in
    /// aligned blocks of `WRITE_BLOCK`.
    #[derive(Debug)]
    struct Flash {
        bytes: std::vec::Vec<u8>,
        erases: usize,
    }

    impl embedded_storage::ReadStorage for Flash {
        type Error = SlotError;
        fn read(&mut self, offset: u32, out: &mut [u8]) -> Result<(), SlotError> {
            out.copy_from_slice(&self.bytes[offset as usize..offset as usize + out.len()]);
            Ok(())
        }
        fn capacity(&self) -> usize {
            self.bytes.len()
        }
    }

    impl Storage for Flash {
        fn write(&mut self, offset: u32, data: &[u8]) -> Result<(), SlotError> {
            let at = offset as usize;
            assert_eq!(at % WRITE_BLOCK, 0, "aligned");
            assert_eq!(data.len() % WRITE_BLOCK, 0, "whole blocks");
            let cells = &mut self.bytes[at..at + data.len()];
            assert!(cells.iter().all(|&b| b == ERASED), "programs erased bytes only, at {at}");
            cells.copy_from_slice(data);
            Ok(())
        }
    }

    impl ConfigMemory for Flash {
        fn mapped(&self) -> &[u8] {
            &self.bytes
        }
        fn erase(&mut self, offset: u32, len: u32) -> Result<(), SlotError> {
            assert_eq!((offset as usize % SLOT, len as usize % SLOT), (0, 0), "whole slots");
            self.bytes[offset as usize..(offset + len) as usize].fill(ERASED);
            self.erases += 1;
            Ok(())
        }
    }

    fn download(slots: &mut ConfigSlots<Flash>, file: &[u8], part: usize) {
        slots.begin().unwrap();
        for (i, chunk) in file.chunks(part).enumerate() {
            slots.write(i * part, chunk).unwrap();
        }
    }

    #[test]
    fn files_alternate_between_the_slots_and_program_flash_only_where_erased() {
        let mut slots = ConfigSlots::new(Flash { bytes: vec![0; ConfigSlots::<Flash>::CAPACITY], erases: 0 });
        assert_eq!(slots.active(), None, "never-erased memory holds no file");
        for (n, len) in [(1_u8, 2217), (2, 7), (3, FILE_MAX), (4, 9)] {
            let file: std::vec::Vec<u8> = (0..len).map(|i| (i as u8).wrapping_mul(n)).collect();
            // Segments of 7 bytes, as a segmented SDO download brings them.
            download(&mut slots, &file, 7);
            assert_eq!(slots.downloaded(), Some(&file[..]));
            assert_ne!(slots.active(), Some(&file[..]), "not active before the commit");
            slots.commit(len, 0).unwrap();
            assert_eq!(slots.active(), Some(&file[..]));
        }
        assert_eq!(slots.memory().erases, 4);
    }

    #[test]
    fn a_cut_download_leaves_the_active_file_and_out_of_order_parts_are_refused() {
        let mut slots = ConfigSlots::new(Flash { bytes: vec![ERASED; ConfigSlots::<Flash>::CAPACITY], erases: 0 });
        let first = [1_u8; 100];
        download(&mut slots, &first, 7);
        slots.downloaded();
        slots.commit(first.len(), 0).unwrap();
        download(&mut slots, &[2; 50], 7);
        slots.discard();
        assert_eq!(slots.active(), Some(&first[..]));
        slots.begin().unwrap();
        assert_eq!(slots.write(7, &[0; 7]), Err(SlotError::OutOfOrder));
        assert_eq!(slots.write(0, &[0; FILE_MAX + 1]), Err(SlotError::TooLong));
        slots.clear().unwrap();
        assert_eq!(slots.active(), None);
    }
}
