//! A millisecond clock: SysTick interrupts every millisecond and counts. [`MsDelay`] waits on
//! it (the 5 ms EEPROM write cycle).

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::exception;

/// The core clock the image sets up: 48 MHz (HSE 8 MHz x 6, or HSI48).
pub const CORE_HZ: u32 = 48_000_000;

static MILLIS: AtomicU32 = AtomicU32::new(0);

/// Starts the clock.
pub fn start(mut syst: SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(CORE_HZ / 1000 - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// Milliseconds since [`start`] (wraps after 49 days; only differences are used).
pub fn millis() -> u32 {
    // thumbv6m has no atomic read-modify-write, but loads and stores of a u32 are atomic.
    MILLIS.load(Ordering::Relaxed)
}

#[exception]
fn SysTick() {
    // The only writer, in the only interrupt that touches it: load + store cannot race.
    MILLIS.store(MILLIS.load(Ordering::Relaxed).wrapping_add(1), Ordering::Relaxed);
}

/// Busy-waits on [`millis`]: at least the time asked, rounded up to whole milliseconds plus
/// one (the current millisecond is partly over).
#[derive(Debug, Clone, Copy, Default)]
pub struct MsDelay;

impl MsDelay {
    fn wait_ms(ms: u32) {
        let start = millis();
        while millis().wrapping_sub(start) <= ms {}
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
