//! How typed dictionary fields are read and written as little-endian bytes.

use crate::od::entry::{Int, le_u64};
use crate::od::{EntryInfo, ReadLen, SdoAbort, read_slice};

/// A value stored in a dictionary field. `write` gets data that already passed the access,
/// length and range checks of [`EntryInfo::check_write`].
pub trait OdValue {
    fn read(&self, entry: &EntryInfo, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort>;
    fn write(&mut self, entry: &EntryInfo, data: &[u8]) -> Result<(), SdoAbort>;
}

/// The two's-complement bits of what `data` stores in an integer field of `width` bytes
/// (`signed` or not): a full-width value as it is, a narrower one (the 24/40/48/56-bit types
/// live in the next wider Rust integer) decoded by the entry's type and refused with
/// `ValueTooHigh` if the field cannot hold it. One function for every integer type, which
/// then only truncates.
fn int_bits(entry: &EntryInfo, data: &[u8], width: usize, signed: bool) -> Result<u64, SdoAbort> {
    if data.len() == width {
        return le_u64(data).ok_or(SdoAbort::LengthMismatch);
    }
    // The field's range: 0..=2^bits - 1, or -2^(bits - 1)..=2^(bits - 1) - 1.
    let unused = 64_u32.saturating_sub(8 * width as u32);
    let (min, max) = if signed { (i64::MIN >> unused, u64::MAX >> (unused + 1)) } else { (0, u64::MAX >> unused) };
    match Int::decode(entry.data_type(), data).ok_or(SdoAbort::LengthMismatch)? {
        Int::Signed(v) if v >= min && u64::try_from(v).map_or(true, |v| v <= max) => Ok(v as u64),
        Int::Unsigned(v) if v <= max => Ok(v),
        _ => Err(SdoAbort::ValueTooHigh),
    }
}

macro_rules! integer_value {
    ($($t:ty),*) => {$(
        impl OdValue for $t {
            fn read(&self, entry: &EntryInfo, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
                let bytes = self.to_le_bytes();
                // The whole value into a buffer that holds it (every PDO and expedited read):
                // a fixed-size copy, not a call to `memcpy`.
                if offset == 0
                    && usize::from(entry.size) == bytes.len()
                    && let Some(dst) = buf.get_mut(..bytes.len())
                {
                    dst.copy_from_slice(&bytes);
                    return Ok(ReadLen { copied: bytes.len(), total: bytes.len() });
                }
                // 24/40/48/56-bit types live in the next wider Rust integer.
                read_slice(bytes.get(..usize::from(entry.size)).unwrap_or(&bytes), offset, buf)
            }
            fn write(&mut self, entry: &EntryInfo, data: &[u8]) -> Result<(), SdoAbort> {
                // A full-width value (all but the 24/40/48/56-bit types) is its bytes: the
                // RPDO and SDO paths take this branch, without the generic decoder's loop.
                if let Ok(bytes) = data.try_into() {
                    *self = <$t>::from_le_bytes(bytes);
                    return Ok(());
                }
                // In range by `int_bits`: the cast keeps the value.
                *self = int_bits(entry, data, size_of::<$t>(), <$t>::MIN != 0)? as $t;
                Ok(())
            }
        }
    )*};
}

integer_value!(u8, u16, u32, u64, i8, i16, i32, i64);

impl OdValue for bool {
    fn read(&self, _: &EntryInfo, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        read_slice(&[u8::from(*self)], offset, buf)
    }
    fn write(&mut self, entry: &EntryInfo, data: &[u8]) -> Result<(), SdoAbort> {
        *self = !Int::decode(entry.data_type(), data).ok_or(SdoAbort::LengthMismatch)?.is(0);
        Ok(())
    }
}

macro_rules! float_value {
    ($($t:ty),*) => {$(
        impl OdValue for $t {
            fn read(&self, _: &EntryInfo, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
                read_slice(&self.to_le_bytes(), offset, buf)
            }
            fn write(&mut self, _: &EntryInfo, data: &[u8]) -> Result<(), SdoAbort> {
                *self = <$t>::from_le_bytes(data.try_into().map_err(|_| SdoAbort::LengthMismatch)?);
                Ok(())
            }
        }
    )*};
}

float_value!(f32, f64);

/// A string or octet string of at most `N` bytes, stored without heap.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bytes<const N: usize> {
    bytes: [u8; N],
    len: usize,
}

