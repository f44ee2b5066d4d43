#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! The CR3101 device end to end on a card image: files configured over the dictionary (as an
//! SDO master would), values logged from RPDO frames and SDO writes in each operating mode,
//! then the card read with mtools and checked with `fsck.fat -n`, record by record.

use coforge_sim::cr3101::{SimBoard, SimCr3101};
use coforge_sim::devices::Console;
use coforge_sim::storage::Eeprom;
use coforge_stack::device::Device;
use coforge_stack::frame::CanFrame;
use coforge_stack::od::{SdoAbort, Side};
use coforge_stack::store::BlockStore;
use cr3101::card::record::{ComponentType, Record, RecordLayout, TimeStamp};
use std::path::Path;

mod card_tools;
use card_tools::{copy_out, fsck_clean, image, listing};

const NODE: u8 = 0x20;
const MS: u64 = 1000;
/// What the tests set the clock to: 2026-12-03 06:30:00.000.
const START: TimeStamp = TimeStamp { millisecond: 0, second: 0, minute: 30, hour: 6, day: 3, month: 12, year: 26 };

fn device(card: &Path) -> SimCr3101 {
    let mut d = SimCr3101::new(SimBoard::new(Some(card.to_path_buf())).unwrap(), BlockStore::new(Eeprom::new(4096), 0), NODE);
    d.start(0);
    d
}

fn write(d: &mut SimCr3101, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
    Device::node_mut(d).write(index, sub, data, Side::Bus)
}

fn read(d: &mut SimCr3101, index: u16, sub: u8) -> Result<Vec<u8>, SdoAbort> {
    let mut buf = [0; 16];
    let n = Device::node_mut(d).read(index, sub, 0, &mut buf, Side::Bus)?;
    Ok(buf[..n.copied].to_vec())
}

fn u32_of(b: Vec<u8>) -> u32 {
    u32::from_le_bytes(b.try_into().unwrap())
}

/// Sets 2010h to [`START`] at `now`, field by field as a master would.
fn set_clock(d: &mut SimCr3101, now: u64) {
    d.logger_mut().set_now(now);
    for (sub, value) in [(7, START.year), (6, START.month), (5, START.day), (4, START.hour), (3, START.minute), (2, START.second)] {
        write(d, 0x2010, sub, &[value]).unwrap();
    }
    write(d, 0x2010, 1, &START.millisecond.to_le_bytes()).unwrap();
}

/// File `f` (0-based) named `name`, components 1 (WORD), 2 (DINT) and 4 (BYTE) relevant, in
/// `mode` with `interval`, `records` records long: 16-byte records.
fn configure(d: &mut SimCr3101, f: u16, name: &[u8], mode: u8, interval: u32, ring: bool, records: u32) -> RecordLayout {
    let base = 0x3000 + 0x100 * f;
    write(d, base, 1, name).unwrap();
    write(d, base + 1, 0, &0b1011_u16.to_le_bytes()).unwrap();
    write(d, base + 0x11, 2, &4_u16.to_le_bytes()).unwrap();
    write(d, base + 0x13, 2, &5_u16.to_le_bytes()).unwrap();
    if interval == 0 {
        write(d, base + 3, 1, &[0x03]).unwrap();
    }
    write(d, base + 3, 3, &interval.to_le_bytes()).unwrap();
    write(d, base + 3, 1, &[mode]).unwrap();
    write(d, base + 3, 2, &[if ring { 0x55 } else { 0 }]).unwrap();
    let mut layout = RecordLayout { relevant: 0b1011, ..RecordLayout::default() };
    layout.types[1] = ComponentType::Dint;
    layout.types[3] = ComponentType::Byte;
    let size = records * layout.len() as u32;
    write(d, 0x2002, f as u8 + 1, &size.to_le_bytes()).unwrap();
    write(d, 0x2003, f as u8 + 1, &size.to_le_bytes()).unwrap();
    layout
}

