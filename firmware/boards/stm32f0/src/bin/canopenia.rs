//! CANopenIA on the STM32F042K6, the chip the manual also lists: [`coprocessor::run`]. It does
//! not fit the chip's 32 KiB of flash and 6 KiB of RAM yet, so it builds only with the feature
//! `canopenia-image` and `cargo xtask dist` lists it as pending, with the bytes it is over. The
//! same image on the STM32F091RC: `firmware/boards/stm32f091`.
#![no_std]
#![no_main]

use coforge_board_stm32f0::coprocessor;
use cortex_m_rt::entry;
use panic_halt as _;

#[entry]
fn main() -> ! {
    coprocessor::run()
}
