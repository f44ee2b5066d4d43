// Shared by the board crates' `clock` modules (`include!`d: each board is its own workspace).
// The including module defines `CORE_HZ`, the core clock SysTick counts.
//
// Time comes from SysTick's counter value, not from counting its interrupts: a tick whose
// interrupt comes late or not at all (QEMU on a busy host merges them) is not lost, since the
// counter says how far it has run. `millis` must therefore be called at least once per counter
// period (2^24 core clocks: 1.4 s at 12 MHz, 0.35 s at 48 MHz), which every main loop does.

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;

/// SysTick's counter is 24 bits wide.
const COUNTER_MASK: u32 = 0x00FF_FFFF;
const CLOCKS_PER_MS: u32 = CORE_HZ / 1000;

// Only the main loop reads the clock (no interrupt does), so plain loads and stores suffice;
// atomics only because statics must be `Sync` (thumbv6m has no read-modify-write, neither
// Cortex-M has 64-bit atomics: the milliseconds are two words).
// 0 reads as the top of the first count: the first call sees the few clocks since `start`.
static LAST_COUNT: AtomicU32 = AtomicU32::new(0);
static CLOCKS: AtomicU32 = AtomicU32::new(0);
static MILLIS_LOW: AtomicU32 = AtomicU32::new(0);
static MILLIS_HIGH: AtomicU32 = AtomicU32::new(0);

/// Starts the clock: SysTick counts the core clock down over its whole range, without
/// interrupts.
pub fn start(mut syst: SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(COUNTER_MASK);
    syst.clear_current();
    syst.enable_counter();
}

/// Milliseconds since [`start`], 64 bits wide: no wrap after 49 days.
pub fn millis() -> u64 {
    let now = SYST::get_current();
    // The counter counts down: what it ran since the last call, across one reload.
    let ran = LAST_COUNT.load(Ordering::Relaxed).wrapping_sub(now) & COUNTER_MASK;
    LAST_COUNT.store(now, Ordering::Relaxed);
    let clocks = CLOCKS.load(Ordering::Relaxed) + ran;
    CLOCKS.store(clocks % CLOCKS_PER_MS, Ordering::Relaxed);
    // The low word's carry goes to the high word.
    let (low, wrapped) = MILLIS_LOW.load(Ordering::Relaxed).overflowing_add(clocks / CLOCKS_PER_MS);
    MILLIS_LOW.store(low, Ordering::Relaxed);
    let high = MILLIS_HIGH.load(Ordering::Relaxed).wrapping_add(u32::from(wrapped));
    MILLIS_HIGH.store(high, Ordering::Relaxed);
    u64::from(high) << 32 | u64::from(low)
}
