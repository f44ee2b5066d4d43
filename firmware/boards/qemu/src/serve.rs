//! The images' main loop: the serial host protocol on UART0, the module's CAN side as an
//! SLCAN adapter on UART1 (frames a host sends are what the node receives, frames the node
//! sends come back as SLCAN lines).

use crate::clock;
use crate::uart::{UART0, UART1, Uart};
use co401memory1::{FixedBoard, Memory1};
use coforge_slcan::{self as slcan, Command};
use embedded_storage::Storage;

/// Starts the module and serves both UARTs for ever.
pub fn run<S: Storage>(device: &mut Memory1<S, FixedBoard>) -> ! {
    let (host, can) = (Uart::new(UART0), Uart::new(UART1));
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

/// The body of each CO401Memory1 image's `main`: takes the core peripherals, starts the
/// clock, builds the module on `banks` (node-ID 5 on the pins, 1 Mbit/s, 9600 baud, 24 V) in
/// a `MaybeUninit` static and serves it. A macro, since `singleton!` needs the module's
/// concrete type (an `Option` static would sit in .data: a second copy of it in flash). The
/// module is built in a function of its own, so that its construction's temporaries (about
/// 1.3 KiB) leave the stack before the loop starts.
#[macro_export]
macro_rules! serve_memory1 {
    ($storage:ty, $banks:expr) => {{
        type Device = co401memory1::Memory1<$storage, co401memory1::FixedBoard>;
        #[inline(never)]
        fn mount(banks: [$storage; 2]) -> &'static mut Device {
            let Ok(device) = co401memory1::Memory1::new(banks, co401memory1::FixedBoard::new(5)) else { panic!("reserved configuration pins") };
            let Some(device) = cortex_m::singleton!(: Device = device) else { panic!("started twice") };
            device
        }
        let Some(core) = cortex_m::Peripherals::take() else { panic!("peripherals taken twice") };
        $crate::clock::start(core.SYST);
        $crate::serve::run(mount($banks))
    }};
}
