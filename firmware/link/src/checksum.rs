//! The 32-bit additive checksum CO401Memory1 reports per memory bank (object 5C00).

/// Sum of all bytes, wrapping at 2^32.
pub fn sum32(data: &[u8]) -> u32 {
    // A loop, not `fold`: Kani (CBMC 6.6) never reduces a slice `fold` to a constant.
    let mut sum = 0_u32;
    for &b in data {
        sum = sum.wrapping_add(u32::from(b));
    }
    sum
}

/// The checksum after one byte changed from `old` to `new`, without re-reading the bank.
#[inline]
pub fn sum32_update(sum: u32, old: u8, new: u8) -> u32 {
    sum.wrapping_sub(u32::from(old)).wrapping_add(u32::from(new))
}
