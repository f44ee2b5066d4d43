//! The dictionary's stored values as one byte image, and every access to it.
//!
//! A generated dictionary keeps its RAM and persistent entries in one `#[repr(C)]` struct of
//! little-endian, byte-aligned fields (zerocopy's byte-order types, [`Bytes`](crate::value::Bytes),
//! [`Array`](crate::value::Array)): typed fields for the device's code, and at the same time a
//! byte image laid out exactly as CANopen transfers its values. Each [`EntryInfo`] carries the
//! offset of its first sub-index in that image, so one piece of code here reads, writes,
//! resets, saves and loads every entry of every device, where the generated code used to
//! dispatch to a field per object (CANopenNode's `OD_entry_t` pointing into `OD_RAM` is the
//! same idea).
//!
//! A value's place: `offset + (sub - first sub) * stride`, the stride being the entry's size,
//! plus 2 for strings and domains, which keep their length in the 2 bytes before their data.
//! Nothing here panics on any offset or sub-index: a place outside the image is `NoSubIndex`.

use super::{EntryInfo, ReadLen, SdoAbort, read_slice};
use coforge_types::DataType;
use core::ops::Range;

/// Bytes before the data of a string or domain: its length, little-endian.
const LEN_BYTES: usize = 2;

/// Bytes one sub-index of `info` takes in the image.
pub const fn stride(info: &EntryInfo) -> usize {
    info.size as usize + if info.is_variable_length() { LEN_BYTES } else { 0 }
}

/// Where `sub` of the run `info` lives in an image of `len` bytes.
fn place(info: &EntryInfo, sub: u8, len: usize) -> Result<Range<usize>, SdoAbort> {
    let n = usize::from(sub.checked_sub(info.sub).ok_or(SdoAbort::NoSubIndex)?);
    let start = usize::from(info.offset) + n * stride(info);
    let end = start + stride(info);
    if sub > info.last_sub || end > len { Err(SdoAbort::NoSubIndex) } else { Ok(start..end) }
}

/// The stored value of `sub` (a string or domain: its current length).
fn value<'a>(image: &'a [u8], info: &EntryInfo, sub: u8) -> Result<&'a [u8], SdoAbort> {
    let slot = image.get(place(info, sub, image.len())?).ok_or(SdoAbort::NoSubIndex)?;
    if !info.is_variable_length() {
        return Ok(slot);
    }
    let (len, data) = slot.split_at_checked(LEN_BYTES).ok_or(SdoAbort::NoSubIndex)?;
    let len = len.first().map_or(0, |&l| usize::from(l)) | len.get(1).map_or(0, |&h| usize::from(h) << 8);
    // A length beyond the entry (a corrupt loaded image) reads as the whole entry.
    Ok(data.get(..len).unwrap_or(data))
}

/// Reads `sub` of `info` from byte `offset` into `buf`.
pub fn read(image: &[u8], info: &EntryInfo, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
    read_slice(value(image, info, sub)?, offset, buf)
}

/// Writes `data`, which passed [`EntryInfo::check_data`], as the value of `sub` of `info`: a
/// BOOLEAN is stored as 0 or 1, a string or domain with its length, anything else as given.
pub fn write(image: &mut [u8], info: &EntryInfo, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
    let len = image.len();
    let slot = image.get_mut(place(info, sub, len)?).ok_or(SdoAbort::NoSubIndex)?;
    match (info.data_type(), &mut *slot) {
        (DataType::Boolean, [b]) => *b = u8::from(data.iter().any(|&d| d != 0)),
        _ if info.is_variable_length() => {
            let (len, rest) = slot.split_at_mut_checked(LEN_BYTES).ok_or(SdoAbort::NoSubIndex)?;
            let count = u16::try_from(data.len()).map_err(|_| SdoAbort::LengthTooHigh)?;
            put(rest.get_mut(..data.len()).ok_or(SdoAbort::LengthTooHigh)?, data);
            put(len, &count.to_le_bytes());
        }
        _ => put(slot.get_mut(..data.len()).ok_or(SdoAbort::LengthTooHigh)?, data),
    }
    Ok(())
}

