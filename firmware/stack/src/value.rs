//! The value types of generated dictionaries, and how app-backed objects' typed values become
//! bytes.
//!
//! A dictionary's stored fields are byte-aligned and little-endian (zerocopy's byte-order
//! types, [`Bytes`], [`Array`]), so that the struct holding them is the value image
//! [`crate::od::image`] reads and writes. [`OdValue`] converts the native Rust values of
//! app-backed objects' hooks (`app::Typed` in the generated code) to and from their bytes.

use crate::od::entry::{Int, le_u64};
use crate::od::{EntryInfo, ReadLen, SdoAbort, read_slice};
use zerocopy::little_endian::U16;
use zerocopy::{FromBytes, Immutable, IntoBytes, KnownLayout, Unaligned};

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

/// A string, octet string or domain of at most `N` bytes, stored without heap: its length
/// (2 bytes, little-endian), then the bytes; as [`crate::od::image`] lays out such a value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, FromBytes, IntoBytes, KnownLayout, Immutable, Unaligned)]
#[repr(C)]
pub struct Bytes<const N: usize> {
    len: U16,
    bytes: [u8; N],
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
        Bytes { bytes, len: U16::new(i as u16) }
    }

    /// The first `N` bytes of `data` (all of them when it is shorter).
    pub fn from_slice(data: &[u8]) -> Self {
        let mut value = Self::default();
        let len = data.len().min(N);
        if let (Some(dst), Some(src)) = (value.bytes.get_mut(..len), data.get(..len)) {
            dst.copy_from_slice(src);
            value.len = U16::new(len as u16);
        }
        value
    }

    /// The value (a length beyond `N`, from a corrupt loaded image, reads as all `N` bytes).
    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.get(..usize::from(self.len.get())).unwrap_or(&self.bytes)
    }
}

/// Empty: what a generated dictionary starts from before it sets the spec's defaults.
impl<const N: usize> Default for Bytes<N> {
    fn default() -> Self {
        Bytes { bytes: [0; N], len: U16::ZERO }
    }
}

impl<const N: usize> OdValue for Bytes<N> {
    fn read(&self, _: &EntryInfo, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        read_slice(self.as_bytes(), offset, buf)
    }
    fn write(&mut self, _: &EntryInfo, data: &[u8]) -> Result<(), SdoAbort> {
        let dst = self.bytes.get_mut(..data.len()).ok_or(SdoAbort::LengthTooHigh)?;
        dst.copy_from_slice(data);
        self.len = U16::new(data.len() as u16);
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

/// The low `N` bytes of `value`, little-endian: the image of a 24-, 40-, 48- or 56-bit
/// integer's default.
#[allow(clippy::indexing_slicing)] // `i < N <= 8`: `get` is not usable in const here.
pub const fn low_bytes<const N: usize>(value: u64) -> [u8; N] {
    let le = value.to_le_bytes();
    let mut out = [0; N];
    let mut i = 0;
    while i < N && i < 8 {
        out[i] = le[i];
        i += 1;
    }
    out
}

/// An ARRAY object's storage: sub 0 and the elements 1..=N (byte-aligned types: no padding
/// between them, as the value image has it).
#[derive(Debug, Clone, Copy, PartialEq, FromBytes, IntoBytes, KnownLayout, Immutable, Unaligned)]
#[repr(C, packed)]
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