/// The RPDO payload for values `n`: component 1 = n, 2 = -1000 n, 4 = n mod 251.
fn payload(n: u32) -> Vec<u8> {
    let mut p = (n as u16).to_le_bytes().to_vec();
    p.extend((n as i32).wrapping_mul(-1000).to_le_bytes());
    p.push((n % 251) as u8);
    p
}

fn expected(layout: &RecordLayout, n: u32, t: TimeStamp) -> Record {
    let mut r = Record::new(layout);
    r.set(layout, 0, &(n as u16).to_le_bytes());
    r.set(layout, 1, &(n as i32).wrapping_mul(-1000).to_le_bytes());
    r.set(layout, 3, &[(n % 251) as u8]);
    r.stamp(&t);
    r
}

fn at_ms(ms: u16) -> TimeStamp {
    TimeStamp { millisecond: ms % 1000, second: (ms / 1000) as u8, ..START }
}

fn operational(d: &mut SimCr3101, now: u64) {
    d.on_frame(&CanFrame::data(0, &[0x01, NODE]).unwrap(), now);
}

/// Every frame the device sends until `now`.
fn drain(d: &mut SimCr3101, now: u64) -> Vec<CanFrame> {
    std::iter::from_fn(|| d.poll(now)).collect()
}

fn emcys(frames: &[CanFrame]) -> Vec<[u8; 8]> {
    frames.iter().filter(|f| f.id == 0x80 + u16::from(NODE)).map(|f| f.data).collect()
}

/// Takes the card out at `now`, as a user does before putting it into a PC: the device sees
/// it gone at its next poll of the slot (every 100 ms).
fn remove_card(d: &mut SimCr3101, now: u64) {
    d.console("card remove").unwrap();
    drain(d, now + 100 * MS);
    assert_eq!(read(d, 0x2001, 1).unwrap(), [0], "2001h.1: no card");
}

#[test]
fn autoincrement_with_window_0_logs_every_rpdo_as_a_record_a_pc_reads_byte_for_byte() {
    let path = image("auto0");
    let mut d = device(&path);
    set_clock(&mut d, 0);
    let layout = configure(&mut d, 0, b"OIL_TEMP", 0x03, 0, false, 100);
    assert_eq!(layout.len(), 16);
    operational(&mut d, 0);
    let mut want = Vec::new();
    for n in 0..50_u32 {
        let now = u64::from(n) * 7 * MS;
        d.on_frame(&CanFrame::data(0x200 + u16::from(NODE), &payload(n)).unwrap(), now);
        want.extend_from_slice(expected(&layout, n, at_ms((n * 7) as u16)).as_bytes());
    }
    // A frame shorter than the record's components (7 bytes): not logged, EMCY 8210h; the
    // next whole one ends it.
    d.on_frame(&CanFrame::data(0x200 + u16::from(NODE), &[1, 2, 3]).unwrap(), 360 * MS);
    assert_eq!(emcys(&drain(&mut d, 360 * MS)), vec![[0x10, 0x82, 0x11, 0, 0, 0, 0, 0]]);
    assert_eq!(u32_of(read(&mut d, 0x3005, 0).unwrap()), 50, "not logged");
    d.on_frame(&CanFrame::data(0x200 + u16::from(NODE), &payload(50)).unwrap(), 370 * MS);
    want.extend_from_slice(expected(&layout, 50, at_ms(370)).as_bytes());
    assert_eq!(emcys(&drain(&mut d, 370 * MS)), vec![[0; 8]]);
    // A frame for file 2, which is not allocated: ignored.
    d.on_frame(&CanFrame::data(0x300 + u16::from(NODE), &[1, 2, 3, 4]).unwrap(), 400 * MS);
    assert_eq!(u32_of(read(&mut d, 0x3005, 0).unwrap()), 51, "the write pointer");
    assert_eq!(u32_of(read(&mut d, 0x3006, 0).unwrap()), 51, "records written");
    // 5000h shows the last record written: its time stamp and values at their sizes.
    assert_eq!(read(&mut d, 0x5000, 1).unwrap(), (370_u16).to_le_bytes());
    assert_eq!(read(&mut d, 0x5000, 9).unwrap(), (-50_000_i32).to_le_bytes(), "a DINT takes 4 bytes");
    assert_eq!(read(&mut d, 0x5000, 11).unwrap(), [50], "a BYTE one");
    assert_eq!(read(&mut d, 0x5000, 10).unwrap(), [0, 0], "component 3 is not relevant: a WORD of zeros");
    remove_card(&mut d, 2000 * MS);

    let names = listing(&path);
    assert!(names.contains("OIL_TEMP.DAT") && names.contains("CANMEM.CFG"), "{names}");
    let file = copy_out(&path, "OIL_TEMP.DAT");
    assert_eq!(file.len(), 1600, "pre-allocated at its 2002h size");
    assert_eq!(&file[..want.len()], &want[..], "every record byte for byte, time stamps included");
    assert!(file[want.len()..].iter().all(|&b| b == 0), "nothing after the last record");
    assert!(fsck_clean(&path), "fsck.fat -n: clean");
}

