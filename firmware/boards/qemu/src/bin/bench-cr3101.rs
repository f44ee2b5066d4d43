//! Measured scenarios of CR3101 for `cargo xtask bench`, as `bench-memory1` does for
//! CO401Memory1, with the `cr3101` image's board: the card is QEMU's SD card on SSI0, so the
//! figures include the card driver, the FAT layer and the SPI transfers (what an access costs
//! in instructions, and how deep it goes into the stack). `cargo xtask bench` gives the image
//! a blank card (`-drive if=sd,format=raw,file=...`, zeros, a power of two in size), which it
//! partitions and formats first as `coforge card` does (an MBR, one FAT16 partition from
//! 1 MiB on), unmeasured.
//!
//! Set up as the image runs (node-ID 20h, parameters in RAM): the card is mounted at start,
//! file 1 is configured over SDO (components 1 WORD, 2 DINT, 4 BYTE; autoincrement writing
//! with a window of 0; 64 records) and NMT starts the node. The scenarios then read and write
//! the dictionary, log one RPDO into one record on the card, poll the slot (the CMD13 probe),
//! and save the moved pointers to `CANMEM.CFG` when their delay is over. Every answer is
//! checked; a wrong one fails the run through semihosting, so the image doubles as a
//! self-test. The stack peaks, of construction and setup and of the scenarios, are reported.
#![no_std]
#![no_main]

use coforge_board_qemu::bench::{Answers, drain, exchange, expect, fail, finish, frame, measure, paint_stack, sdo_write, stack_peak};
use coforge_board_qemu::cr3101_board::{QemuBoard, QemuCard};
use coforge_board_qemu::sd::{SdSpi, SpinDelay};
use coforge_stack::device::Device;
use coforge_stack::nmt::NmtState;
use coforge_stack::od::NodeDictionary;
use coforge_stack::store::{BlockStore, MAX_SLOTS};
use coforge_storage::ram::RamEeprom;
use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use cr3101::Cr3101;
use cr3101::app::Typed;
use cr3101::logger::Logger;
use embedded_sdmmc::{Block, BlockDevice, BlockIdx, SdCard};
use panic_semihosting as _;

/// The parameter block's ring, as the image keeps it (in RAM here).
const PARAMS: usize = BlockStore::<RamEeprom<[u8; 0]>>::capacity_for_slots(<cr3101::Od<Typed<Logger<QemuCard>>> as NodeDictionary>::PERSISTENT_SIZE, MAX_SLOTS);
type DataLogger = Cr3101<QemuBoard, BlockStore<RamEeprom<&'static mut [u8; PARAMS]>>>;

const NODE_ID: u8 = 0x20;
const SDO_RX: u16 = 0x600 + NODE_ID as u16;
const SDO_TX: u16 = 0x580 + NODE_ID as u16;
const RPDO1: u16 = 0x200 + NODE_ID as u16;
/// Set-up and the dictionary scenarios happen before the slot's next poll (100 ms after the
/// start); the slot poll after it, the pointers' save 1 s after the record.
const SETUP_US: u64 = 10_000;
const NOW_US: u64 = 20_000;
const POLL_US: u64 = 150_000;
const SAVE_US: u64 = 1_100_000;

const NAMES: [&str; 7] = [
    "calibration (empty)",
    "sdo-expedited-upload 20F0.0",
    "sdo-expedited-download 20F5.0 (u8, saved at once)",
    "logging: RPDO1 7 bytes into one record on the card (autoincrement, window 0)",
    "sdo-expedited-upload 5000.9 (the last record's DINT)",
    "slot poll (CMD13 probe: the card is still there)",
    "pointers saved to CANMEM.CFG 1 s after the record (and a slot poll)",
];

/// The first block of the FAT16 partition (1 MiB), as `coforge card` lays it out.
const PARTITION: u32 = 2048;
const BLOCKS_PER_CLUSTER: u8 = 4;
const ROOT_ENTRIES: u16 = 512;

