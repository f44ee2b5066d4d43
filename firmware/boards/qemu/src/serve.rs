//! The images' main loop, for any device: its serial host port (if it has one) on UART0, its
//! CAN side as an SLCAN adapter on UART1 (frames a host sends are what the node receives,
//! frames the node sends come back as SLCAN lines), and whatever else an image adds through
//! [`serve_with`]'s hook (CO401GW1's pin console on UART2).

use crate::clock;
use crate::uart::{UART0, UART1, Uart};
use coforge_slcan::{self as slcan, Command};
use coforge_stack::device::Device;

/// Starts the clock and the device and serves both UARTs for ever.
pub fn serve<D: Device>(device: &mut D) -> ! {
    serve_with(device, |_, _| {})
}

/// As [`serve`], and `hook` is called on every pass of the loop with the device and the
/// time in milliseconds, after the two UARTs and before the device is polled (so that what
/// the hook changed is seen in the same pass).
pub fn serve_with<D: Device>(device: &mut D, mut hook: impl FnMut(&mut D, u64)) -> ! {
    let Some(core) = cortex_m::Peripherals::take() else { panic!("peripherals taken twice") };
    clock::start(core.SYST);
    let (mut host, mut can) = (Uart::new(UART0), Uart::new(UART1));
    device.start(0);
    let mut lines = slcan::Decoder::new();
    let mut line = [0_u8; slcan::MAX_FRAME_LINE];
    loop {
        let now_ms = clock::millis();
        let now_us = now_ms * 1000;
        if let Some(port) = device.host_port() {
            while let Some(byte) = host.read() {
                port.on_host_byte(byte, now_ms);
            }
            // Polled on every pass, not only after a byte: answers may come late or unasked.
            // One byte at a time: the UART sends no faster anyway.
            let mut byte = [0];
            while port.host_output(now_ms, &mut byte) == 1 {
                host.write(&byte);
            }
        }
        while let Some(byte) = can.read() {
            if let Some(cmd) = lines.push(byte) {
                if let Command::Frame(frame) = cmd {
                    device.on_frame(&frame, now_us);
                }
                can.write(slcan::reply(&cmd));
            }
        }
        hook(device, now_ms);
        while let Some(frame) = device.poll(now_us) {
            let n = slcan::encode(&frame, &mut line);
            can.write(line.get(..n).unwrap_or(&[]));
        }
    }
}