#[test]
fn an_autoincrement_window_collects_frames_and_a_linear_file_ends_in_direct_reading() {
    let path = image("window");
    let mut d = device(&path);
    set_clock(&mut d, 0);
    let layout = configure(&mut d, 2, b"WINDOW", 0x03, 5, false, 2);
    operational(&mut d, 0);
    let rpdo3 = 0x400 + u16::from(NODE);
    // Two frames in the first 50 ms window: one record with the later values, stamped when
    // the window closes.
    d.on_frame(&CanFrame::data(rpdo3, &payload(1)).unwrap(), 10 * MS);
    d.on_frame(&CanFrame::data(rpdo3, &payload(2)).unwrap(), 30 * MS);
    assert!(emcys(&drain(&mut d, 59 * MS)).is_empty());
    assert_eq!(u32_of(read(&mut d, 0x3205, 0).unwrap()), 0, "the window is open");
    drain(&mut d, 60 * MS);
    assert_eq!(u32_of(read(&mut d, 0x3205, 0).unwrap()), 1, "written when the window closed");
    d.on_frame(&CanFrame::data(rpdo3, &payload(3)).unwrap(), 100 * MS);
    let frames = drain(&mut d, 160 * MS);
    // The second record filled the file: EMCY 6200h with file 3 in byte 3, and direct reading.
    assert_eq!(emcys(&frames), vec![[0x00, 0x62, 0x81, 3, 0, 0, 0, 0]]);
    assert_eq!(read(&mut d, 0x3203, 1).unwrap(), [0x10], "autoincrement went over to direct reading");
    assert_eq!(read(&mut d, 0x3204, 0).unwrap(), 1_u32.to_le_bytes(), "showing the last record");
    assert_eq!(write(&mut d, 0x5200, 8, &[9, 0]), Err(SdoAbort::DataTransferState), "direct reading takes no value");
    write(&mut d, 0x3204, 0, &0_u32.to_le_bytes()).unwrap();
    assert_eq!(read(&mut d, 0x5200, 8).unwrap(), [2, 0], "record 0 holds the window's last value");
    // Resetting the file (3x06h = 55h) ends the emergency.
    write(&mut d, 0x3206, 0, &0x55_u32.to_le_bytes()).unwrap();
    assert_eq!(emcys(&drain(&mut d, 200 * MS)), vec![[0; 8]], "error reset");
    remove_card(&mut d, 300 * MS);
    let file = copy_out(&path, "WINDOW.DAT");
    assert_eq!(&file[..16], expected(&layout, 2, at_ms(60)).as_bytes());
    assert_eq!(&file[16..32], expected(&layout, 3, at_ms(150)).as_bytes());
    assert!(fsck_clean(&path));
}

