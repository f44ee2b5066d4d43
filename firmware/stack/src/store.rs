//! The parameter block of 1010h/1011h on any `embedded-storage` device (EEPROM, flash
//! emulation, a file on a PC).
//!
//! A ring of slots (two, or as many as the storage holds up to [`MAX_SLOTS`]), each a header
//! (magic "CFG1", block length u32 LE, CRC-16/XMODEM u16 LE, sequence number u16 LE) and the
//! data as [`NodeDictionary::save_area`] lays it out. The CRC covers length, sequence and
//! data. A save writes the slot after the one holding the newest valid block, and its header
//! last, so a save torn by a reset or a storage error leaves the previous block in place; the
//! ring spreads the writes over every slot, so that a device which saves on every write
//! (CR3101's automatic save) wears each cell once per ring turn, not once per write. A save
//! that would store what the newest block already holds writes nothing. A slot whose magic,
//! length or CRC does not match is ignored; with no valid slot the node keeps the spec
//! defaults instead of loading garbage. Restoring the defaults (1011h) writes an erase marker
//! (magic "CFGE", no data) into the next slot: one write, however many slots there are.

use crate::od::{Area, NodeDictionary};
use coforge_link::crc::{Crc16, XMODEM};
use embedded_storage::Storage;

const MAGIC: [u8; 4] = *b"CFG1";
/// A block that says "nothing stored": the defaults were restored.
const ERASED: [u8; 4] = *b"CFGE";
const HEADER: u32 = 12;
/// The most slots a store uses: every one is read at power-on.
pub const MAX_SLOTS: u32 = 16;
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
    fn erase(&mut self, od: &dyn DictionaryImage) -> Result<(), StoreError>;
}

