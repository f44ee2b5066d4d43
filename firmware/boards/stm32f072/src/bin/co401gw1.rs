//! The CO401GW1 gateway on the STM32F072CB: [`gw1::run`] of the STM32F0 board library, built
//! for this chip. The F072CB in LQFP48 is pin-compatible with the STM32F042C6 the gateway's
//! board was drawn for, and has the room the gateway needs (128 KiB flash, 16 KiB RAM): the
//! same board with this chip in place of the F042C6. Pin map:
//! `firmware/boards/stm32f0/PINS-co401gw1.md`.
//!
//! `cargo build --release` here, then `cargo xtask flash --device co401gw1 --board stm32f072`
//! (chip `STM32F072CBTx`; or `probe-rs run --chip STM32F072CBTx <elf>`).
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