/// `dst` := `src` (of the same length), byte by byte: a loop as long as the data, which Kani
/// unrolls over the few bytes a write brings, where a slice copy of symbolic length into the
/// whole image made its formula too large to solve.
fn put(dst: &mut [u8], src: &[u8]) {
    for (d, s) in dst.iter_mut().zip(src) {
        *d = *s;
    }
}

/// A contiguous piece of the image that belongs to one index class: the unit of resets
/// (what `$NODEID` patches and defaults act on) and of the persistent block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Span {
    /// An index of the piece: which [`Area`](super::Area) it belongs to (a piece never
    /// straddles two).
    pub index: u16,
    /// Bytes `start..start + len` of the image.
    pub start: u16,
    pub len: u16,
}

impl Span {
    fn range(&self) -> Range<usize> {
        usize::from(self.start)..usize::from(self.start) + usize::from(self.len)
    }
}

/// A default the value image of the defaults cannot hold: one that depends on the node-ID
/// (`$NODEID + value` in the spec) or on the mode. `width` bytes (1..=4) little-endian at
/// `at`, in the area of its index. Eight bytes, built with [`Patch::new`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Patch {
    at: u16,
    /// The index's high byte: enough to tell its [`Area`](super::Area), whose bounds are
    /// multiples of 1000h.
    page: u8,
    /// Bits 0..=2: the width; bit 7: the node-ID is added to `value`.
    kind: u8,
    value: u32,
}

impl Patch {
    pub const fn new(index: u16, at: u16, width: u8, plus_node_id: bool, value: u32) -> Patch {
        Patch { at, page: (index >> 8) as u8, kind: (width & 7) | (plus_node_id as u8) << 7, value }
    }

    fn index(&self) -> u16 {
        u16::from(self.page) << 8
    }

    fn width(&self) -> usize {
        usize::from(self.kind & 7).min(4)
    }

    fn plus_node_id(&self) -> bool {
        self.kind & 0x80 != 0
    }
}

/// The defaults as a generated dictionary keeps them in flash: the value image of its spec
/// defaults without most of its zeros (most entries default to 0). A series of records, each
/// `[zeros, n, n bytes]`: skip `zeros` zero bytes, then `n` bytes as given; 255 in a count
/// is as far as one record reaches, the next goes on.
///
/// [`sparse_len`] and [`sparse`] make it at compile time from the image.
pub const fn sparse_len(image: &[u8]) -> usize {
    let (mut at, mut len) = (0, 0);
    while at < image.len() {
        let (zeros, n) = next_record(image, at);
        len += 2 + n;
        at += zeros + n;
    }
    len
}

/// The sparse form of `image` ([`sparse_len`] bytes: `N`).
#[allow(clippy::indexing_slicing)] // Const code: `at + i < image.len()` and `len + i < N` by construction.
pub const fn sparse<const N: usize>(image: &[u8]) -> [u8; N] {
    let mut out = [0; N];
    let (mut at, mut len) = (0, 0);
    while at < image.len() && len + 2 <= N {
        let (zeros, n) = next_record(image, at);
        out[len] = zeros as u8;
        out[len + 1] = n as u8;
        let mut i = 0;
        while i < n && len + 2 + i < N {
            out[len + 2 + i] = image[at + zeros + i];
            i += 1;
        }
        len += 2 + n;
        at += zeros + n;
    }
    out
}

/// From `at`: how many zero bytes to skip, then how many bytes to give (a run ends at 3 zeros
/// in a row, where a new record is cheaper than the zeros).
#[allow(clippy::indexing_slicing)] // Const code: every index is checked against `image.len()`.
const fn next_record(image: &[u8], at: usize) -> (usize, usize) {
    let mut zeros = 0;
    while at + zeros < image.len() && image[at + zeros] == 0 && zeros < 255 {
        zeros += 1;
    }
    let start = at + zeros;
    let mut n = 0;
    while start + n < image.len() && n < 255 {
        let zero_run = start + n + 2 < image.len() && image[start + n] == 0 && image[start + n + 1] == 0 && image[start + n + 2] == 0;
        if zero_run {
            break;
        }
        n += 1;
    }
    // Trailing zeros of the image are left to the clearing.
    while n > 0 && image[start + n - 1] == 0 {
        n -= 1;
    }
    (zeros, n)
}

