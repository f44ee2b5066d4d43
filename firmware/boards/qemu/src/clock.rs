//! A millisecond clock from SysTick's counter.

/// The core clock QEMU gives the lm3s6965evb after reset (the 12 MHz main oscillator).
pub const CORE_HZ: u32 = 12_000_000;

include!("../../systick_millis.rs");
