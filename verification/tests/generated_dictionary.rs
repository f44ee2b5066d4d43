//! The generated dictionaries behave as the specs say: typed defaults with `$NODEID`
//! resolved, access per side and NMT state, abort codes, app-backed routing, modes; and every
//! entry of every device can be read and written back through the generated dispatch.

use coforge_stack::od::{AccessContext, AppObjects, EntryAccess, EntryInfo, NmtState, ReadLen, SdoAbort, Side, Table, read_slice};

/// App-backed storage for tests: one byte per (index, sub), like CO401Memory1's banks.
#[derive(Debug, Clone)]
struct Memory(std::collections::BTreeMap<(u16, u8), Vec<u8>>);

impl AppObjects for Memory {
    fn read(&mut self, e: &EntryInfo, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        let v = self.0.get(&(index, sub)).cloned().unwrap_or_else(|| vec![0; usize::from(e.size.min(8))]);
        read_slice(&v, offset, buf)
    }
    fn write(&mut self, _: &EntryInfo, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.0.insert((index, sub), data.to_vec());
        Ok(())
    }
}

fn memory() -> Memory {
    Memory(Default::default())
}

const PREOP: AccessContext = AccessContext { nmt: NmtState::PreOperational, can_enabled: false };
const OP: AccessContext = AccessContext { nmt: NmtState::Operational, can_enabled: true };

fn read(od: &mut impl EntryAccess, index: u16, sub: u8, side: Side) -> Result<Vec<u8>, SdoAbort> {
    let mut buf = [0_u8; 64];
    od.read(index, sub, 0, &mut buf, side).map(|n| buf[..n.copied].to_vec())
}

/// Reads every entry as the device and writes the value back: every dispatch arm runs.
fn sweep(od: &mut impl EntryAccess, table: Table<'_>) -> usize {
    let mut n = 0;
    for run in table.iter() {
        for index in run.index..=run.index + u16::from(run.copies()) {
            for sub in run.sub..=run.last_sub {
                let value = read(od, index, sub, Side::Device).unwrap_or_else(|a| panic!("{index:04X}.{sub}: {a:?}"));
                assert!(value.len() <= usize::from(run.size), "{index:04X}.{sub}");
                // Fixed-size values are written back whole; a value outside its own limits (a
                // default of 0 under `low: 1`) is refused with the range abort, nothing else.
                match od.write(index, sub, &value, Side::Device, &PREOP) {
                    Ok(()) | Err(SdoAbort::ValueTooLow | SdoAbort::ValueTooHigh | SdoAbort::InvalidValue) => {}
                    Err(a) => panic!("{index:04X}.{sub} write-back: {a:?}"),
                }
                n += 1;
            }
        }
    }
    n
}

#[test]
fn co401memory1_dictionary() {
    use co401memory1::{Mode, Od, od};
    let mut d = Od::new(Mode::Default, 0x22, memory());
    assert_eq!(read(&mut d, 0x1018, 1, Side::Bus), Ok(vec![0x58, 0, 0, 0]));
    assert_eq!(read(&mut d, 0x1014, 0, Side::Bus), Ok(vec![0xA2, 0, 0, 0]), "$NODEID + 0x80 for node 0x22");
    assert_eq!(read(&mut d, 0x1800, 1, Side::Bus), Ok(vec![0xA2, 0x01, 0, 0]));
    assert_eq!(d.write(0x1000, 0, &[0; 4], Side::Bus, &PREOP), Err(SdoAbort::ReadOnly));
    assert_eq!(d.write(0x1017, 0, &[0xE8, 0x03], Side::Bus, &OP), Ok(()));
    assert_eq!(d.producer_heartbeat_time, 1000);
    assert_eq!(d.write(0x1017, 0, &[1], Side::Bus, &OP), Err(SdoAbort::LengthTooLow));
    assert_eq!(d.producer_heartbeat_time, 1000, "a refused write keeps the value");
    // App-backed memory bytes reach the device's own storage.
    assert_eq!(d.write(0x5000, 5, &[0xAB], Side::Bus, &OP), Ok(()));
    assert_eq!(d.app.0.get(&(0x5000, 5)), Some(&vec![0xAB]));
    assert_eq!(read(&mut d, 0x5000, 5, Side::Host), Ok(vec![0xAB]));
    // Not reachable from CAN; the host has no access to it either.
    assert_eq!(read(&mut d, 0x100B, 0, Side::Bus), Err(SdoAbort::NoObject));
    assert_eq!(read(&mut d, 0x100B, 0, Side::Host), Err(SdoAbort::UnsupportedAccess));
    // Mapping is writable in pre-operational only (note *1).
    assert_eq!(d.write(0x1600, 0, &[0], Side::Bus, &OP), Err(SdoAbort::DataTransferState));
    assert_eq!(d.write(0x1600, 0, &[0], Side::Bus, &PREOP), Ok(()));
    assert_eq!(read(&mut d, 0x9999, 0, Side::Bus), Err(SdoAbort::NoObject));
    assert_eq!(read(&mut d, 0x1018, 9, Side::Bus), Err(SdoAbort::NoSubIndex));
    assert!(sweep(&mut d, od::entries(Mode::Default)) > 8000);
}

