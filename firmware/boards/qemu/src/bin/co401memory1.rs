//! CO401Memory1 on QEMU's lm3s6965evb: the serial host protocol on UART0, the module's CAN
//! side as an SLCAN adapter on UART1 (frames a host sends are what the node receives, frames
//! the node sends come back as SLCAN lines), the two EEPROM banks in RAM.
//!
//! ```text
//! qemu-system-arm -machine lm3s6965evb -nographic -kernel co401memory1 \
//!     -serial tcp:127.0.0.1:P0,server=on,wait=off,nodelay=on \
//!     -serial tcp:127.0.0.1:P1,server=on,wait=off,nodelay=on
//! ```
#![no_std]
#![no_main]

use co401memory1::{BANK_SIZE, FixedBoard, Memory1};
use coforge_board_qemu::{
    clock,
    uart::{UART0, UART1, Uart},
};
use coforge_stack::slcan::{self, Command};
use coforge_storage::ram::BorrowedEeprom;
use cortex_m_rt::entry;
use panic_semihosting as _;

/// Node-ID 5 on the ID pins, 1 Mbit/s, 9600 baud, a 24 V supply.
type Device = Memory1<BorrowedEeprom<'static>, FixedBoard>;

#[entry]
fn main() -> ! {
    // cortex-m-rt turns these into `&'static mut` (no unsafe): the banks live in .bss, and the
    // module only borrows them, so nothing large is built on the stack.
    static mut BANK1: [u8; BANK_SIZE] = [0; BANK_SIZE];
    static mut BANK2: [u8; BANK_SIZE] = [0; BANK_SIZE];
    let Some(core) = cortex_m::Peripherals::take() else { panic!("peripherals taken twice") };
    clock::start(core.SYST);
    let (host, can) = (Uart::new(UART0), Uart::new(UART1));
    let Ok(device) = Memory1::new([BorrowedEeprom::erased(BANK1), BorrowedEeprom::erased(BANK2)], FixedBoard::new(5)) else {
        panic!("reserved configuration pins")
    };
    // In a `MaybeUninit` static (.bss): an `Option` static would sit in .data, a second copy
    // of the module in flash.
    let Some(device) = cortex_m::singleton!(: Device = device) else { panic!("started twice") };
    device.start(0);
    let mut lines = slcan::Decoder::new();
    let mut answer = [0_u8; 16];
    let mut line = [0_u8; slcan::MAX_FRAME_LINE];
    loop {
        let ms = clock::millis();
        let now_us = u64::from(ms) * 1000;
        while let Some(byte) = host.read() {
            let n = device.on_serial_byte(byte, ms, &mut answer);
            host.write(answer.get(..n).unwrap_or(&[]));
        }
        while let Some(byte) = can.read() {
            if let Some(cmd) = lines.push(byte) {
                if let Command::Frame(frame) = cmd {
                    device.on_frame(&frame, now_us);
                }
                can.write(slcan::reply(&cmd));
            }
        }
        while let Some(frame) = device.poll(now_us) {
            let n = slcan::encode(&frame, &mut line);
            can.write(line.get(..n).unwrap_or(&[]));
        }
    }
}
