//! CR3101's card layer on QEMU's SD card (`-drive if=sd,format=raw,file=card.img`): mounts the
//! card through `embedded-sdmmc` on SSI0, lays out two data files, writes 200 records into the
//! first (saying `record n` after each, so a test can cut the power at a known point), reads
//! one back, unmounts and exits 0 through semihosting (1 on any failure, with the reason). `tests/python/test_cr3101_card.py` then reads the card with mtools and checks it
//! with `fsck.fat -n`. A fixture for the card layer until the CR3101 device image exists.
#![no_std]
#![no_main]

use coforge_board_qemu::sd::{SdSpi, SpinDelay};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use cr3101::card::files::Card;
use cr3101::card::record::Record;
use cr3101::card::sample::{layout, record};
use embedded_sdmmc::{SdCard, TimeSource, Timestamp};
use panic_semihosting as _;

/// 2026-12-03 06:30:00, as the test expects in the directory entries.
struct Clock;

impl TimeSource for Clock {
    fn get_timestamp(&self) -> Timestamp {
        Timestamp { year_since_1970: 56, zero_indexed_month: 11, zero_indexed_day: 2, hours: 6, minutes: 30, seconds: 0 }
    }
}

fn fail(what: &str) -> ! {
    hprintln!("cr3101-card: {}", what);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}

#[entry]
fn main() -> ! {
    let sd = SdCard::new(SdSpi::new(), SpinDelay);
    let Ok(mut card) = Card::mount(sd, Clock) else { fail("mount") };
    let len = layout().len() as u32;
    if card.lay_out(0, "OIL_TEMP.DAT", 200 * len, false).is_err() || card.lay_out(2, "PRESS.DAT", 4096, false).is_err() {
        fail("lay out");
    }
    hprintln!("cr3101-card: laid out");
    for n in 0..200 {
        if card.write_at(0, n * len, record(n).as_bytes()).is_err() {
            fail("write a record");
        }
        hprintln!("record {}", n);
    }
    let mut back = [0_u8; 16];
    if card.read_at(0, 123 * len, &mut back).is_err() || Record::from_bytes(&layout(), &back) != Some(record(123)) {
        fail("read record 123 back");
    }
    let _ = card.unmount();
    hprintln!("cr3101-card: 200 records written");
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::wfi();
    }
}
