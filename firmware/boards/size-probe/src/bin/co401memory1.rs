//! co401memory1: the whole module (dictionary, stack, mirrored banks, serial host protocol,
//! monitoring, supply guard) on a Cortex-M0, with stand-ins for the two I2C EEPROMs and the
//! board so that the size report shows the device's code and its static RAM.
#![no_std]
#![no_main]

use co401memory1::{Board, Memory1, StatusOutputs};
use coforge_stack::frame::CanFrame;
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
    let Ok(device) = Memory1::new([ProbeEeprom, ProbeEeprom], ProbeBoard) else { loop {} };
    // The module lives in .bss, so the size report shows its static RAM.
    let Some(device) = cortex_m::singleton!(: Memory1<ProbeEeprom, ProbeBoard> = device) else { loop {} };
    device.start(0);
    let mut now = 0_u64;
    let mut answer = [0_u8; 16];
    loop {
        now += 1000;
        let frame = CanFrame { id: black_box(0x605), rtr: black_box(false), dlc: 8, data: black_box([0x40, 0x18, 0x10, 1, 0, 0, 0, 0]) };
        device.on_frame(&frame, now);
        while let Some(out) = device.poll(now) {
            black_box(out);
        }
        let n = device.on_serial_byte(black_box(0x33), black_box(now as u32), &mut answer);
        black_box(answer.get(..n));
    }
}