#[test]
fn cyclic_writing_stamps_a_record_every_interval_and_a_ring_file_wraps() {
    let path = image("cyclic");
    let mut d = device(&path);
    set_clock(&mut d, 0);
    let layout = configure(&mut d, 1, b"CYCLE", 0x02, 2, true, 3);
    write(&mut d, 0x5100, 8, &7_u16.to_le_bytes()).unwrap();
    assert!(emcys(&drain(&mut d, 100 * MS)).is_empty());
    assert_eq!(u32_of(read(&mut d, 0x3105, 0).unwrap()), 0, "pre-operational: no cycle");
    operational(&mut d, 100 * MS);
    let mut wrapped = Vec::new();
    for step in 1..=4 {
        wrapped.extend(emcys(&drain(&mut d, (100 + 20 * step) * MS)));
    }
    // Four records in a ring of three: the fourth went to record 0, and the wrap was an event.
    assert_eq!(wrapped, vec![[0x00, 0x62, 0x81, 2, 0, 0, 0, 0], [0; 8]]);
    assert_eq!(u32_of(read(&mut d, 0x3105, 0).unwrap()), 1);
    assert_eq!(u32_of(read(&mut d, 0x3106, 0).unwrap()), 3);
    remove_card(&mut d, 300 * MS);
    let file = copy_out(&path, "CYCLE.DAT");
    let mut values = Record::new(&layout);
    values.set(&layout, 0, &7_u16.to_le_bytes());
    let record = |t: TimeStamp, modified: bool| {
        let mut r = values;
        if !modified {
            r.clear_modified();
        }
        r.stamp(&t);
        r
    };
    assert_eq!(&file[..16], record(at_ms(180), false).as_bytes(), "record 0 again, on the wrap");
    assert_eq!(&file[16..32], record(at_ms(140), false).as_bytes(), "the value kept, not written again");
    assert_eq!(&file[32..48], record(at_ms(160), false).as_bytes());
    assert!(fsck_clean(&path));
}

#[test]
fn the_configuration_lives_on_the_card_and_a_card_that_comes_back_brings_it() {
    let path = image("config");
    let mut d = device(&path);
    write(&mut d, 0x2000, 0, b"TRUCK 17").unwrap();
    configure(&mut d, 4, b"PRESS", 0x01, 1, false, 10);
    remove_card(&mut d, 0);
    // No card: card data is refused, and EMCY 5001h is raised once.
    assert_eq!(read(&mut d, 0x2000, 0), Err(SdoAbort::DataTransfer));
    assert_eq!(write(&mut d, 0x5400, 8, &[1, 0]), Err(SdoAbort::DataTransfer));
    assert_eq!(emcys(&drain(&mut d, 200 * MS)), vec![[0x01, 0x50, 0x81, 0, 0, 0, 0, 0]]);
    assert_eq!(u32_of(read(&mut d, 0x1002, 0).unwrap()) & 1, 0);
    d.console("card insert").unwrap();
    assert_eq!(emcys(&drain(&mut d, 400 * MS)), vec![[0; 8]], "the card is back: error reset");
    assert_eq!(read(&mut d, 0x2000, 0).unwrap(), b"TRUCK 17");
    assert_eq!(read(&mut d, 0x3400, 1).unwrap(), b"PRESS");
    assert_eq!(u32_of(read(&mut d, 0x2002, 5).unwrap()), 160);
    assert_eq!(read(&mut d, 0x2001, 1).unwrap(), [1]);
    assert_eq!(u32_of(read(&mut d, 0x1002, 0).unwrap()), 0b111, "inserted, not write-protected, battery good");
    // Direct writing: the record at 3x04h, stamped at each write.
    write(&mut d, 0x3404, 0, &4_u32.to_le_bytes()).unwrap();
    write(&mut d, 0x5400, 8, &0x1234_u16.to_le_bytes()).unwrap();
    assert_eq!(write(&mut d, 0x5400, 9, &[1, 2]), Err(SdoAbort::LengthMismatch), "a DINT takes 4 bytes");
    assert_eq!(write(&mut d, 0x5400, 10, &[1, 2]), Err(SdoAbort::DataTransfer), "component 3 is not relevant");
    assert_eq!(write(&mut d, 0x3404, 0, &10_u32.to_le_bytes()), Err(SdoAbort::ValueTooHigh), "past the file's end");
    assert_eq!(u32_of(read(&mut d, 0x3406, 0).unwrap()), 5, "records up to the one written");
    remove_card(&mut d, 500 * MS);
    let file = copy_out(&path, "PRESS.DAT");
    assert_eq!(&file[64 + 9..64 + 11], &[0x34, 0x12]);
    assert_eq!(file[64 + 8], 0b1, "modification status: component 1 written");
    assert!(fsck_clean(&path));
}

