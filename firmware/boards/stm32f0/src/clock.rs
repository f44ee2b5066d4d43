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

/// Every image's first step: the core clock at [`CORE_HZ`] (the 8 MHz crystal x 6, or the
/// HSI48 with the `hsi48` feature), then the SysTick millisecond clock.
pub fn start_core(rcc: stm32f0xx_hal::pac::RCC, flash: &mut stm32f0xx_hal::pac::FLASH, syst: cortex_m::peripheral::SYST) -> stm32f0xx_hal::rcc::Rcc {
    use stm32f0xx_hal::prelude::*;
    #[cfg(not(feature = "hsi48"))]
    let cfgr = rcc.configure().hse(8.mhz(), stm32f0xx_hal::rcc::HSEBypassMode::NotBypassed);
    #[cfg(feature = "hsi48")]
    let cfgr = rcc.configure().hsi48();
    let rcc = cfgr.sysclk(48.mhz()).pclk(48.mhz()).freeze(flash);
    start(syst);
    rcc
}