impl<const N: usize> Bytes<N> {
    /// The spec's default text; longer text is cut at `N` (the spec check prevents that).
    // Indexing in a const loop bounded by both lengths; `get` is not usable in const here.
    #[allow(clippy::indexing_slicing)]
    pub const fn new(text: &str) -> Self {
        let src = text.as_bytes();
        let mut bytes = [0_u8; N];
        let mut i = 0;
        while i < src.len() && i < N {
            bytes[i] = src[i];
            i += 1;
        }
        Bytes { bytes, len: i }
    }

    /// The first `N` bytes of `data` (all of them when it is shorter).
    pub fn from_slice(data: &[u8]) -> Self {
        let mut value = Self::default();
        let len = data.len().min(N);
        if let (Some(dst), Some(src)) = (value.bytes.get_mut(..len), data.get(..len)) {
            dst.copy_from_slice(src);
            value.len = len;
        }
        value
    }

    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.get(..self.len).unwrap_or(&[])
    }
}

/// Empty: what a generated dictionary starts from before it sets the spec's defaults.
impl<const N: usize> Default for Bytes<N> {
    fn default() -> Self {
        Bytes { bytes: [0; N], len: 0 }
    }
}

impl<const N: usize> OdValue for Bytes<N> {
    fn read(&self, _: &EntryInfo, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        read_slice(self.as_bytes(), offset, buf)
    }
    fn write(&mut self, _: &EntryInfo, data: &[u8]) -> Result<(), SdoAbort> {
        let dst = self.bytes.get_mut(..data.len()).ok_or(SdoAbort::LengthTooHigh)?;
        dst.copy_from_slice(data);
        self.len = data.len();
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::od::{Access, DataType, HostAccess};

    fn info(data_type: DataType, size: u16) -> EntryInfo {
        crate::od::test_entry(data_type, Access::Rw, HostAccess::None, size)
    }

    #[test]
    fn integers_round_trip_little_endian() {
        let e = info(DataType::Integer24, 3);
        let mut v: i32 = 0;
        v.write(&e, &[0xFE, 0xFF, 0xFF]).unwrap();
        assert_eq!(v, -2);
        let mut buf = [0; 8];
        assert_eq!(v.read(&e, 0, &mut buf), Ok(ReadLen { copied: 3, total: 3 }));
        assert_eq!(buf[..3], [0xFE, 0xFF, 0xFF]);
        let mut u: u16 = 0;
        u.write(&info(DataType::Unsigned16, 2), &[0x34, 0x12]).unwrap();
        assert_eq!(u, 0x1234);
    }

    #[test]
    fn integer_writes_store_what_fits_the_field_as_the_exact_conversion_does() {
        let mut x = 3_u64;
        macro_rules! check {
            ($($t:ty),*) => {$(
                for t in DataType::ALL {
                    let Some(bits) = t.bits() else { continue };
                    let len = bits.div_ceil(8) as usize;
                    for n in 0..300 {
                        x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
                        let raw = [0, u64::MAX, x][n.min(2)];
                        let data = &raw.to_le_bytes()[..len];
                        let mut v: $t = 0 as $t;
                        let got = v.write(&info(t, len as u16), data).map(|()| v);
                        // Full width: the bytes as they are; narrower: the decoded value, if it fits.
                        let want = match <[u8; size_of::<$t>()]>::try_from(data) {
                            Ok(bytes) => Ok(<$t>::from_le_bytes(bytes)),
                            Err(_) => crate::od::decode_int(t, data)
                                .ok_or(SdoAbort::LengthMismatch)
                                .and_then(|v| <$t>::try_from(v).map_err(|_| SdoAbort::ValueTooHigh)),
                        };
                        assert_eq!(got, want, "{} as {t}: {data:02X?}", stringify!($t));
                    }
                }
            )*};
        }
        check!(u8, u16, u32, u64, i8, i16, i32, i64);
    }

    #[test]
    fn strings_keep_their_length() {
        let e = info(DataType::VisibleString, 8);
        let mut s = Bytes::<8>::new("Datei1");
        assert_eq!(s.as_bytes(), b"Datei1");
        s.write(&e, b"oil").unwrap();
        let mut buf = [0; 8];
        assert_eq!(s.read(&e, 0, &mut buf), Ok(ReadLen { copied: 3, total: 3 }));
        assert_eq!(s.write(&e, b"123456789"), Err(SdoAbort::LengthTooHigh));
        assert_eq!(s.as_bytes(), b"oil", "a refused write keeps the stored value");
        assert_eq!(Bytes::<4>::from_slice(b"abcdef").as_bytes(), b"abcd", "cut at the capacity");
        assert_eq!(Bytes::<8>::from_slice(b"ab").as_bytes(), b"ab");
    }

    #[test]
    fn floats_and_booleans() {
        let mut f: f32 = 0.0;
        f.write(&info(DataType::Real32, 4), &1.5_f32.to_le_bytes()).unwrap();
        assert_eq!(f, 1.5);
        let mut b = false;
        b.write(&info(DataType::Boolean, 1), &[1]).unwrap();
        assert!(b);
    }
}

/// An ARRAY object's storage: sub 0 and the elements 1..=N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Array<T, const N: usize> {
    pub sub0: u8,
    pub items: [T; N],
}

