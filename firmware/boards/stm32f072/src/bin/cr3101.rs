//! The CR3101 CANmem data logger on the STM32F072CB: [`cr3101::run`] of the STM32F0 board
//! library, built for this chip. Pin map: `PINS.md`.
//!
//! `cargo build --release` here, then `cargo xtask flash --device cr3101 --board stm32f072`
//! (chip `STM32F072CBTx`; or `probe-rs run --chip STM32F072CBTx <elf>`).
#![no_std]
#![no_main]

use coforge_board_stm32f0::cr3101;
use cortex_m_rt::entry;
use panic_halt as _;

#[entry]
fn main() -> ! {
    cr3101::run()
}
