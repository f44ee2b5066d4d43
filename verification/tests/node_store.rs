//! The 1010h parameter block on an `embedded-storage` device: what is saved comes back, and
//! a corrupt or torn block is ignored so the node keeps the spec defaults.

use co401gw1::{Mode, Od};
use coforge_stack::od::{AccessContext, Area, NmtState, NoAppObjects, ObjectDictionary, Side};
use coforge_stack::store::{BlockStore, ParamStore};
use coforge_verification::node::RamStorage;

const PREOP: AccessContext = AccessContext { nmt: NmtState::PreOperational, can_enabled: true };

fn guard_time(od: &mut Od<NoAppObjects>) -> u16 {
    let mut buf = [0; 2];
    od.read(0x100C, 0, 0, &mut buf, Side::Device).expect("100Ch exists");
    u16::from_le_bytes(buf)
}

fn saved_block() -> BlockStore<RamStorage<1024>> {
    let mut od = Od::new(Mode::Mixed, 5, NoAppObjects);
    od.write(0x100C, 0, &500_u16.to_le_bytes(), Side::Bus, &PREOP).expect("writable in pre-operational");
    let mut store = BlockStore::new(RamStorage([0xFF; 1024]), 0);
    store.save(&od, Area::ALL).expect("fits");
    store
}

#[test]
fn a_saved_block_loads_back() {
    let mut store = saved_block();
    let mut fresh = Od::new(Mode::Mixed, 5, NoAppObjects);
    assert_eq!(store.load(&mut fresh, Area::ALL), Ok(true));
    assert_eq!(guard_time(&mut fresh), 500);
}

#[test]
fn every_corrupted_byte_falls_back_to_defaults() {
    let len = 12 + <Od<NoAppObjects> as coforge_stack::od::Dictionary>::PERSISTENT_SIZE;
    for at in 0..len {
        let mut image = saved_block().into_inner();
        // Every byte of header (magic, length, CRC, reserved) and data.
        image.0[at] ^= 0x5A;
        let mut store = BlockStore::new(image, 0);
        let mut fresh = Od::new(Mode::Mixed, 5, NoAppObjects);
        assert_eq!(store.load(&mut fresh, Area::ALL), Ok(false), "corrupted byte {at} was accepted");
        assert_eq!(guard_time(&mut fresh), 0, "defaults stay after a rejected block (byte {at})");
    }
}

#[test]
fn erase_and_a_too_small_device_are_handled() {
    let mut store = saved_block();
    store.erase().expect("writable");
    let mut fresh = Od::new(Mode::Mixed, 5, NoAppObjects);
    assert_eq!(store.load(&mut fresh, Area::ALL), Ok(false), "1011h: nothing valid stored");
    let od = Od::new(Mode::Mixed, 5, NoAppObjects);
    let mut tiny = BlockStore::new(RamStorage([0xFF; 16]), 0);
    assert!(tiny.save(&od, Area::ALL).is_err(), "a block larger than the device is refused");
}
