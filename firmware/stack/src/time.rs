//! Time arithmetic of the engines' timers, in microseconds since the board's epoch.

/// `now_us` plus `count` periods of `unit_us` (a configured time in ms or in 100 us units),
/// saturating. Out of line: a Cortex-M0 multiplies 64-bit values in a library call, and every
/// timer that restarts needs this.
#[inline(never)]
pub fn later_us(now_us: u64, count: u32, unit_us: u32) -> u64 {
    now_us.saturating_add(u64::from(count) * u64::from(unit_us))
}

/// `x / d` and `x % d` for a 16-bit divisor (`d` = 0 divides by 1), exactly, in four 32-bit
/// divisions: on a Cortex-M0 a 64-bit division is a library routine of about 1 KiB that
/// every `u64 / constant` on the microsecond clock would link.
pub const fn div_rem_u64(x: u64, d: u16) -> (u64, u32) {
    let d = if d == 0 { 1 } else { d as u32 };
    let (mut q, mut r, mut shift) = (0_u64, 0_u32, 64);
    // Long division in 16-bit digits: the remainder is below `d`, so remainder and digit
    // fit 32 bits, and each quotient digit is below 2^16.
    while shift > 0 {
        shift -= 16;
        let t = r << 16 | (x >> shift) as u32 & 0xFFFF;
        q = q << 16 | (t / d) as u64;
        r = t % d;
    }
    (q, r)
}

/// Milliseconds of a microsecond time: `us / 1000`, without a 64-bit division.
pub const fn ms_of_us(us: u64) -> u64 {
    div_rem_u64(us, 1000).0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn divisions_in_32_bit_steps_are_exact() {
        let mut x = 0x0123_4567_89AB_CDEF_u64;
        for _ in 0..2000 {
            x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            for v in [x, x >> 7, x >> 33, x >> 50, u64::MAX, 0, 999, 1000, 1001] {
                for d in [1_u16, 2, 7, 100, 200, 400, 1000, 1200, 2000, 0xFFFF] {
                    assert_eq!(div_rem_u64(v, d), (v / u64::from(d), (v % u64::from(d)) as u32), "{v} / {d}");
                }
            }
        }
        assert_eq!(div_rem_u64(5, 0), (5, 0), "0 divides by 1");
        assert_eq!(ms_of_us(u64::MAX), u64::MAX / 1000);
    }

    #[test]
    fn later_saturates() {
        assert_eq!(later_us(5, 3, 1000), 3005);
        assert_eq!(later_us(u64::MAX - 10, 1, 100), u64::MAX);
        assert_eq!(later_us(0, u32::MAX, u32::MAX), u64::from(u32::MAX) * u64::from(u32::MAX));
    }
}
