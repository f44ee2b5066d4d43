//! cr3101: the generated dictionary (read and write through the dispatch, defaults, the
//! persistent block), kept alive by black_box. The CANmem has no serial protocol.
#![no_std]
#![no_main]

use coforge_stack::od::{AccessContext, NmtState, NoAppObjects, ObjectDictionary, Side};
use core::hint::black_box;
use cr3101::{Mode, Od};
use panic_halt as _;

#[cortex_m_rt::entry]
fn main() -> ! {
    let mut od = Od::new(black_box(Mode::ALL[0]), black_box(0x20), NoAppObjects);
    let ctx = AccessContext { nmt: NmtState::Operational, can_enabled: true };
    let mut buf = [0_u8; 64];
    let mut block = [0_u8; Od::<NoAppObjects>::PERSISTENT_SIZE];
    loop {
        let (index, sub) = black_box((0x1018_u16, 1_u8));
        let _ = black_box(od.read(index, sub, 0, &mut buf, Side::Bus));
        let _ = black_box(od.write(index, sub, black_box(&buf[..4]), Side::Bus, &ctx));
        let _ = black_box(od.save_persistent(&mut block));
    }
}
