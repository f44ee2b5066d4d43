//! The 1010h parameter block on an `embedded-storage` device: what is saved comes back, and
//! a corrupt or torn block is ignored so the node keeps the spec defaults.

use co401gw1::{Mode, Od};
use coforge_stack::od::NodeDictionary;
use coforge_stack::od::{AccessContext, Area, EntryAccess, NmtState, NoAppObjects, Side};
use coforge_stack::store::{BlockStore, MAX_SLOTS, ParamStore};
use coforge_storage::ram::RamEeprom;

const PREOP: AccessContext = AccessContext { nmt: NmtState::PreOperational, can_enabled: true };

fn guard_time(od: &mut Od<NoAppObjects>) -> u16 {
    let mut buf = [0; 2];
    od.read(0x100C, 0, 0, &mut buf, Side::Device).expect("100Ch exists");
    u16::from_le_bytes(buf)
}

fn saved_block() -> BlockStore<RamEeprom<[u8; 2048]>> {
    let mut od = Od::new(Mode::Mixed, 5, NoAppObjects);
    od.write(0x100C, 0, &500_u16.to_le_bytes(), Side::Bus, &PREOP).expect("writable in pre-operational");
    let mut store = BlockStore::new(RamEeprom::new(), 0);
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
    let len = 12 + <Od<NoAppObjects> as coforge_stack::od::NodeDictionary>::PERSISTENT_SIZE;
    for at in 0..len {
        let mut image = saved_block().into_inner();
        // Every byte of header (magic, length, CRC, reserved) and data.
        image.as_bytes_mut()[at] ^= 0x5A;
        let mut store = BlockStore::new(image, 0);
        let mut fresh = Od::new(Mode::Mixed, 5, NoAppObjects);
        assert_eq!(store.load(&mut fresh, Area::ALL), Ok(false), "corrupted byte {at} was accepted");
        assert_eq!(guard_time(&mut fresh), 0, "defaults stay after a rejected block (byte {at})");
    }
}

#[test]
fn erase_and_a_too_small_device_are_handled() {
    let mut store = saved_block();
    store.erase(&Od::new(Mode::Mixed, 5, NoAppObjects)).expect("writable");
    let mut fresh = Od::new(Mode::Mixed, 5, NoAppObjects);
    assert_eq!(store.load(&mut fresh, Area::ALL), Ok(false), "1011h: nothing valid stored");
    let od = Od::new(Mode::Mixed, 5, NoAppObjects);
    let mut tiny = BlockStore::new(RamEeprom::<[u8; 16]>::new(), 0);
    assert!(tiny.save(&od, Area::ALL).is_err(), "a block larger than the device is refused");
}

/// A storage device that fails every write after `budget` of them: a save torn at any point.
#[derive(Debug)]
struct Torn {
    image: RamEeprom<[u8; 2048]>,
    budget: usize,
}

impl embedded_storage::ReadStorage for Torn {
    type Error = ();
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), ()> {
        self.image.read(offset, bytes).map_err(|_| ())
    }
    fn capacity(&self) -> usize {
        self.image.capacity()
    }
}

impl embedded_storage::Storage for Torn {
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), ()> {
        if self.budget == 0 {
            return Err(());
        }
        self.budget -= 1;
        self.image.write(offset, bytes).map_err(|_| ())
    }
}

/// Bytes of one slot: header and block.
const SLOT: usize = 12 + <Od<NoAppObjects> as NodeDictionary>::PERSISTENT_SIZE;

/// A storage device that counts the writes that land in each slot.
#[derive(Debug)]
struct Counting {
    image: RamEeprom<[u8; 2048]>,
    writes: Vec<usize>,
}

impl embedded_storage::ReadStorage for Counting {
    type Error = ();
    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), ()> {
        self.image.read(offset, bytes).map_err(|_| ())
    }
    fn capacity(&self) -> usize {
        self.image.capacity()
    }
}

impl embedded_storage::Storage for Counting {
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), ()> {
        let slot = offset as usize / SLOT;
        if self.writes.len() <= slot {
            self.writes.resize(slot + 1, 0);
        }
        self.writes[slot] += 1;
        self.image.write(offset, bytes).map_err(|_| ())
    }
}

#[test]
fn saves_go_round_the_ring_and_a_save_of_what_is_stored_writes_nothing() {
    let slots = (2048 / SLOT).min(MAX_SLOTS as usize);
    assert!(slots > 2, "{slots} slots of {SLOT} bytes");
    let mut store = BlockStore::new(Counting { image: RamEeprom::new(), writes: Vec::new() }, 0);
    for n in 0..3 * slots as u16 {
        store.save(&od_with_guard_time(100 + n), Area::ALL).expect("fits");
        // The same values again: nothing written.
        let before = store.storage().writes.clone();
        store.save(&od_with_guard_time(100 + n), Area::ALL).expect("fits");
        assert_eq!(store.storage().writes, before, "save {n} repeated");
    }
    let writes = &store.storage().writes;
    assert_eq!(writes.len(), slots, "every slot used, none past the ring");
    assert!(writes.iter().all(|&w| w == writes[0]), "each slot written as often as the others: {writes:?}");
    let mut fresh = Od::new(Mode::Mixed, 5, NoAppObjects);
    assert_eq!(store.load(&mut fresh, Area::ALL), Ok(true));
    assert_eq!(guard_time(&mut fresh), 100 + 3 * slots as u16 - 1, "the newest after the ring wrapped three times");
}

