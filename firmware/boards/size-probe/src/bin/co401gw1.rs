//! co401gw1: the whole chip (dictionary, stack, process image, host protocol, DS401 events,
//! pins and error states) on a Cortex-M0, with a stand-in board whose pins the optimiser
//! cannot predict, so that the size report shows the device's code and its static RAM (see
//! `src/probe.rs`). No parameter store: its driver is the board's.
#![no_std]
#![no_main]

use co401gw1::{Board, Gw1};
use coforge_stack::store::NoStore;
use core::hint::black_box;
use panic_halt as _;

struct ProbeBoard;

impl Board for ProbeBoard {
    fn node_id_pins(&mut self) -> u16 {
        black_box(0x7A)
    }
    fn config_pins(&mut self) -> u16 {
        black_box(7)
    }
    fn input_pins(&mut self) -> u8 {
        black_box(0xFF)
    }
    fn emergency_pins(&mut self) -> u8 {
        black_box(3)
    }
    fn set_output_pins(&mut self, levels: u8) {
        black_box(levels);
    }
    fn set_indicators(&mut self, run_lit: bool, error_lit: bool, watchdog: bool) {
        black_box((run_lit, error_lit, watchdog));
    }
}

#[cortex_m_rt::entry]
fn main() -> ! {
    let chip = Gw1::new(ProbeBoard, NoStore);
    // The chip lives in .bss, so the size report shows its static RAM.
    let Some(chip) = cortex_m::singleton!(: Gw1<ProbeBoard, NoStore> = chip) else {
        loop {
            cortex_m::asm::wfi()
        }
    };
    probe::run(chip)
}