/// All zero (`[T; N]: Default` stops at 32 elements).
impl<T: Default + Copy, const N: usize> Default for Array<T, N> {
    fn default() -> Self {
        Array { sub0: 0, items: [T::default(); N] }
    }
}

impl<T: OdValue, const N: usize> Array<T, N> {
    /// The field of sub-index `sub`: 0 the count, 1..=N the items (the generated dispatch
    /// routes every sub-index of an array here, one arm per array).
    #[inline]
    pub fn sub(&mut self, sub: u8) -> Option<&mut dyn OdValue> {
        array_sub(&mut self.sub0, &mut self.items, sub)
    }
}

/// [`Array::sub`] for any length: one copy per item type, not one per array object (the
/// dispatch has one arm per array).
#[inline(never)]
fn array_sub<'a, T: OdValue>(sub0: &'a mut u8, items: &'a mut [T], sub: u8) -> Option<&'a mut dyn OdValue> {
    match sub.checked_sub(1) {
        None => Some(sub0),
        Some(i) => items.get_mut(usize::from(i)).map(|v| v as &mut dyn OdValue),
    }
}

/// A field's fixed-size image in the 1010h/1011h store: what `save` writes, `load` reads.
pub trait Persist {
    /// Bytes of the image.
    const SIZE: usize;
    fn save(&self, out: &mut [u8]);
    fn load(&mut self, data: &[u8]);
}

macro_rules! persist_number {
    ($($t:ty),*) => {$(
        impl Persist for $t {
            const SIZE: usize = core::mem::size_of::<$t>();
            fn save(&self, out: &mut [u8]) {
                if let Some(dst) = out.get_mut(..Self::SIZE) {
                    dst.copy_from_slice(&self.to_le_bytes());
                }
            }
            fn load(&mut self, data: &[u8]) {
                if let Some(bytes) = data.get(..Self::SIZE).and_then(|b| b.try_into().ok()) {
                    *self = <$t>::from_le_bytes(bytes);
                }
            }
        }
    )*};
}

persist_number!(u8, u16, u32, u64, i8, i16, i32, i64, f32, f64);

impl Persist for bool {
    const SIZE: usize = 1;
    fn save(&self, out: &mut [u8]) {
        if let Some(b) = out.first_mut() {
            *b = u8::from(*self);
        }
    }
    fn load(&mut self, data: &[u8]) {
        if let Some(&b) = data.first() {
            *self = b != 0;
        }
    }
}

/// Strings: a 2-byte length, then `N` bytes.
impl<const N: usize> Persist for Bytes<N> {
    const SIZE: usize = 2 + N;
    fn save(&self, out: &mut [u8]) {
        let len = u16::try_from(self.len).unwrap_or(u16::MAX);
        if let Some(l) = out.get_mut(..2) {
            l.copy_from_slice(&len.to_le_bytes());
        }
        if let Some(b) = out.get_mut(2..2 + N) {
            b.copy_from_slice(&self.bytes);
        }
    }
    fn load(&mut self, data: &[u8]) {
        let (Some(&[l0, l1]), Some(b)) = (data.get(..2).and_then(|l| <&[u8; 2]>::try_from(l).ok()), data.get(2..2 + N)) else { return };
        let len = usize::from(u16::from_le_bytes([l0, l1]));
        if len <= N {
            self.bytes.copy_from_slice(b);
            self.len = len;
        }
    }
}

