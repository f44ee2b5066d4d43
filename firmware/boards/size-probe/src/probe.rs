//! One image per device: the generated dictionary (read and write through the dispatch,
//! defaults, the persistent block) and, if the device has one, its serial codecs (deframe,
//! decode, encode). `black_box` keeps everything from being optimised away.

/// `probe!(device, node_id)` or `probe!(device, node_id, serial)`.
macro_rules! probe {
    ($device:ident, $node_id:expr $(, $serial:ident)?) => {
        use coforge_stack::od::{AccessContext, NmtState, NoAppObjects, ObjectDictionary, Side};
        use core::hint::black_box;
        use panic_halt as _;

        #[cortex_m_rt::entry]
        fn main() -> ! {
            let mut od = $device::Od::new(black_box($device::Mode::ALL[0]), black_box($node_id), NoAppObjects);
            let ctx = AccessContext { nmt: NmtState::Operational, can_enabled: true };
            let mut buf = [0_u8; 64];
            let mut block = [0_u8; $device::Od::<NoAppObjects>::PERSISTENT_SIZE];
            $(let mut decoder = $device::$serial::decoder();)?
            loop {
                let (index, sub) = black_box((0x1018_u16, 1_u8));
                let _ = black_box(od.read(index, sub, 0, &mut buf, Side::Bus));
                let _ = black_box(od.write(index, sub, black_box(&buf[..4]), Side::Host, &ctx));
                let _ = black_box(od.save_persistent(&mut block));
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
