//! canopenia: the whole coprocessor (dictionary, stack, manager with its scan cache,
//! remote-access engine) on a Cortex-M0, so that the size report shows the device's code and
//! its static RAM (see `src/probe.rs`). No parameter store: its driver is the board's.
#![no_std]
#![no_main]

use canopenia::Canopenia;
use coforge_stack::store::NoStore;
use core::hint::black_box;
use panic_halt as _;

#[cortex_m_rt::entry]
fn main() -> ! {
    let chip = Canopenia::new(black_box(1), NoStore);
    // The coprocessor lives in .bss, so the size report shows its static RAM.
    let Some(chip) = cortex_m::singleton!(: Canopenia<NoStore> = chip) else {
        loop {
            cortex_m::asm::wfi()
        }
    };
    probe::run(chip)
}
