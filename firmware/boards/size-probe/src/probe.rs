//! One image per device: its CANopen node (the generated dictionary and every protocol
//! engine of coforge-stack, fed frames from the bus) and, if the device has one, its serial
//! codecs (deframe, decode, encode). `black_box` keeps everything from being optimised away.

/// `probe!(device, node_id)` or `probe!(device, node_id, serial)`.
macro_rules! probe {
    ($device:ident, $node_id:expr $(, $serial:ident)?) => {
        use coforge_stack::frame::CanFrame;
        use coforge_stack::od::NoAppObjects;
        use coforge_stack::store::NoStore;
        use core::hint::black_box;
        use panic_halt as _;

        #[cortex_m_rt::entry]
        fn main() -> ! {
            let od = $device::Od::new(black_box($device::Mode::ALL[0]), black_box($node_id), NoAppObjects);
            let node = coforge_stack::node::Node::new(od, NoStore, $device::node_config($node_id));
            // The node lives in .bss (a `MaybeUninit` static), so the size report shows its
            // static RAM and no copy of it in flash.
            let Some(node) = cortex_m::singleton!(: $device::Node<NoAppObjects, NoStore> = node) else { loop {} };
            node.start(0);
            let mut now = 0_u64;
            #[allow(unused_mut, unused_variables)]
            let mut buf = [0_u8; 64];
            $(let mut decoder = $device::$serial::decoder();)?
            loop {
                now += 1000;
                let frame = CanFrame { id: black_box(0x601), rtr: black_box(false), dlc: 8, data: black_box([0x40, 0x18, 0x10, 1, 0, 0, 0, 0]) };
                node.on_frame(&frame, now);
                while let Some(out) = node.poll(now) {
                    black_box(out);
                }
                $(
                    use coforge_link::Deframer as _;
                    if let Some(Ok(frame)) = decoder.push(black_box(0x11), black_box(0))
                        && let Ok(cmd) = $device::$serial::HostToDevice::decode(&frame)
                    {
                        let _ = black_box(cmd.encode(&mut buf));
                    }
                )?
            }
        }
    };
}
