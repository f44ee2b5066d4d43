//! A millisecond clock from SysTick's counter. [`MsDelay`] waits on
//! it (the 5 ms EEPROM write cycle).

/// The core clock the image sets up: 48 MHz (HSE 8 MHz x 6, or HSI48).
pub const CORE_HZ: u32 = 48_000_000;

include!("../../systick_millis.rs");

/// Busy-waits on [`millis`]: at least the time asked, rounded up to whole milliseconds plus
/// one (the current millisecond is partly over).
#[derive(Debug, Clone, Copy, Default)]
pub struct MsDelay;

impl MsDelay {
    fn wait_ms(ms: u32) {
        let start = millis();
        while millis().wrapping_sub(start) <= u64::from(ms) {}
    }
}

impl embedded_hal::delay::DelayNs for MsDelay {
    fn delay_ns(&mut self, ns: u32) {
        MsDelay::wait_ms(ns.div_ceil(1_000_000));
    }

    fn delay_us(&mut self, us: u32) {
        MsDelay::wait_ms(us.div_ceil(1000));
    }

    fn delay_ms(&mut self, ms: u32) {
        MsDelay::wait_ms(ms);
    }
}
