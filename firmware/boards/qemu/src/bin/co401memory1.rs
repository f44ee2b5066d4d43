//! CO401Memory1 on QEMU's lm3s6965evb: the serial host protocol on UART0, the module's CAN
//! side as an SLCAN adapter on UART1 (see `serve`), the two EEPROM banks in RAM.
//!
//! ```text
//! qemu-system-arm -machine lm3s6965evb -nographic -kernel co401memory1 \
//!     -serial tcp:127.0.0.1:P0,server=on,wait=off,nodelay=on \
//!     -serial tcp:127.0.0.1:P1,server=on,wait=off,nodelay=on
//! ```
#![no_std]
#![no_main]

use co401memory1::{BANK_SIZE, ConfigError, FixedBoard, Memory1};
use coforge_board_qemu::serve::serve;
use coforge_storage::ram::RamEeprom;
use cortex_m_rt::entry;
use panic_semihosting as _;

type Bank = RamEeprom<&'static mut [u8; BANK_SIZE]>;
type Device = Memory1<Bank, FixedBoard>;

#[entry]
fn main() -> ! {
    // cortex-m-rt turns these into `&'static mut` (no unsafe): the banks live in .bss, and the
    // module only borrows them, so nothing large is built on the stack.
    static mut BANK1: [u8; BANK_SIZE] = [0; BANK_SIZE];
    static mut BANK2: [u8; BANK_SIZE] = [0; BANK_SIZE];
    serve(mount([RamEeprom::erased(BANK1), RamEeprom::erased(BANK2)]))
}

/// The module (node-ID 5 on the pins, 1 Mbit/s, 9600 baud, 24 V) in a `MaybeUninit` static
/// (an `Option` static would sit in .data: a second copy in flash), built right there rather
/// than moved in. Built in a function of its own, so that its construction's temporaries
/// (about 1.3 KiB) leave the stack before the loop starts.
#[inline(never)]
fn mount(banks: [Bank; 2]) -> &'static mut Device {
    let Some(Ok(device)) = cortex_m::singleton!(: Result<Device, ConfigError> = Memory1::new(banks, FixedBoard::new(5))) else {
        panic!("started twice, or reserved configuration pins")
    };
    device
}
