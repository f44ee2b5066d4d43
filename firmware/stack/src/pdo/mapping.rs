//! PDO mapping entries (16xxh/1Axxh): decoding, the CiA 301 mappability checks, and packing
//! mapped values into a frame.

use super::Dir;
use crate::od::{EntryAccess, EntryInfo, SdoAbort, Table, find_run};

/// Most entries a PDO maps (one per byte of a CAN frame).
pub const MAX_MAPPED: usize = 8;

/// One mapped object, byte-aligned. It keeps the position of its entry in the dictionary's
/// table, so sending and receiving a PDO needs no lookup.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Mapped {
    /// Position in [`EntryAccess::entries`], or [`DUMMY`].
    pub run: u16,
    pub sub: u8,
    /// Bits 0..=2: bytes - 1; bits 3..=7: which copy of the run's object is mapped (see
    /// [`EntryInfo::copies`]). Every PDO caches eight of these, so they stay four bytes.
    shape: u8,
}

/// The most copies a run may describe: what [`Mapped`] has room for.
pub const MAX_COPIES: u8 = 31;

/// The `run` of a dummy entry (indices 0002h..0007h fill RPDO bytes nobody needs).
pub const DUMMY: u16 = u16::MAX;

impl Mapped {
    /// `bytes` is 1..=8 and `copy` at most [`MAX_COPIES`]; larger values are cut.
    const fn new(run: u16, copy: u8, sub: u8, bytes: u8) -> Mapped {
        Mapped { run, sub, shape: (copy << 3) | (bytes.wrapping_sub(1) & 7) }
    }

    /// Bytes in the PDO.
    pub const fn bytes(&self) -> u8 {
        (self.shape & 7) + 1
    }

    /// The mapped object's index, given its run's description.
    pub fn index(&self, info: &EntryInfo) -> u16 {
        info.index.wrapping_add(u16::from(self.shape >> 3))
    }

    /// Decodes `index << 16 | sub << 8 | bits`.
    pub const fn decode(word: u32) -> (u16, u8, u8) {
        ((word >> 16) as u16, (word >> 8) as u8, word as u8)
    }

    pub const fn is_dummy(&self) -> bool {
        self.run == DUMMY
    }

    /// The mapped entry's description.
    pub fn info<'t>(&self, entries: Table<'t>) -> Option<&'t EntryInfo> {
        entries.get(usize::from(self.run))
    }
}

/// The bytes a dummy data type (CiA 301 7.4.7.1) occupies, if it can be mapped byte-aligned.
const fn dummy_bytes(index: u16) -> Option<u8> {
    match index {
        0x0002 | 0x0005 => Some(1),
        0x0003 | 0x0006 => Some(2),
        0x0004 | 0x0007 => Some(4),
        _ => None,
    }
}

/// Checks one mapping entry against the dictionary (CiA 301 7.5.2.36): the object exists,
/// may be mapped in this direction, and the length fits its type.
pub fn check_entry(od: &impl EntryAccess, word: u32, dir: Dir) -> Result<Mapped, SdoAbort> {
    let (index, sub, bits) = Mapped::decode(word);
    if bits == 0 || bits % 8 != 0 {
        // Only byte-aligned mapping is supported.
        return Err(SdoAbort::NotMappable);
    }
    let bytes = bits / 8;
    if bytes > 8 {
        return Err(SdoAbort::PdoTooLong);
    }
    if let Some(size) = dummy_bytes(index) {
        return if dir == Dir::Rx && size == bytes && sub == 0 { Ok(Mapped::new(DUMMY, 0, sub, bytes)) } else { Err(SdoAbort::NotMappable) };
    }
    let entries = od.entries();
    let run = find_run(entries, index, sub)?;
    let e = entries.get(run).ok_or(SdoAbort::NoObject)?;
    let allowed = match dir {
        Dir::Rx => e.access().writable(),
        Dir::Tx => e.access().readable(),
    };
    if !e.pdo_mappable() || !allowed {
        return Err(SdoAbort::NotMappable);
    }
    let fits = e.takes_len(usize::from(bytes));
    let run = u16::try_from(run).map_err(|_| SdoAbort::NotMappable)?;
    // `find_run` only returns a run that covers `index`, so the copy is at most `e.copies()`.
    let copy = u8::try_from(index - e.index).map_err(|_| SdoAbort::NotMappable)?;
    if fits { Ok(Mapped::new(run, copy, sub, bytes)) } else { Err(SdoAbort::NotMappable) }
}

/// A PDO's mapping, checked and cached so that sending and receiving need no lookups of the
/// mapping object.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Mapping {
    entries: [Mapped; MAX_MAPPED],
    count: u8,
    bytes: u8,
}

impl Mapping {
    /// Checks a whole mapping: every entry, and at most 64 bits in total.
    pub fn check(od: &impl EntryAccess, words: &[u32], dir: Dir) -> Result<Mapping, SdoAbort> {
        let mut m = Mapping::default();
        for &w in words {
            let e = check_entry(od, w, dir)?;
            let total = m.bytes.saturating_add(e.bytes());
            if total > 8 {
                return Err(SdoAbort::PdoTooLong);
            }
            let slot = m.entries.get_mut(usize::from(m.count)).ok_or(SdoAbort::PdoTooLong)?;
            *slot = e;
            m.count += 1;
            m.bytes = total;
        }
        Ok(m)
    }

    pub fn entries(&self) -> &[Mapped] {
        self.entries.get(..usize::from(self.count)).unwrap_or(&[])
    }

    /// Mapped length in bytes.
    pub const fn len(&self) -> u8 {
        self.bytes
    }

    pub const fn is_empty(&self) -> bool {
        self.count == 0
    }

    pub fn contains(&self, entries: Table<'_>, index: u16, sub: u8) -> bool {
        self.entries().iter().any(|e| e.sub == sub && e.info(entries).is_some_and(|i| e.index(i) == index))
    }

    /// Reads the mapped values into a frame payload: its bytes (zero from the mapped length
    /// on) and the mapped length.
    pub fn pack(&self, od: &mut impl EntryAccess) -> Result<([u8; 8], u8), SdoAbort> {
        let entries = od.entries();
        // Zeroed once here, not per entry: an 8-byte store instead of a fill per entry.
        let mut out = [0_u8; 8];
        let mut at = 0;
        for e in self.entries() {
            let end = at + usize::from(e.bytes());
            let dst = out.get_mut(at..end).ok_or(SdoAbort::PdoTooLong)?;
            if e.is_dummy() {
                // Only RPDOs map dummies; their bytes read as zero (CO401GW1's `4P`).
                at = end;
                continue;
            }
            let info = e.info(entries).ok_or(SdoAbort::NoObject)?;
            od.read_entry(info, e.index(info), e.sub, 0, dst)?;
            at = end;
        }
        // At most 8: `out.get_mut(..end)` succeeded.
        Ok((out, at as u8))
    }
}