/// Partitions and formats the blank card (the volume `Card::mount` then mounts): an MBR with
/// one FAT16 (LBA) partition from [`PARTITION`] to the end, its boot sector, two FATs and the
/// root directory written, the data area left as it is.
fn format_card() {
    let card = SdCard::new(SdSpi::new(), SpinDelay);
    let Ok(blocks) = card.num_blocks().map(|n| n.0) else { fail("format: no card (run with -drive if=sd)", &Answers::NONE) };
    let sectors = blocks.saturating_sub(PARTITION);
    let root_blocks = u32::from(ROOT_ENTRIES) * 32 / 512;
    let clusters = sectors / u32::from(BLOCKS_PER_CLUSTER);
    let fat_blocks = (clusters + 2).div_ceil(256);
    let write = |at: u32, block: &Block| {
        if card.write(core::slice::from_ref(block), BlockIdx(at)).is_err() {
            fail("format: block write", &Answers::NONE);
        }
    };
    let put = |block: &mut Block, at: usize, bytes: &[u8]| {
        if let Some(dst) = block.contents.get_mut(at..at + bytes.len()) {
            dst.copy_from_slice(bytes);
        }
    };
    let mut mbr = Block::new();
    put(&mut mbr, 446, &[0x00, 0xFE, 0xFF, 0xFF, 0x0E, 0xFE, 0xFF, 0xFF]);
    put(&mut mbr, 454, &PARTITION.to_le_bytes());
    put(&mut mbr, 458, &sectors.to_le_bytes());
    put(&mut mbr, 510, &[0x55, 0xAA]);
    write(0, &mbr);
    let mut boot = Block::new();
    put(&mut boot, 0, b"\xEB\x3C\x90COFORGE ");
    put(&mut boot, 11, &512_u16.to_le_bytes());
    put(&mut boot, 13, &[BLOCKS_PER_CLUSTER, 1, 0, 2]);
    put(&mut boot, 17, &ROOT_ENTRIES.to_le_bytes());
    put(&mut boot, 21, &[0xF8]);
    put(&mut boot, 22, &(fat_blocks as u16).to_le_bytes());
    put(&mut boot, 24, &[32, 0, 64, 0]);
    put(&mut boot, 28, &PARTITION.to_le_bytes());
    put(&mut boot, 32, &sectors.to_le_bytes());
    put(&mut boot, 36, &[0x80, 0, 0x29, 0x01, 0x31, 0x01, 0x30]);
    put(&mut boot, 43, b"NO NAME    FAT16   ");
    put(&mut boot, 510, &[0x55, 0xAA]);
    write(PARTITION, &boot);
    let mut first_fat = Block::new();
    put(&mut first_fat, 0, &[0xF8, 0xFF, 0xFF, 0xFF]);
    let zeros = Block::new();
    for fat in 0..2 {
        let start = PARTITION + 1 + fat * fat_blocks;
        write(start, &first_fat);
        for at in start + 1..start + fat_blocks {
            write(at, &zeros);
        }
    }
    let root = PARTITION + 1 + 2 * fat_blocks;
    for at in root..root + root_blocks {
        write(at, &zeros);
    }
}