#[test]
fn co401gw1_dictionary_sides_and_modes() {
    use co401gw1::{Mode, Od, od};
    for mode in Mode::ALL {
        let mut d = Od::new(mode, 5, memory());
        // 100B: host-writable until the CANopen interface is enabled, invisible to CAN.
        assert_eq!(d.write(0x100B, 0, &[9], Side::Host, &PREOP), Ok(()));
        assert_eq!(d.node_id, 9);
        assert_eq!(d.write(0x100B, 0, &[10], Side::Host, &OP), Err(SdoAbort::DataTransferState));
        assert_eq!(read(&mut d, 0x100B, 0, Side::Bus), Err(SdoAbort::NoObject));
        // 2E00: read-only from CAN, writable from the host.
        assert_eq!(d.write(0x2E00, 1, &[0xFF], Side::Bus, &PREOP), Err(SdoAbort::ReadOnly));
        assert_eq!(d.write(0x2E00, 1, &[0xFF], Side::Host, &OP), Ok(()));
        // Below 3000h the host may not write.
        assert_eq!(d.write(0x1017, 0, &[0, 0], Side::Host, &PREOP), Err(SdoAbort::ReadOnly));
        sweep(&mut d, od::entries(mode));
    }
    // The digital modes have 16 input bytes, the mixed mode 8.
    let mut mixed = Od::new(Mode::Mixed, 5, memory());
    let mut digital = Od::new(Mode::Digital, 5, memory());
    assert_eq!(read(&mut mixed, 0x6000, 16, Side::Bus), Err(SdoAbort::NoSubIndex));
    assert!(read(&mut digital, 0x6000, 16, Side::Bus).is_ok());
}

#[test]
fn cr3101_and_canopenia_dictionaries_sweep() {
    for mode in cr3101::Mode::ALL {
        let mut d = cr3101::Od::new(mode, 0x20, memory());
        sweep(&mut d, cr3101::od::entries(mode));
        // 3x03.1 accepts only the four operating modes.
        assert_eq!(d.write(0x3203, 1, &[0x04], Side::Bus, &OP), Err(SdoAbort::InvalidValue));
    }
    let mut ia = canopenia::Od::new(canopenia::Mode::Default, 1, memory());
    let n = sweep(&mut ia, canopenia::od::entries(canopenia::Mode::Default));
    assert!(n > 300);
}

#[test]
fn co401gw1_persistent_block_saves_loads_and_restores() {
    use co401gw1::{Mode, Od};
    use coforge_stack::od::{Area, NodeDictionary};
    let size = <Od<Memory> as NodeDictionary>::PERSISTENT_SIZE;
    let mut a = Od::new(Mode::Mixed, 5, memory());
    assert_eq!(a.write(0x100C, 0, &[0xF4, 0x01], Side::Bus, &PREOP), Ok(()));
    assert_eq!(a.write(0x1800, 1, &[0x85, 0x03, 0, 0], Side::Bus, &PREOP), Ok(()), "TPDO1 COB-ID is persistent");
    assert_eq!(a.write(0x2180, 0, &[0x10, 0x27], Side::Bus, &PREOP), Ok(()), "manufacturer area");
    let save = |od: &Od<Memory>, area, block: &mut Vec<u8>| {
        od.save_area(area, &mut |at, image| {
            block[at..at + image.len()].copy_from_slice(image);
            true
        })
    };
    let mut block = vec![0xEE_u8; size];
    assert!(save(&a, Area::ALL, &mut block));
    assert!(block.iter().filter(|&&b| b == 0xEE).count() < 4, "every byte of the block is written");
    let mut comm_only = vec![0xEE_u8; size];
    assert!(save(&a, Area::COMMUNICATION, &mut comm_only));
    assert!(comm_only.contains(&0xEE), "other areas are left as they were");
    let mut b = Od::new(Mode::Mixed, 5, memory());
    assert!(!b.load_area(Area::ALL, &mut |_, _| false), "a source that fails is reported");
    assert!(b.load_area(Area::COMMUNICATION, &mut |at, buf| {
        buf.copy_from_slice(&block[at..at + buf.len()]);
        true
    }));
    assert_eq!(b.guard_time, 500);
    assert_eq!(read(&mut b, 0x1800, 1, Side::Bus), Ok(vec![0x85, 0x03, 0, 0]));
    assert_eq!(read(&mut b, 0x2180, 0, Side::Bus), Ok(vec![0xE8, 0x03]), "manufacturer area not loaded");
    b.reset_area(Area::COMMUNICATION, 7);
    assert_eq!(b.guard_time, 0);
    assert_eq!(read(&mut b, 0x1800, 1, Side::Bus), Ok(vec![0x87, 0x01, 0, 0]), "defaults with $NODEID for node 7");
    const { assert!(<Od<Memory> as NodeDictionary>::PERSISTENT_SIZE > 40) };
}