#[test]
fn a_write_protected_card_is_read_and_never_written() {
    let path = image("protected");
    let mut d = device(&path);
    let layout = configure(&mut d, 0, b"PRESETS", 0x01, 1, false, 4);
    write(&mut d, 0x5000, 8, &0x0BEE_u16.to_le_bytes()).unwrap();
    remove_card(&mut d, 0);
    let before = std::fs::read(&path).unwrap();
    d.console("card insert protected").unwrap();
    drain(&mut d, 200 * MS);
    assert_eq!(read(&mut d, 0x2001, 3).unwrap(), [1], "2001h.3: write-protected");
    assert_eq!(u32_of(read(&mut d, 0x1002, 0).unwrap()) & 0b10, 0, "1002h bit 1 clear: write-protected (CR-10)");
    assert_eq!(read(&mut d, 0x5000, 8).unwrap(), [0xEE, 0x0B], "the preset reads back");
    assert_eq!(write(&mut d, 0x5000, 8, &[1, 0]), Err(SdoAbort::DataTransfer));
    assert_eq!(write(&mut d, 0x2002, 1, &0_u32.to_le_bytes()), Err(SdoAbort::DataTransfer));
    remove_card(&mut d, 300 * MS);
    assert_eq!(std::fs::read(&path).unwrap(), before, "not one byte written");
    assert_eq!(layout.len(), 16);
}

#[test]
fn pdo_read_mode_answers_a_request_with_the_values_or_the_time_stamp() {
    let path = image("pdoread");
    let mut d = device(&path);
    set_clock(&mut d, 0);
    configure(&mut d, 0, b"TABLE", 0x01, 1, false, 8);
    write(&mut d, 0x3004, 0, &3_u32.to_le_bytes()).unwrap();
    d.logger_mut().set_now(1_234 * MS);
    write(&mut d, 0x5000, 8, &0x0102_u16.to_le_bytes()).unwrap();
    write(&mut d, 0x5000, 9, &(-2_i32).to_le_bytes()).unwrap();
    // 20F5h = 1 takes effect at the next power-on.
    write(&mut d, 0x20F5, 0, &[1]).unwrap();
    assert_eq!(d.mode(), cr3101::Mode::Logging);
    d.start(2000 * MS);
    assert_eq!(d.mode(), cr3101::Mode::PdoRead);
    operational(&mut d, 2000 * MS);
    drain(&mut d, 2000 * MS);
    let request = 0x200 + u16::from(NODE);
    d.on_frame(&CanFrame::data(request, &[0, 3, 0, 0, 0, 0, 0, 0]).unwrap(), 2001 * MS);
    d.on_frame(&CanFrame::data(request, &[0, 3, 0, 0, 0, 1]).unwrap(), 2002 * MS);
    d.on_frame(&CanFrame::data(request, &[0, 8, 0, 0, 0, 0]).unwrap(), 2003 * MS);
    let answers: Vec<[u8; 8]> = drain(&mut d, 2004 * MS).iter().filter(|f| f.id == 0x180 + u16::from(NODE)).map(|f| f.data).collect();
    assert_eq!(
        answers,
        vec![
            // The record's data bytes: WORD 0102h, DINT -2, BYTE 0.
            [0x02, 0x01, 0xFE, 0xFF, 0xFF, 0xFF, 0, 0],
            // The time stamp, milliseconds most significant byte first (CR-31): 06:30:01.234.
            [0x00, 0xEA, 1, 30, 6, 3, 12, 26],
        ],
        "record 8 is past the file: no answer"
    );
}

