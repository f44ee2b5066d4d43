//! CO401GW1 on the STM32F042C6 board (LQFP48): [`gw1::run`] of the board library. CAN on
//! bxCAN at the BD pins' bit rate, the gateway's host protocol on USART2 at the RSBD pins'
//! baud rate, the parameters of 1010h/1011h in a 24C128 EEPROM on I2C1. Pin map:
//! `PINS-co401gw1.md` and the `coforge_board_stm32f0` crate documentation.
//!
//! `cargo build --release` here, then `cargo xtask flash --device co401gw1 --board stm32f0
//! --chip STM32F042C6Tx` (or `probe-rs run --chip STM32F042C6Tx <elf>`).
#![no_std]
#![no_main]

use coforge_board_stm32f0::gw1::{self, Chip};
use core::mem::MaybeUninit;
use cortex_m_rt::entry;
use panic_halt as _;

#[entry]
fn main() -> ! {
    // cortex-m-rt turns this into a `&'static mut` (no unsafe): see `gw1::run`.
    static mut CHIP: MaybeUninit<Chip> = MaybeUninit::uninit();
    gw1::run(CHIP)
}