/// The object-safe part of [`NodeDictionary`] that storing needs.
pub trait DictionaryImage {
    fn size(&self) -> usize;
    fn save_area(&self, area: Area, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool;
    fn load_area(&mut self, area: Area, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool;
}

impl<D: NodeDictionary> DictionaryImage for D {
    fn size(&self) -> usize {
        D::PERSISTENT_SIZE
    }
    fn save_area(&self, area: Area, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
        NodeDictionary::save_area(self, area, sink)
    }
    fn load_area(&mut self, area: Area, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
        NodeDictionary::load_area(self, area, source)
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
    fn erase(&mut self, _: &dyn DictionaryImage) -> Result<(), StoreError> {
        Ok(())
    }
}

/// The parameter block on an `embedded-storage` device, from byte `base` on.
#[derive(Debug)]
pub struct BlockStore<S> {
    storage: S,
    base: u32,
}

/// The slot holding the newest valid block, and whether that block is an erase marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Newest {
    slot: u32,
    seq: u16,
    erased: bool,
}

impl<S: Storage> BlockStore<S> {
    pub const fn new(storage: S, base: u32) -> Self {
        BlockStore { storage, base }
    }

    /// Bytes of storage the two slots of a `len`-byte block take.
    pub const fn capacity_for(len: usize) -> usize {
        Self::capacity_for_slots(len, 2)
    }

    /// Bytes of storage `slots` slots of a `len`-byte block take (a store uses as many slots
    /// as its storage holds, up to [`MAX_SLOTS`]).
    pub const fn capacity_for_slots(len: usize, slots: u32) -> usize {
        slots as usize * (HEADER as usize + len)
    }

    /// The slots a `len`-byte block has: as many as fit after `base`, at most [`MAX_SLOTS`].
    fn slots(&self, len: usize) -> u32 {
        let size = HEADER as usize + len;
        let room = self.storage.capacity().saturating_sub(self.base as usize) / size;
        u32::try_from(room).unwrap_or(MAX_SLOTS).min(MAX_SLOTS)
    }

    pub fn storage(&self) -> &S {
        &self.storage
    }

    pub fn into_inner(self) -> S {
        self.storage
    }

    /// Where slot `slot` of a `len`-byte block starts.
    fn slot_at(&self, slot: u32, len: usize) -> Result<u32, StoreError> {
        let size = HEADER.checked_add(u32::try_from(len).map_err(|_| StoreError::TooSmall)?).ok_or(StoreError::TooSmall)?;
        self.base.checked_add(slot * size).ok_or(StoreError::TooSmall)
    }

    /// Magic, length, CRC and sequence number of the slot at `at`.
    fn header(&mut self, at: u32) -> Result<([u8; 4], u32, u16, u16), StoreError> {
        let mut h = [0_u8; HEADER as usize];
        self.storage.read(at, &mut h).map_err(|_| StoreError::Device)?;
        let [m0, m1, m2, m3, l0, l1, l2, l3, c0, c1, s0, s1] = h;
        Ok(([m0, m1, m2, m3], u32::from_le_bytes([l0, l1, l2, l3]), u16::from_le_bytes([c0, c1]), u16::from_le_bytes([s0, s1])))
    }

    /// CRC of length, sequence number and the `len` data bytes of the slot at `at`, read
    /// back in small chunks.
    fn slot_crc(&mut self, at: u32, len: usize, seq: u16) -> Result<u16, StoreError> {
        let len32 = u32::try_from(len).map_err(|_| StoreError::TooSmall)?;
        let mut crc = CRC.update(CRC.update(CRC.start(), &len32.to_le_bytes()), &seq.to_le_bytes());
        let mut chunk = [0_u8; 32];
        let mut done = 0;
        while done < len {
            let n = (len - done).min(chunk.len());
            let buf = chunk.get_mut(..n).ok_or(StoreError::TooSmall)?;
            self.storage.read(data_at(at, done)?, buf).map_err(|_| StoreError::Device)?;
            crc = CRC.update(crc, buf);
            done += n;
        }
        Ok(CRC.finish(crc))
    }

    /// The slot's block, if it holds a valid `len`-byte block or an erase marker.
    fn valid(&mut self, slot: u32, len: usize) -> Result<Option<Newest>, StoreError> {
        let at = self.slot_at(slot, len)?;
        let (magic, stored_len, crc, seq) = self.header(at)?;
        let valid = match magic {
            MAGIC => usize::try_from(stored_len).ok() == Some(len) && self.slot_crc(at, len, seq)? == crc,
            ERASED => stored_len == 0 && self.slot_crc(at, 0, seq)? == crc,
            _ => false,
        };
        Ok(valid.then_some(Newest { slot, seq, erased: magic == ERASED }))
    }

    /// The slot with the newest valid block (sequence numbers compared with wrap-around: the
    /// ring's valid blocks hold at most [`MAX_SLOTS`] consecutive numbers).
    fn newest(&mut self, len: usize) -> Result<Option<Newest>, StoreError> {
        let mut newest: Option<Newest> = None;
        for slot in 0..self.slots(len) {
            if let Some(b) = self.valid(slot, len)? {
                newest = match newest {
                    Some(a) if b.seq.wrapping_sub(a.seq) as i16 <= 0 => Some(a),
                    _ => Some(b),
                };
            }
        }
        Ok(newest)
    }

    /// Whether a valid block of `len` bytes is stored.
    pub fn is_valid(&mut self, len: usize) -> Result<bool, StoreError> {
        Ok(self.newest(len)?.is_some_and(|n| !n.erased))
    }

    /// Whether the newest block `newest` already holds what `od` would save of `area`.
    fn holds(&mut self, newest: Newest, od: &dyn DictionaryImage, area: Area) -> Result<bool, StoreError> {
        let from = self.slot_at(newest.slot, od.size())?;
        let mut stored = [0_u8; GATHER];
        let storage = &mut self.storage;
        let same = od.save_area(area, &mut |offset, image| {
            // Compared a chunk at a time; any difference ends the walk.
            image.chunks(GATHER).enumerate().all(|(i, piece)| {
                let at = data_at(from, offset + i * GATHER);
                let buf = stored.get_mut(..piece.len());
                match (at, buf) {
                    (Ok(at), Some(buf)) => storage.read(at, buf).is_ok() && buf == piece,
                    _ => false,
                }
            })
        });
        Ok(same)
    }

    fn write_header(&mut self, at: u32, magic: [u8; 4], len: usize, crc: u16, seq: u16) -> Result<(), StoreError> {
        let [l0, l1, l2, l3] = u32::try_from(len).map_err(|_| StoreError::TooSmall)?.to_le_bytes();
        let [c0, c1] = crc.to_le_bytes();
        let [s0, s1] = seq.to_le_bytes();
        let [m0, m1, m2, m3] = magic;
        self.storage.write(at, &[m0, m1, m2, m3, l0, l1, l2, l3, c0, c1, s0, s1]).map_err(|_| StoreError::Device)
    }

    /// Copies the data of one slot into the other, in small chunks.
    fn copy_data(&mut self, from: u32, to: u32, len: usize) -> Result<(), StoreError> {
        let mut chunk = [0_u8; 32];
        let mut done = 0;
        while done < len {
            let n = (len - done).min(chunk.len());
            let buf = chunk.get_mut(..n).ok_or(StoreError::TooSmall)?;
            self.storage.read(data_at(from, done)?, buf).map_err(|_| StoreError::Device)?;
            self.storage.write(data_at(to, done)?, buf).map_err(|_| StoreError::Device)?;
            done += n;
        }
        Ok(())
    }
}

/// Bytes a save gathers into one storage write.
const GATHER: usize = 32;

/// Consecutive pieces of a block being saved, written together once the next piece does not
/// follow them or does not fit.
struct Gather<'a, S> {
    storage: &'a mut S,
    /// Where the gathered bytes go, and how many there are.
    at: u32,
    len: usize,
    buf: [u8; GATHER],
    /// A write failed.
    failed: bool,
}

impl<S: Storage> Gather<'_, S> {
    /// Takes the piece `bytes` for `at`; `false` once a write has failed.
    fn put(&mut self, at: u32, bytes: &[u8]) -> bool {
        let follows = u32::try_from(self.len).ok().and_then(|len| self.at.checked_add(len)) == Some(at);
        match self.buf.get_mut(self.len..self.len + bytes.len()) {
            Some(dst) if follows => dst.copy_from_slice(bytes),
            _ => {
                self.flush();
                match self.buf.get_mut(..bytes.len()) {
                    Some(dst) => dst.copy_from_slice(bytes),
                    // Longer than the buffer: written as it is.
                    None => {
                        self.failed |= self.storage.write(at, bytes).is_err();
                        return !self.failed;
                    }
                }
                self.at = at;
            }
        }
        self.len += bytes.len();
        !self.failed
    }