#[test]
fn the_node_id_comes_from_its_pair_at_the_next_power_on() {
    let path = image("pairs");
    let mut d = device(&path);
    write(&mut d, 0x20F0, 0, &[0x33]).unwrap();
    write(&mut d, 0x20F2, 0, &[1]).unwrap();
    write(&mut d, 0x20F3, 0, &[1]).unwrap();
    d.start(0);
    assert_eq!((d.node().node_id(), d.bitrate_kbit()), (NODE, 500), "20F0h alone is no change; the bit-rate pair agrees");
    write(&mut d, 0x20F1, 0, &[0x33]).unwrap();
    d.start(0);
    assert_eq!(d.node().node_id(), 0x33);
}

#[test]
fn records_logged_since_the_last_save_are_found_again_when_a_pulled_card_comes_back() {
    let path = image("pulled");
    let mut d = device(&path);
    set_clock(&mut d, 0);
    let layout = configure(&mut d, 0, b"PULLED", 0x03, 0, false, 50);
    operational(&mut d, 0);
    for n in 0..10_u32 {
        d.on_frame(&CanFrame::data(0x200 + u16::from(NODE), &payload(n)).unwrap(), (10 + u64::from(n)) * MS);
    }
    // Pulled within the save delay: the pointers on the card still say 0.
    d.console("card remove").unwrap();
    drain(&mut d, 150 * MS);
    assert_eq!(read(&mut d, 0x3005, 0), Err(SdoAbort::DataTransfer));
    d.console("card insert").unwrap();
    drain(&mut d, 300 * MS);
    assert_eq!(u32_of(read(&mut d, 0x3005, 0).unwrap()), 10, "the ten records found again");
    assert_eq!(u32_of(read(&mut d, 0x3006, 0).unwrap()), 10);
    d.on_frame(&CanFrame::data(0x200 + u16::from(NODE), &payload(10)).unwrap(), 400 * MS);
    remove_card(&mut d, 500 * MS);
    let file = copy_out(&path, "PULLED.DAT");
    for n in 0..10 {
        assert_eq!(&file[n * 16..n * 16 + 16], expected(&layout, n as u32, at_ms(10 + n as u16)).as_bytes(), "record {n} kept");
    }
    assert_eq!(&file[160..176], expected(&layout, 10, at_ms(400)).as_bytes(), "logging went on after them");
    assert!(fsck_clean(&path));
}

#[test]
fn a_file_reset_with_55h_is_logged_over_from_record_0() {
    let path = image("reset");
    let mut d = device(&path);
    set_clock(&mut d, 0);
    configure(&mut d, 0, b"RESET", 0x03, 0, false, 50);
    operational(&mut d, 0);
    for n in 0..5_u32 {
        d.on_frame(&CanFrame::data(0x200 + u16::from(NODE), &payload(n)).unwrap(), (10 + u64::from(n)) * MS);
    }
    write(&mut d, 0x3006, 0, &0x55_u32.to_le_bytes()).unwrap();
    remove_card(&mut d, 2000 * MS);
    d.console("card insert").unwrap();
    drain(&mut d, 2200 * MS);
    assert_eq!(u32_of(read(&mut d, 0x3005, 0).unwrap()), 0, "the old records are older than the reset: not found again");
}

