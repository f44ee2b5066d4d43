//! The 32-bit additive checksum CO401Memory1 reports per memory bank (object 5C00).

/// Sum of all bytes, wrapping at 2^32.
pub fn sum32(data: &[u8]) -> u32 {
    data.iter().fold(0_u32, |sum, &b| sum.wrapping_add(u32::from(b)))
}

/// The checksum after one byte changed from `old` to `new`, without re-reading the bank.
#[inline]
pub fn sum32_update(sum: u32, old: u8, new: u8) -> u32 {
    sum.wrapping_sub(u32::from(old)).wrapping_add(u32::from(new))
}