    /// Writes what is gathered.
    fn flush(&mut self) {
        if let Some(bytes) = self.buf.get(..self.len).filter(|b| !b.is_empty()) {
            self.failed |= self.storage.write(self.at, bytes).is_err();
        }
        self.len = 0;
    }
}

/// Where byte `offset` of the data of the slot at `slot_at` lives.
fn data_at(slot_at: u32, offset: usize) -> Result<u32, StoreError> {
    slot_at.checked_add(HEADER).and_then(|d| d.checked_add(u32::try_from(offset).ok()?)).ok_or(StoreError::TooSmall)
}

impl<S: Storage> ParamStore for BlockStore<S> {
    fn save(&mut self, od: &dyn DictionaryImage, area: Area) -> Result<(), StoreError> {
        let len = od.size();
        let slots = self.slots(len);
        if slots < 2 {
            return Err(StoreError::TooSmall);
        }
        let newest = self.newest(len)?;
        if let Some(n) = newest.filter(|n| !n.erased)
            && self.holds(n, od, area)?
        {
            // Nothing changed: nothing is written (a master writing the same configuration
            // at every start wears nothing).
            return Ok(());
        }
        let target_slot = newest.map_or(0, |n| (n.slot + 1) % slots);
        let target = self.slot_at(target_slot, len)?;
        // The newest block stays valid until the new header is written.
        self.write_header(target, [0; 4], len, 0, 0)?;
        let area = match newest {
            // Only some areas change: start from the newest block's contents.
            Some(n) if area != Area::ALL && !n.erased => {
                let from = self.slot_at(n.slot, len)?;
                self.copy_data(from, target, len)?;
                area
            }
            // Without a valid block there is nothing to keep: store every area.
            _ => Area::ALL,
        };
        // The entries' images come a few bytes at a time: gathered into writes of up to
        // `GATHER` bytes, so an EEPROM spends one write cycle (some 5 ms) per gathered piece,
        // not one per entry (a 541-byte block of 272 entries took 1.4 s).
        let mut gather = Gather { storage: &mut self.storage, at: 0, len: 0, buf: [0; GATHER], failed: false };
        let written = od.save_area(area, &mut |offset, image| data_at(target, offset).is_ok_and(|at| gather.put(at, image)));
        gather.flush();
        if !written || gather.failed {
            return Err(StoreError::Device);
        }
        let seq = newest.map_or(1, |n| n.seq.wrapping_add(1));
        let crc = self.slot_crc(target, len, seq)?;
        self.write_header(target, MAGIC, len, crc, seq)
    }

    fn load(&mut self, od: &mut dyn DictionaryImage, area: Area) -> Result<bool, StoreError> {
        let len = od.size();
        let Some(newest) = self.newest(len)?.filter(|n| !n.erased) else { return Ok(false) };
        let from = self.slot_at(newest.slot, len)?;
        let loaded = od.load_area(area, &mut |offset, buf| data_at(from, offset).is_ok_and(|at| self.storage.read(at, buf).is_ok()));
        if loaded { Ok(true) } else { Err(StoreError::Device) }
    }

    fn erase(&mut self, od: &dyn DictionaryImage) -> Result<(), StoreError> {
        let len = od.size();
        let slots = self.slots(len);
        match self.newest(len)? {
            None => Ok(()),
            Some(n) if n.erased => Ok(()),
            Some(n) => {
                // The marker goes into the next slot; the block stays valid until it is written.
                let seq = n.seq.wrapping_add(1);
                let at = self.slot_at((n.slot + 1) % slots.max(1), len)?;
                self.write_header(at, [0; 4], 0, 0, 0)?;
                let crc = self.slot_crc(at, 0, seq)?;
                self.write_header(at, ERASED, 0, crc, seq)
            }
        }
    }
}
