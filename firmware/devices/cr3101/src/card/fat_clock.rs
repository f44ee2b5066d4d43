//! The time FAT directory entries take: the device's real-time clock, as a FAT date-time
//! word in one clock register.
//!
//! `embedded-sdmmc` asks its `TimeSource` for the time whenever it writes a file and gives
//! the time source no way back to its owner, so the device publishes the clock here before
//! each card access, as a hardware RTC register would hold it. It is one register per
//! program: a firmware image runs one device; a simulator running several CR3101 devices
//! in one process may stamp one card's directory entries with another device's clock.

use core::sync::atomic::{AtomicU32, Ordering};
use embedded_sdmmc::{TimeSource, Timestamp};

/// FAT date (high half) and time (low half) words; 0 (1980-01-01) until the device sets it.
static NOW: AtomicU32 = AtomicU32::new(0);

/// The clock register, as `embedded-sdmmc`'s time source.
#[derive(Debug, Clone, Copy, Default)]
pub struct FatClock;

impl FatClock {
    /// Publishes `t` (two-second resolution, as FAT keeps it).
    pub fn set(t: &Timestamp) {
        let [t0, t1, d0, d1] = t.serialize_to_fat();
        NOW.store(u32::from_le_bytes([t0, t1, d0, d1]), Ordering::Relaxed);
    }
}

impl TimeSource for FatClock {
    fn get_timestamp(&self) -> Timestamp {
        let word = NOW.load(Ordering::Relaxed);
        Timestamp::from_fat((word >> 16) as u16, word as u16)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_register_keeps_the_time_at_two_second_resolution() {
        let t = Timestamp { year_since_1970: 56, zero_indexed_month: 11, zero_indexed_day: 2, hours: 6, minutes: 30, seconds: 59 };
        FatClock::set(&t);
        assert_eq!(FatClock.get_timestamp(), Timestamp { seconds: 58, ..t });
    }
}
