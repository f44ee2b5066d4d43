//! Time arithmetic of the engines' timers, in microseconds since the board's epoch.

/// `now_us` plus `count` periods of `unit_us` (a configured time in ms or in 100 us units),
/// saturating. Out of line: a Cortex-M0 multiplies 64-bit values in a library call, and every
/// timer that restarts needs this.
#[inline(never)]
pub fn later_us(now_us: u64, count: u32, unit_us: u32) -> u64 {
    now_us.saturating_add(u64::from(count) * u64::from(unit_us))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn later_saturates() {
        assert_eq!(later_us(5, 3, 1000), 3005);
        assert_eq!(later_us(u64::MAX - 10, 1, 100), u64::MAX);
        assert_eq!(later_us(0, u32::MAX, u32::MAX), u64::from(u32::MAX) * u64::from(u32::MAX));
    }
}