/// Builds the device in a static, in a frame of its own (see `bench-memory1`).
#[inline(never)]
fn mount(params: RamEeprom<&'static mut [u8; PARAMS]>) -> &'static mut DataLogger {
    let Some(device) = cortex_m::singleton!(: DataLogger = Cr3101::new(QemuBoard::new(), BlockStore::new(params, 0), NODE_ID)) else { panic!("mounted twice") };
    device
}

/// An expedited SDO upload during setup or after a scenario: the answer's four data bytes.
fn sdo_read(device: &mut DataLogger, index: u16, sub: u8, now_us: u64) -> [u8; 4] {
    let [lo, hi] = index.to_le_bytes();
    let answers = exchange(device, &frame(SDO_RX, &[0x40, lo, hi, sub, 0, 0, 0, 0]), now_us);
    match answers.get(0) {
        Some(f) if answers.n == 1 && f.id == SDO_TX && f.payload().len() == 8 && f.payload()[0] & 0xF3 == 0x43 => {
            let p = f.payload();
            [p[4], p[5], p[6], p[7]]
        }
        _ => fail("setup SDO upload", &answers),
    }
}

#[entry]
fn main() -> ! {
    static mut PARAMETERS: [u8; PARAMS] = [0; PARAMS];
    paint_stack();
    format_card();
    let device = mount(RamEeprom::erased(PARAMETERS));

    // Unmeasured setup: the card mounted at the start (CANMEM.CFG made), file 1 configured as
    // the end-to-end tests do, NMT start.
    device.start(0);
    let _ = drain(device, SETUP_US);
    if sdo_read(device, 0x2001, 1, SETUP_US)[0] != 1 {
        fail("no card inserted after the start (2001h.1)", &Answers::NONE);
    }
    sdo_write(device, NODE_ID, 0x3000, 1, b"BNCH", SETUP_US);
    sdo_write(device, NODE_ID, 0x3001, 0, &0b1011_u16.to_le_bytes(), SETUP_US);
    sdo_write(device, NODE_ID, 0x3011, 2, &4_u16.to_le_bytes(), SETUP_US);
    sdo_write(device, NODE_ID, 0x3013, 2, &5_u16.to_le_bytes(), SETUP_US);
    sdo_write(device, NODE_ID, 0x3003, 1, &[0x03], SETUP_US);
    sdo_write(device, NODE_ID, 0x3003, 3, &0_u32.to_le_bytes(), SETUP_US);
    sdo_write(device, NODE_ID, 0x3003, 1, &[0x03], SETUP_US);
    for pair in [0x2002, 0x2003] {
        sdo_write(device, NODE_ID, pair, 1, &(64_u32 * 16).to_le_bytes(), SETUP_US);
    }
    let _ = exchange(device, &frame(0x000, &[0x01, NODE_ID]), SETUP_US);
    if device.node().state() != NmtState::Operational {
        fail("NMT start: not operational", &Answers::NONE);
    }
    let _ = drain(device, SETUP_US);

    hprintln!("stack-peak-setup-bytes: {}", stack_peak());
    paint_stack();

    measure(0, || {});

    let request = frame(SDO_RX, &[0x40, 0xF0, 0x20, 0x00, 0, 0, 0, 0]);
    let answers = measure(1, || exchange(device, &request, NOW_US));
    expect("SDO upload 20F0.0", &answers, &[(SDO_TX, &[0x4F, 0xF0, 0x20, 0x00, NODE_ID, 0, 0, 0])]);

    let request = frame(SDO_RX, &[0x2F, 0xF5, 0x20, 0x00, 0, 0, 0, 0]);
    let answers = measure(2, || exchange(device, &request, NOW_US));
    expect("SDO download 20F5.0 = 0", &answers, &[(SDO_TX, &[0x60, 0xF5, 0x20, 0x00, 0, 0, 0, 0])]);

    // Component 1 (WORD) 7, 2 (DINT) -7000, 4 (BYTE) 7.
    let rpdo = frame(RPDO1, &[0x07, 0x00, 0xA8, 0xE4, 0xFF, 0xFF, 0x07]);
    let answers = measure(3, || exchange(device, &rpdo, NOW_US));
    expect("RPDO1 logged: nothing on CAN", &answers, &[]);

    let request = frame(SDO_RX, &[0x40, 0x00, 0x50, 0x09, 0, 0, 0, 0]);
    let answers = measure(4, || exchange(device, &request, NOW_US));
    expect("SDO upload 5000.9", &answers, &[(SDO_TX, &[0x43, 0x00, 0x50, 0x09, 0xA8, 0xE4, 0xFF, 0xFF])]);
    if sdo_read(device, 0x3005, 0, NOW_US) != [1, 0, 0, 0] {
        fail("one record on the card (3005h)", &Answers::NONE);
    }

    let answers = measure(5, || drain(device, POLL_US));
    expect("slot poll: nothing on CAN", &answers, &[]);
    if sdo_read(device, 0x2001, 1, POLL_US)[0] != 1 {
        fail("the card is still there after the probe (2001h.1)", &Answers::NONE);
    }

    let answers = measure(6, || drain(device, SAVE_US));
    expect("pointers saved: nothing on CAN", &answers, &[]);
    if device.logger().card_errors != 0 {
        fail("a card access failed", &Answers::NONE);
    }

    finish(&NAMES, stack_peak())
}