/// Sets the spans of `area` back to the defaults ([`sparse`] form): one pass over the image,
/// byte by byte (a reset is rare; small code matters more than speed here).
pub fn reset(image: &mut [u8], defaults: &[u8], spans: &[Span], area: super::Area) {
    let in_area = |at: usize| spans.iter().any(|s| area.contains(s.index) && s.range().contains(&at));
    // The record being read: zeros still to give, then bytes still to give from `rest`.
    let (mut zeros, mut given, mut rest) = (0_usize, 0_usize, defaults);
    for (at, byte) in image.iter_mut().enumerate() {
        while zeros == 0 && given == 0 {
            let [z, n, tail @ ..] = rest else { break };
            (zeros, given, rest) = (usize::from(*z), usize::from(*n), tail);
        }
        let value = if zeros > 0 {
            zeros -= 1;
            0
        } else if let ([b, tail @ ..], true) = (rest, given > 0) {
            (given, rest) = (given - 1, tail);
            *b
        } else {
            0
        };
        if in_area(at) {
            *byte = value;
        }
    }
}

/// Applies the patches of `area`, the node-ID being `node_id`. Not inlined: a reset calls
/// it twice (the node-ID's defaults, the mode's).
#[inline(never)]
pub fn patch(image: &mut [u8], patches: &[Patch], area: super::Area, node_id: u8) {
    for p in patches.iter().filter(|p| area.contains(p.index())) {
        let value = if p.plus_node_id() { p.value.wrapping_add(u32::from(node_id)) } else { p.value }.to_le_bytes();
        let at = usize::from(p.at);
        if let (Some(dst), Some(src)) = (image.get_mut(at..at + p.width()), value.get(..p.width())) {
            dst.copy_from_slice(src);
        }
    }
}

/// Hands the persistent spans of `area` to `sink`, each at its offset in the persistent
/// block (the spans one after the other, in order, whatever `area` is); `false` if `sink`
/// refused one (the rest are still handed over).
pub fn save(image: &[u8], spans: &[Span], area: super::Area, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
    let (mut at, mut ok) = (0, true);
    for span in spans {
        if area.contains(span.index) {
            ok &= image.get(span.range()).is_some_and(|bytes| sink(at, bytes));
        }
        at += usize::from(span.len);
    }
    ok
}

/// Loads the persistent spans of `area` from `source` ([`save`]'s layout); a span `source`
/// cannot give keeps its bytes, and the result is `false`.
pub fn load(image: &mut [u8], spans: &[Span], area: super::Area, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
    let (mut at, mut ok) = (0, true);
    let mut buf = [0_u8; 32];
    for span in spans {
        if area.contains(span.index) {
            // Through a buffer, 32 bytes at a time: a piece the source fails to give is not
            // copied, so a storage error never leaves bytes the source only half read.
            let range = span.range();
            let mut done = 0;
            while done < range.len() {
                let n = (range.len() - done).min(buf.len());
                let (Some(piece), Some(dst)) = (buf.get_mut(..n), image.get_mut(range.start + done..range.start + done + n)) else {
                    ok = false;
                    break;
                };
                if !source(at + done, piece) {
                    ok = false;
                    break;
                }
                dst.copy_from_slice(piece);
                done += n;
            }
        }
        at += usize::from(span.len);
    }
    ok
}

