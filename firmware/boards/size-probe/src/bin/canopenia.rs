//! canopenia: the generated dictionary (read and write through the dispatch, defaults, the
//! persistent block) and the serial codecs (deframe, decode, encode), kept alive by black_box.
#![no_std]
#![no_main]

use coforge_link::Deframer;
use coforge_stack::od::{AccessContext, NmtState, NoAppObjects, ObjectDictionary, Side};
use core::hint::black_box;
use canopenia::{Mode, Od, serial};
use panic_halt as _;

#[cortex_m_rt::entry]
fn main() -> ! {
    let mut od = Od::new(black_box(Mode::ALL[0]), black_box(5), NoAppObjects);
    let mut decoder = serial::decoder();
    let ctx = AccessContext { nmt: NmtState::Operational, can_enabled: true };
    let mut buf = [0_u8; 64];
    let mut block = [0_u8; Od::<NoAppObjects>::PERSISTENT_SIZE];
    loop {
        let (index, sub) = black_box((0x1018_u16, 1_u8));
        let _ = black_box(od.read(index, sub, 0, &mut buf, Side::Bus));
        let _ = black_box(od.write(index, sub, black_box(&buf[..4]), Side::Host, &ctx));
        let _ = black_box(od.save_persistent(&mut block));
        if let Some(Ok(frame)) = decoder.push(black_box(0x11), black_box(0))
            && let Ok(cmd) = serial::HostToDevice::decode(&frame)
        {
            let _ = black_box(cmd.encode(&mut buf));
        }
    }
}
