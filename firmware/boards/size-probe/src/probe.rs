//! What each image measures, for any device: its CANopen node (the generated dictionary and
//! every protocol engine of coforge-stack, fed frames from the bus), its serial host port if
//! it has one, and for a plain node the serial codecs of its spec (deframe, decode, encode).
//! `black_box` keeps everything from being optimised away.
#![no_std]

use coforge_link::{Deframer, Message, SerialCodec};
use coforge_stack::device::Device;
use coforge_stack::frame::CanFrame;
use core::hint::black_box;

/// Drives `device` for ever.
pub fn run<D: Device>(device: &'static mut D) -> ! {
    drive(device, || {})
}

/// Drives `device` for ever, and the codecs `C` beside it.
pub fn run_with_codec<D: Device, C: SerialCodec>(device: &'static mut D) -> ! {
    let mut decoder = C::decoder();
    let mut buf = [0_u8; 64];
    drive(device, move || {
        if let Some(Ok(frame)) = decoder.push(black_box(0x11), black_box(0))
            && let Ok(cmd) = C::HostToDevice::decode(&frame)
        {
            let _ = black_box(cmd.encode(&mut buf));
        }
    })
}

fn drive<D: Device>(device: &'static mut D, mut codec: impl FnMut()) -> ! {
    device.start(0);
    let (mut now, mut now_ms) = (0_u64, 0_u64);
    let mut out = [0_u8; 16];
    loop {
        now += 1000;
        now_ms += 1;
        let frame = CanFrame { id: black_box(0x605), rtr: black_box(false), dlc: 8, data: black_box([0x40, 0x18, 0x10, 1, 0, 0, 0, 0]) };
        device.on_frame(&frame, now);
        while let Some(sent) = device.poll(now) {
            black_box(sent);
        }
        if let Some(port) = device.host_port() {
            port.on_host_byte(black_box(0x33), now_ms);
            let n = port.host_output(now_ms, &mut out);
            black_box(out.get(..n));
        }
        codec();
    }
}
