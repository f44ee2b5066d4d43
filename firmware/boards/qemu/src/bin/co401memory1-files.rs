//! CO401Memory1 on QEMU's lm3s6965evb, as `co401memory1`, but with the two EEPROM banks kept
//! in the host files `co401memory1.bank1` and `co401memory1.bank2` (QEMU's working
//! directory) through semihosting: stop the image, start it again, and the memory is as the
//! module left it, with what a power cut would have left if QEMU was killed in a write.
//!
//! ```text
//! qemu-system-arm -machine lm3s6965evb -nographic -semihosting-config enable=on,target=native \
//!     -kernel co401memory1-files \
//!     -serial tcp:127.0.0.1:P0,server=on,wait=off,nodelay=on \
//!     -serial tcp:127.0.0.1:P1,server=on,wait=off,nodelay=on
//! ```
#![no_std]
#![no_main]

use co401memory1::{BANK_SIZE, ConfigError, FixedBoard, Memory1};
use coforge_board_qemu::host_file::HostFileEeprom;
use coforge_board_qemu::serve::serve;
use cortex_m_rt::entry;
use panic_semihosting as _;

type Device = Memory1<HostFileEeprom<'static>, FixedBoard>;

#[entry]
fn main() -> ! {
    // The banks' RAM images, in .bss (cortex-m-rt makes them `&'static mut`, no unsafe).
    static mut BANK1: [u8; BANK_SIZE] = [0; BANK_SIZE];
    static mut BANK2: [u8; BANK_SIZE] = [0; BANK_SIZE];
    let (Ok(bank1), Ok(bank2)) = (HostFileEeprom::open("co401memory1.bank1\0", BANK1), HostFileEeprom::open("co401memory1.bank2\0", BANK2)) else {
        panic!("cannot open the bank files (is semihosting enabled?)")
    };
    serve(mount([bank1, bank2]))
}

/// The module in a static, built in a frame of its own (see `co401memory1`).
#[inline(never)]
fn mount(banks: [HostFileEeprom<'static>; 2]) -> &'static mut Device {
    let Some(Ok(device)) = cortex_m::singleton!(: Result<Device, ConfigError> = Memory1::new(banks, FixedBoard::new(5))) else {
        panic!("started twice, or reserved configuration pins")
    };
    device
}
