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

use co401memory1::BANK_SIZE;
use coforge_storage::ram::RamEeprom;
use cortex_m_rt::entry;
use panic_semihosting as _;

#[entry]
fn main() -> ! {
    // cortex-m-rt turns these into `&'static mut` (no unsafe): the banks live in .bss, and the
    // module only borrows them, so nothing large is built on the stack.
    static mut BANK1: [u8; BANK_SIZE] = [0; BANK_SIZE];
    static mut BANK2: [u8; BANK_SIZE] = [0; BANK_SIZE];
    coforge_board_qemu::serve_memory1!(RamEeprom<&'static mut [u8]>, [RamEeprom::erased(BANK1), RamEeprom::erased(BANK2)])
}