#[test]
fn restoring_the_defaults_is_one_marker_and_the_next_save_stores_everything() {
    let mut store = BlockStore::new(Counting { image: RamEeprom::new(), writes: Vec::new() }, 0);
    for n in 0..5 {
        store.save(&od_with_guard_time(700 + n), Area::ALL).expect("fits");
    }
    let before: usize = store.storage().writes.iter().sum();
    store.erase(&Od::new(Mode::Mixed, 5, NoAppObjects)).expect("erased");
    assert_eq!(store.storage().writes.iter().sum::<usize>() - before, 2, "the marker's slot header, cleared then written");
    let mut fresh = Od::new(Mode::Mixed, 5, NoAppObjects);
    assert_eq!(store.load(&mut fresh, Area::ALL), Ok(false), "nothing stored: the defaults");
    assert!(!store.is_valid(<Od<NoAppObjects> as NodeDictionary>::PERSISTENT_SIZE).unwrap());
    // Saving one area after the restore stores every area (there is no block to keep).
    store.save(&od_with_guard_time(900), Area::MANUFACTURER).expect("fits");
    assert_eq!(store.load(&mut fresh, Area::ALL), Ok(true));
    assert_eq!(guard_time(&mut fresh), 900);
}

fn od_with_guard_time(ms: u16) -> Od<NoAppObjects> {
    let mut od = Od::new(Mode::Mixed, 5, NoAppObjects);
    od.write(0x100C, 0, &ms.to_le_bytes(), Side::Bus, &PREOP).expect("writable in pre-operational");
    od
}

#[test]
fn a_save_torn_at_any_write_keeps_the_previous_block() {
    let image = saved_block().into_inner();
    let mut completed = false;
    for budget in 0..2000 {
        let mut store = BlockStore::new(Torn { image: image.clone(), budget }, 0);
        let result = store.save(&od_with_guard_time(700), Area::ALL);
        let mut fresh = Od::new(Mode::Mixed, 5, NoAppObjects);
        assert_eq!(store.load(&mut fresh, Area::ALL), Ok(true), "a block is always there (budget {budget})");
        let expected = if result.is_ok() { 700 } else { 500 };
        assert_eq!(guard_time(&mut fresh), expected, "budget {budget}: {result:?}");
        if result.is_ok() {
            completed = true;
            break;
        }
    }
    assert!(completed, "a save completes with enough writes");
}

#[test]
fn the_newest_block_wins_and_a_corrupt_newest_falls_back_to_the_previous() {
    let mut store = saved_block();
    store.save(&od_with_guard_time(700), Area::ALL).expect("fits");
    store.save(&od_with_guard_time(900), Area::ALL).expect("fits");
    let mut fresh = Od::new(Mode::Mixed, 5, NoAppObjects);
    assert_eq!(store.load(&mut fresh, Area::ALL), Ok(true));
    assert_eq!(guard_time(&mut fresh), 900, "three saves: the last one wins");
    // The third save went to the third slot of the ring; corrupt its data.
    let mut image = store.into_inner();
    image.as_bytes_mut()[2 * SLOT + 12] ^= 0xFF;
    let mut store = BlockStore::new(image, 0);
    let mut fresh = Od::new(Mode::Mixed, 5, NoAppObjects);
    assert_eq!(store.load(&mut fresh, Area::ALL), Ok(true));
    assert_eq!(guard_time(&mut fresh), 700, "the previous block");
}

#[test]
fn saving_one_area_keeps_the_others_from_the_previous_block() {
    let mut store = saved_block();
    let mut od = od_with_guard_time(700);
    od.write(0x2180, 0, &2000_u16.to_le_bytes(), Side::Bus, &PREOP).expect("manufacturer area");
    store.save(&od, Area::MANUFACTURER).expect("fits");
    let mut fresh = Od::new(Mode::Mixed, 5, NoAppObjects);
    assert_eq!(store.load(&mut fresh, Area::ALL), Ok(true));
    assert_eq!(guard_time(&mut fresh), 500, "communication area as saved before");
    let mut buf = [0; 2];
    fresh.read(0x2180, 0, 0, &mut buf, Side::Device).expect("2180h exists");
    assert_eq!(u16::from_le_bytes(buf), 2000, "manufacturer area saved now");
}

#[test]
fn a_save_gathers_the_entries_into_few_writes_of_the_same_bytes() {
    use coforge_stack::od::NodeDictionary;
    let od = od_with_guard_time(700);
    let len = <Od<NoAppObjects> as NodeDictionary>::PERSISTENT_SIZE;
    let mut expected = vec![0_u8; len];
    assert!(od.save_area(Area::ALL, &mut |at, bytes| {
        expected[at..at + bytes.len()].copy_from_slice(bytes);
        true
    }));
    let mut store = BlockStore::new(Counting { image: RamEeprom::new(), writes: Vec::new() }, 0);
    store.save(&od, Area::ALL).expect("fits");
    let Counting { image, writes } = store.into_inner();
    let writes: usize = writes.iter().sum();
    // An EEPROM write cycle (some 5 ms) per write: two headers and the data gathered into
    // pieces of up to 32 bytes (each more than 16 full), not one write per entry (272).
    assert!(writes <= 2 + len.div_ceil(16), "{writes} writes for {len} bytes");
    assert_eq!(&image.as_bytes()[12..12 + len], &expected[..], "the block's data as save_area gives it");
}