/// Bytes of the persistent block `spans` describe.
#[allow(clippy::indexing_slicing)] // Const code: `i < spans.len()`.
pub const fn block_len(spans: &[Span]) -> usize {
    let (mut i, mut n) = (0, 0);
    while i < spans.len() {
        n += spans[i].len as usize;
        i += 1;
    }
    n
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::od::{Access, Area, HostAccess, test_entry};

    /// `data_type` entries `sub..=last_sub` at `offset`.
    fn run(data_type: DataType, size: u16, offset: u16, sub: u8, last_sub: u8) -> EntryInfo {
        EntryInfo { offset, sub, last_sub, ..test_entry(data_type, Access::Rw, HostAccess::Rw, size) }
    }

    #[test]
    fn runs_are_laid_out_by_stride() {
        // 4 u16 items from byte 3: sub 2 is bytes 5..7.
        let items = run(DataType::Unsigned16, 2, 3, 1, 4);
        let mut image = [0_u8; 11];
        write(&mut image, &items, 2, &[0x34, 0x12]).unwrap();
        assert_eq!(image, [0, 0, 0, 0, 0, 0x34, 0x12, 0, 0, 0, 0]);
        let mut buf = [0; 4];
        assert_eq!(read(&image, &items, 2, 0, &mut buf), Ok(ReadLen { copied: 2, total: 2 }));
        assert_eq!(buf[..2], [0x34, 0x12]);
        // Sub 4 ends at byte 11, the image's end; sub 5 is outside the run, sub 0 before it.
        assert!(write(&mut image, &items, 4, &[1, 2]).is_ok());
        assert_eq!(image[9..], [1, 2]);
        assert_eq!(write(&mut image, &items, 5, &[1, 2]), Err(SdoAbort::NoSubIndex));
        assert_eq!(read(&image, &items, 0, 0, &mut buf), Err(SdoAbort::NoSubIndex));
        // A place past the image (a table that does not fit it) is refused, not a panic.
        let past = run(DataType::Unsigned32, 4, 9, 0, 0);
        assert_eq!(write(&mut image, &past, 0, &[1, 2, 3, 4]), Err(SdoAbort::NoSubIndex));
        assert_eq!(read(&image, &past, 0, 0, &mut buf), Err(SdoAbort::NoSubIndex));
    }

    #[test]
    fn strings_keep_their_length_before_their_bytes() {
        let name = run(DataType::VisibleString, 6, 1, 0, 0);
        assert_eq!(stride(&name), 8);
        let mut image = [0xEE_u8; 9];
        write(&mut image, &name, 0, b"oil").unwrap();
        assert_eq!(image[..6], [0xEE, 3, 0, b'o', b'i', b'l']);
        let mut buf = [0; 8];
        assert_eq!(read(&image, &name, 0, 0, &mut buf), Ok(ReadLen { copied: 3, total: 3 }));
        assert_eq!(read(&image, &name, 0, 1, &mut buf), Ok(ReadLen { copied: 2, total: 3 }));
        assert_eq!(&buf[..2], b"il");
        write(&mut image, &name, 0, b"").unwrap();
        assert_eq!(read(&image, &name, 0, 0, &mut buf), Ok(ReadLen { copied: 0, total: 0 }));
        // A corrupt length (a damaged loaded image) reads as the whole entry, never past it.
        image[1..3].copy_from_slice(&900_u16.to_le_bytes());
        assert_eq!(read(&image, &name, 0, 0, &mut buf).map(|n| n.total), Ok(6));
    }

    #[test]
    fn booleans_are_stored_as_0_or_1() {
        let flag = run(DataType::Boolean, 1, 0, 0, 0);
        let mut image = [7_u8; 1];
        write(&mut image, &flag, 0, &[1]).unwrap();
        assert_eq!(image, [1]);
        write(&mut image, &flag, 0, &[0]).unwrap();
        assert_eq!(image, [0]);
    }

    const SPANS: [Span; 3] = [Span { index: 0x1005, start: 0, len: 4 }, Span { index: 0x2000, start: 4, len: 2 }, Span { index: 0x6000, start: 8, len: 2 }];

    #[test]
    fn a_reset_takes_the_defaults_and_patches_of_its_area_only() {
        const IMAGE: [u8; 10] = [1, 2, 3, 4, 5, 6, 7, 8, 9, 0];
        const DEFAULTS: [u8; sparse_len(&IMAGE)] = sparse(&IMAGE);
        let mut image = [0xEE_u8; 10];
        reset(&mut image, &DEFAULTS, &SPANS, Area::COMMUNICATION);
        assert_eq!(image, [1, 2, 3, 4, 0xEE, 0xEE, 0xEE, 0xEE, 0xEE, 0xEE]);
        reset(&mut image, &DEFAULTS, &SPANS, Area::ALL);
        // Bytes 6 and 7 belong to no span: a reset never touches them.
        assert_eq!(image, [1, 2, 3, 4, 5, 6, 0xEE, 0xEE, 9, 0]);
        let patches = [Patch::new(0x1005, 0, 4, true, 0x180), Patch::new(0x6000, 8, 1, false, 0x10)];
        patch(&mut image, &patches, Area::COMMUNICATION, 5);
        assert_eq!(image, [0x85, 1, 0, 0, 5, 6, 0xEE, 0xEE, 9, 0]);
        patch(&mut image, &patches, Area::APPLICATION, 5);
        assert_eq!(image[8..], [0x10, 0]);
    }

    /// Every image of up to 12 bytes of 0, 1 and 0xFF, and long runs of zeros and of bytes:
    /// the sparse form resets to exactly the image, and is no longer than needed.
    #[test]
    fn sparse_defaults_reset_to_the_image() {
        fn round_trip(img: &[u8]) {
            let mut buf = std::vec![0_u8; sparse_len(img)];
            let n = buf.len();
            // `sparse` wants a constant length: through the largest used here.
            let full: [u8; 1200] = sparse(img);
            buf.copy_from_slice(&full[..n]);
            assert!(full[n..].iter().all(|&b| b == 0));
            let spans = [Span { index: 0x2000, start: 0, len: img.len() as u16 }];
            let mut out = std::vec![0xA5_u8; img.len()];
            reset(&mut out, &buf, &spans, Area::ALL);
            assert_eq!(out, img, "sparse form {buf:?}");
        }
        for len in 0..=8_u32 {
            for pattern in 0..3_u32.pow(len) {
                let img: std::vec::Vec<u8> = (0..len).map(|i| [0, 1, 0xFF][(pattern / 3_u32.pow(i) % 3) as usize]).collect();
                round_trip(&img);
            }
        }
        let mut long = std::vec![0_u8; 700];
        long[600..690].fill(7);
        long[3] = 1;
        round_trip(&long);
        round_trip(&[9; 600]);
        assert_eq!(sparse_len(&[0; 700]), 6, "700 zeros: three records of skips, nothing given");
    }

    #[test]
    fn the_persistent_block_is_the_spans_one_after_the_other() {
        let image = [1, 2, 3, 4, 5, 6, 0, 0, 9, 10];
        assert_eq!(block_len(&SPANS), 8);
        let mut block = [0_u8; 8];
        assert!(save(&image, &SPANS, Area::ALL, &mut |at, bytes| {
            block[at..at + bytes.len()].copy_from_slice(bytes);
            true
        }));
        assert_eq!(block, [1, 2, 3, 4, 5, 6, 9, 10]);
        // An area's spans keep their place in the block.
        let mut seen = std::vec::Vec::new();
        assert!(save(&image, &SPANS, Area::MANUFACTURER, &mut |at, bytes| {
            seen.push((at, bytes.to_vec()));
            true
        }));
        assert_eq!(seen, [(4, std::vec![5, 6])]);
        let mut loaded = [0_u8; 10];
        assert!(load(&mut loaded, &SPANS, Area::ALL, &mut |at, buf| {
            buf.copy_from_slice(&block[at..at + buf.len()]);
            true
        }));
        assert_eq!(loaded, image);
        // A source that fails keeps the bytes it could not give, and says so.
        let mut kept = [0xAA_u8; 10];
        assert!(!load(&mut kept, &SPANS, Area::ALL, &mut |at, buf| {
            buf.copy_from_slice(&block[at..at + buf.len()]);
            at != 4
        }));
        assert_eq!(kept, [1, 2, 3, 4, 0xAA, 0xAA, 0xAA, 0xAA, 9, 10]);
    }

    #[test]
    fn no_place_or_data_panics() {
        // Every sub-index and length against runs at the image's edge.
        for data_type in [DataType::Unsigned8, DataType::Unsigned32, DataType::Boolean, DataType::OctetString] {
            for offset in [0, 5, 7, 8, 200] {
                let info = run(data_type, if data_type == DataType::Unsigned32 { 4 } else { 3 }, offset, 1, 2);
                for sub in 0..=3 {
                    for len in 0..=6 {
                        let mut image = [0_u8; 8];
                        let _ = write(&mut image, &info, sub, &[0x5A; 6][..len]);
                        let mut buf = [0; 2];
                        let _ = read(&image, &info, sub, usize::from(sub), &mut buf);
                    }
                }
            }
        }
    }
}
