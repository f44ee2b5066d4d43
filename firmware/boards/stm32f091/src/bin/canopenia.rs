//! CANopenIA on the STM32F091RC: [`coprocessor::run`] of the STM32F0 board library, built for
//! this chip. Pin map: `PINS.md`.
//!
//! `cargo build --release` here, then `cargo xtask flash --device canopenia --board stm32f091`
//! (chip `STM32F091RCTx`; or `probe-rs run --chip STM32F091RCTx <elf>`).
#![no_std]
#![no_main]

use coforge_board_stm32f0::coprocessor;
use cortex_m_rt::entry;
use panic_halt as _;

#[entry]
fn main() -> ! {
    coprocessor::run()
}