#[test]
fn a_new_allocation_empties_its_file_and_a_full_card_refuses_what_does_not_fit() {
    let path = image("allocation");
    let mut d = device(&path);
    set_clock(&mut d, 0);
    configure(&mut d, 0, b"FIRST", 0x01, 1, false, 10);
    write(&mut d, 0x5000, 8, &[0x11, 0x22]).unwrap();
    // One half alone changes nothing; both halves re-lay the file out, emptied.
    write(&mut d, 0x2002, 1, &320_u32.to_le_bytes()).unwrap();
    assert_eq!(u32_of(read(&mut d, 0x2003, 1).unwrap()), 160);
    assert_eq!(read(&mut d, 0x5000, 8).unwrap(), [0x11, 0x22], "still the old file");
    write(&mut d, 0x2003, 1, &320_u32.to_le_bytes()).unwrap();
    assert_eq!(read(&mut d, 0x5000, 8).unwrap(), [0, 0], "emptied");
    // 16 MiB card: a 20 MiB file does not fit. The pair takes effect and the card refuses.
    write(&mut d, 0x3100, 1, b"HUGE").unwrap();
    write(&mut d, 0x2002, 2, &(20_u32 << 20).to_le_bytes()).unwrap();
    assert_eq!(write(&mut d, 0x2003, 2, &(20_u32 << 20).to_le_bytes()), Err(SdoAbort::DataTransfer));
    drain(&mut d, 10 * MS);
    assert!(d.status_leds().card_error, "CARD ERROR: the card is full");
    // The other file is untouched and still logs.
    write(&mut d, 0x5000, 8, &[0x33, 0x44]).unwrap();
    remove_card(&mut d, 100 * MS);
    let first = copy_out(&path, "FIRST.DAT");
    assert_eq!(first.len(), 320);
    assert_eq!(&first[9..11], &[0x33, 0x44]);
    assert!(fsck_clean(&path), "a card that ran full is still clean");
}

#[test]
fn the_status_leds_show_operational_and_card_access() {
    let path = image("leds");
    let mut d = device(&path);
    configure(&mut d, 0, b"LEDS", 0x03, 0, false, 10);
    drain(&mut d, MS);
    let leds = d.status_leds();
    assert!(leds.on && !leds.can && !leds.card_access && !leds.card_error && !leds.error, "{leds:?}");
    operational(&mut d, 2 * MS);
    d.on_frame(&CanFrame::data(0x200 + u16::from(NODE), &payload(1)).unwrap(), 3 * MS);
    let leds = d.status_leds();
    assert!(leds.can && leds.card_access, "logging: {leds:?}");
    drain(&mut d, 60 * MS);
    assert!(!d.status_leds().card_access, "a pulse per record");
    assert_eq!(d.console("leds").unwrap(), "leds lit: on can");
}

#[test]
fn an_rpdo_moved_to_another_identifier_logs_from_there() {
    let path = image("cobid");
    let mut d = device(&path);
    configure(&mut d, 1, b"MOVED", 0x03, 0, false, 10);
    // CiA 301: invalid first, then the new identifier.
    write(&mut d, 0x1401, 1, &(0x8000_0000_u32 | (0x300 + u32::from(NODE))).to_le_bytes()).unwrap();
    write(&mut d, 0x1401, 1, &0x333_u32.to_le_bytes()).unwrap();
    operational(&mut d, MS);
    d.on_frame(&CanFrame::data(0x300 + u16::from(NODE), &payload(1)).unwrap(), 2 * MS);
    assert_eq!(u32_of(read(&mut d, 0x3105, 0).unwrap()), 0, "the old identifier is no longer file 2's");
    d.on_frame(&CanFrame::data(0x333, &payload(2)).unwrap(), 3 * MS);
    assert_eq!(u32_of(read(&mut d, 0x3105, 0).unwrap()), 1);
    // Saved automatically (CR-06): a reset communication keeps it.
    d.on_frame(&CanFrame::data(0, &[0x82, NODE]).unwrap(), 4 * MS);
    operational(&mut d, 5 * MS);
    d.on_frame(&CanFrame::data(0x300 + u16::from(NODE), &payload(3)).unwrap(), 6 * MS);
    d.on_frame(&CanFrame::data(0x333, &payload(4)).unwrap(), 7 * MS);
    assert_eq!(u32_of(read(&mut d, 0x3105, 0).unwrap()), 2);
    // Restoring the defaults (1011h "load") and a reset bring the default back.
    write(&mut d, 0x1011, 1, b"load").unwrap();
    d.on_frame(&CanFrame::data(0, &[0x82, NODE]).unwrap(), 8 * MS);
    operational(&mut d, 9 * MS);
    d.on_frame(&CanFrame::data(0x300 + u16::from(NODE), &payload(5)).unwrap(), 10 * MS);
    assert_eq!(u32_of(read(&mut d, 0x3105, 0).unwrap()), 3);
}
