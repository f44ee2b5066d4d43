//! co401memory1: the whole module (dictionary, stack, mirrored banks, serial host protocol,
//! monitoring, supply guard) on a Cortex-M0, with stand-ins for the two I2C EEPROMs and the
//! board so that the size report shows the device's code and its static RAM (see
//! `src/probe.rs`).
#![no_std]
#![no_main]

use co401memory1::{Board, Memory1, StatusOutputs};
use core::hint::black_box;
use panic_halt as _;

/// An external EEPROM whose bytes the optimiser cannot predict.
struct ProbeEeprom;

impl embedded_storage::ReadStorage for ProbeEeprom {
    type Error = ();
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), ()> {
        bytes.iter_mut().for_each(|b| *b = black_box(offset as u8));
        black_box(Ok(()))
    }
    fn capacity(&self) -> usize {
        co401memory1::BANK_SIZE
    }
}

impl embedded_storage::Storage for ProbeEeprom {
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), ()> {
        black_box((offset, bytes));
        black_box(Ok(()))
    }
}

struct ProbeBoard;

impl Board for ProbeBoard {
    fn node_id_pins(&mut self) -> u16 {
        black_box(0x7A)
    }
    fn can_bitrate_pins(&mut self) -> u16 {
        black_box(7)
    }
    fn serial_bitrate_pins(&mut self) -> u16 {
        black_box(7)
    }
    fn config_pins(&mut self) -> u16 {
        black_box(7)
    }
    fn supply_mv(&mut self) -> u16 {
        black_box(24_000)
    }
    fn set_outputs(&mut self, outputs: StatusOutputs) {
        black_box(outputs);
    }
}

#[cortex_m_rt::entry]
fn main() -> ! {
    let Ok(device) = Memory1::new([ProbeEeprom, ProbeEeprom], ProbeBoard) else {
        loop {
            cortex_m::asm::wfi()
        }
    };
    // The module lives in .bss, so the size report shows its static RAM.
    let Some(device) = cortex_m::singleton!(: Memory1<ProbeEeprom, ProbeBoard> = device) else {
        loop {
            cortex_m::asm::wfi()
        }
    };
    probe::run(device)
}
