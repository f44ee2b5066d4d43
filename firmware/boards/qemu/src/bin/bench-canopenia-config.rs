//! CANopenIA's start with a loaded configuration, for `cargo xtask bench`: the vendor's CiA 401
//! file active in the configuration memory (stored as a download leaves it), then one start
//! measured: the file checked again and every value of it written into the dictionary, the
//! work of every power-on and reset. Apart from `bench-canopenia` so that a second coprocessor
//! type does not change how the first one is compiled.
#![no_std]
#![no_main]

use canopenia::Canopenia;
use canopenia::config::slots::{ConfigSlots, SLOT};
use coforge_board_qemu::bench::{Answers, fail, finish, measure, paint_stack, stack_peak};
use coforge_stack::device::Device;
use coforge_stack::store::BlockStore;
use coforge_storage::ram::RamEeprom;
use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use panic_semihosting as _;

const PARAMS: usize = 2048;
const FILES: usize = 2 * SLOT;
type Files = RamEeprom<&'static mut [u8; FILES]>;
type Chip = Canopenia<BlockStore<RamEeprom<&'static mut [u8; PARAMS]>>, Files>;
/// The vendor's CiA 401 configuration (node-ID 3).
const VENDOR_401: &[u8] = include_bytes!("../../../../../tests/vendor-data/canopenia/CiA401_IO_Node3.bin");

const NAMES: [&str; 2] = ["calibration (empty)", "start with the vendor's CiA 401 file active (checked, every value applied)"];

/// The coprocessor, its configuration memory holding the vendor's file.
#[inline(never)]
fn mount(params: RamEeprom<&'static mut [u8; PARAMS]>, files: Files) -> &'static mut Chip {
    let mut slots = ConfigSlots::new(files);
    let stored = slots.begin().and_then(|()| slots.write(0, VENDOR_401));
    let crc = u16::from_le_bytes([VENDOR_401[VENDOR_401.len() - 2], VENDOR_401[VENDOR_401.len() - 1]]);
    if stored.is_err() || slots.downloaded().is_none() || slots.commit(VENDOR_401.len(), crc).is_err() {
        fail("store the vendor's file", &Answers::NONE);
    }
    let files = slots.into_memory();
    let Some(chip) = cortex_m::singleton!(: Chip = Canopenia::with_configuration(2, BlockStore::new(params, 0), files)) else { panic!("mounted twice") };
    chip
}

#[entry]
fn main() -> ! {
    static mut PARAMETERS: [u8; PARAMS] = [0; PARAMS];
    static mut FILE_SLOTS: [u8; FILES] = [0; FILES];
    paint_stack();
    let chip = mount(RamEeprom::erased(PARAMETERS), RamEeprom::erased(FILE_SLOTS));
    hprintln!("stack-peak-setup-bytes: {}", stack_peak());
    paint_stack();

    measure(0, || {});
    measure(1, || chip.start(0));
    if chip.node().node_id() != 3 || chip.config_write_errors != 0 {
        fail("the vendor's file: node-ID 3, every value taken", &Answers::NONE);
    }
    finish(&NAMES, stack_peak())
}
