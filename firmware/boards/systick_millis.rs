// Shared by the board crates' `clock` modules (`include!`d: each board is its own workspace).
// The including module defines `CORE_HZ`, the core clock SysTick counts.

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::exception;

static MILLIS: AtomicU32 = AtomicU32::new(0);

/// Starts the clock: SysTick interrupts every millisecond and counts.
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