/// One unit of the persistent block as the generated `save_area`/`load_area` walk it: a field,
/// an array's items, a whole array or a whole record, each handing its entries' images over
/// one by one at their offsets (the same pieces, in the same order, as a walk entry by entry).
/// Object-safe, so a dictionary names its units in one `match` instead of unrolling a copy of
/// the store code per entry.
pub trait Persistent {
    /// Hands the image of every entry of the unit to `sink`, the first at offset `at`; `false`
    /// if `sink` refused one (the rest are still handed over).
    fn save_to(&self, at: usize, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool;
    /// Loads every entry of the unit from `source`, the first at offset `at`; an entry whose
    /// image `source` cannot give keeps its value, and the result is `false`.
    fn load_from(&mut self, at: usize, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool;
}

macro_rules! persistent_number {
    ($($t:ty),*) => {$(
        // Out of line: records call these once per field.
        impl Persistent for $t {
            #[inline(never)]
            fn save_to(&self, at: usize, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
                sink(at, &self.to_le_bytes())
            }
            #[inline(never)]
            fn load_from(&mut self, at: usize, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
                let mut image = [0_u8; size_of::<$t>()];
                let ok = source(at, &mut image);
                if ok {
                    *self = <$t>::from_le_bytes(image);
                }
                ok
            }
        }
    )*};
}

persistent_number!(u8, u16, u32, u64, i8, i16, i32, i64, f32, f64);

impl Persistent for bool {
    fn save_to(&self, at: usize, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
        sink(at, &[u8::from(*self)])
    }
    fn load_from(&mut self, at: usize, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
        let mut image = [0_u8; 1];
        let ok = source(at, &mut image);
        if ok {
            self.load(&image);
        }
        ok
    }
}

/// The length (2 bytes), then the `N` bytes: [`Persist`]'s image, in two pieces.
impl<const N: usize> Persistent for Bytes<N> {
    fn save_to(&self, at: usize, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
        let len = u16::try_from(self.len).unwrap_or(u16::MAX);
        let ok = sink(at, &len.to_le_bytes());
        sink(at + 2, &self.bytes) && ok
    }
    fn load_from(&mut self, at: usize, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
        let (mut len, mut bytes) = ([0_u8; 2], [0_u8; N]);
        let ok = source(at, &mut len) && source(at + 2, &mut bytes);
        let len = usize::from(u16::from_le_bytes(len));
        // A corrupt length leaves the value as it was.
        if ok && len <= N {
            (self.bytes, self.len) = (bytes, len);
        }
        ok
    }
}

/// An array's items 1..=N, each [`Persist::SIZE`] bytes.
impl<T: Persist + Persistent, const N: usize> Persistent for [T; N] {
    fn save_to(&self, at: usize, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
        let mut ok = true;
        for (i, item) in self.iter().enumerate() {
            ok &= item.save_to(at + i * T::SIZE, sink);
        }
        ok
    }
    fn load_from(&mut self, at: usize, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
        let mut ok = true;
        for (i, item) in self.iter_mut().enumerate() {
            ok &= item.load_from(at + i * T::SIZE, source);
        }
        ok
    }
}

/// A whole array: sub 0, then the items.
impl<T: Persist + Persistent, const N: usize> Persistent for Array<T, N> {
    fn save_to(&self, at: usize, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
        let ok = self.sub0.save_to(at, sink);
        self.items.save_to(at + 1, sink) && ok
    }
    fn load_from(&mut self, at: usize, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
        let ok = self.sub0.load_from(at, source);
        self.items.load_from(at + 1, source) && ok
    }
}

/// A generated record's fields, one after the other from `at`, each with its image size: one
/// loop for every record type instead of a call sequence per type.
#[inline(never)]
pub fn save_fields(fields: &[(&dyn Persistent, usize)], mut at: usize, sink: &mut dyn FnMut(usize, &[u8]) -> bool) -> bool {
    let mut ok = true;
    for &(field, size) in fields {
        ok &= field.save_to(at, sink);
        at += size;
    }
    ok
}

/// Loads a generated record's fields ([`save_fields`]).
#[inline(never)]
pub fn load_fields(fields: &mut [(&mut dyn Persistent, usize)], mut at: usize, source: &mut dyn FnMut(usize, &mut [u8]) -> bool) -> bool {
    let mut ok = true;
    for (field, size) in fields {
        ok &= field.load_from(at, source);
        at += *size;
    }
    ok
}

#[cfg(test)]
mod persist_tests {
    use super::*;

    #[test]
    fn images_round_trip() {
        let mut out = [0_u8; 16];
        0x1234_u16.save(&mut out);
        let mut v = 0_u16;
        v.load(&out);
        assert_eq!(v, 0x1234);
        let s = Bytes::<8>::new("oil");
        s.save(&mut out);
        assert_eq!(out[..5], [3, 0, b'o', b'i', b'l']);
        let mut t = Bytes::<8>::new("");
        t.load(&out);
        assert_eq!(t.as_bytes(), b"oil");
        // A corrupt length leaves the value as it was.
        out[0] = 200;
        t.load(&out);
        assert_eq!(t.as_bytes(), b"oil");
    }
}
