//! Measured scenarios of CO401GW1 for `cargo xtask bench`, as `bench-memory1` does for
//! CO401Memory1: no UART, no clock, only the chip's code between the marker functions of
//! [`coforge_board_qemu::bench`], every answer checked after the end marker (a wrong one fails
//! the run through semihosting, so the image doubles as a self-test), and the stack peak.
//!
//! The chip is set up as the QEMU image runs it (node-ID 5 on the ID pins, mixed mode, a
//! parameter block in RAM): the host enables CAN with `02 00` and switches on the unsolicited
//! RPDO telegrams (2E01h.1 = 1), then NMT starts the node. The two paths the issue measures
//! are the host's write-TPDO telegram until the TPDO is on its way (the bytes in, the
//! answer out, `poll` until the chip is quiet) and an RPDO until the unsolicited `40`
//! telegram is out.
#![no_std]
#![no_main]

use co401gw1::{FixedBoard, Gw1};
use coforge_board_qemu::bench::{Answers, drain, exchange, expect, expect_bytes, fail, finish, frame, measure, paint_stack, stack_peak};
use coforge_stack::device::{Device, HostPort};
use coforge_stack::nmt::NmtState;
use coforge_stack::store::BlockStore;
use coforge_storage::ram::RamEeprom;
use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use panic_semihosting as _;

/// Room for the two slots of the chip's parameter block (checked at start).
const PARAMS: usize = 1024;
type Chip = Gw1<FixedBoard, BlockStore<RamEeprom<&'static mut [u8; PARAMS]>>>;

const NODE_ID: u8 = 5;
const SDO_RX: u16 = 0x600 + NODE_ID as u16;
const SDO_TX: u16 = 0x580 + NODE_ID as u16;
/// One fixed time for every input: no timer runs in between, and every host telegram's
/// bytes arrive within the 10 ms gap.
const NOW_US: u64 = 10_000;
const NOW_MS: u64 = NOW_US / 1000;

const NAMES: [&str; 7] = [
    "calibration (empty)",
    "host write-tpdo 30 08 (TPDO1 queued and sent)",
    "rpdo1 8 bytes (unsolicited 40 08 to the host)",
    "sdo-expedited-upload 1018.1",
    "sdo-expedited-download 2180.0 (u16)",
    "host read-od 21 03 18 10 01",
    "input pin IN0 (DS401 event, TPDO1)",
];

/// Hands a host telegram to the chip, polls the CAN side until it is quiet, and collects
/// the host's answer into `out`: (frames sent, answer length).
fn host_exchange(chip: &mut Chip, telegram: &[u8], out: &mut [u8; 32]) -> (Answers, usize) {
    for &byte in telegram {
        chip.on_host_byte(byte, NOW_MS);
    }
    let answers = drain(chip, NOW_US);
    (answers, chip.host_output(NOW_MS, out))
}

/// Builds the chip right in a `MaybeUninit` static, in a frame of its own (see
/// `bench-memory1`).
#[inline(never)]
fn mount(params: RamEeprom<&'static mut [u8; PARAMS]>) -> &'static mut Chip {
    let Some(chip) = cortex_m::singleton!(: Chip = Gw1::new(FixedBoard::new(NODE_ID, true), BlockStore::new(params, 0))) else { panic!("mounted twice") };
    chip
}

#[entry]
fn main() -> ! {
    static mut PARAMETERS: [u8; PARAMS] = [0; PARAMS];
    paint_stack();
    let chip = mount(RamEeprom::erased(PARAMETERS));
    let mut out = [0_u8; 32];

    // Unmeasured setup: the boot phase's first 01 00, enable, the unsolicited RPDO1 telegram
    // on (2E01h.1 bit 0), NMT start.
    chip.start(0);
    let n = chip.host_output(0, &mut out);
    expect_bytes("boot-up telegram", out.get(..n).unwrap_or(&[]), &[0x01, 0x00]);
    let (answers, n) = host_exchange(chip, &[0x02, 0x00], &mut out);
    expect_bytes("enable 02 00", out.get(..n).unwrap_or(&[]), &[0x02, 0x00]);
    expect("CAN boot-up after enable", &answers, &[(0x700 + u16::from(NODE_ID), &[0x00])]);
    let (_, n) = host_exchange(chip, &[0x20, 0x05, 0x01, 0x2E, 0x01, 0x01, 0x00], &mut out);
    expect_bytes("host write 2E01h.1 = 1", out.get(..n).unwrap_or(&[]), &[0x20, 0x00]);
    let _ = exchange(chip, &frame(0x000, &[0x01, NODE_ID]), NOW_US);
    if chip.node().state() != NmtState::Operational {
        fail("NMT start: not operational", &Answers::NONE);
    }
    let _ = chip.host_output(NOW_MS, &mut out);

    hprintln!("stack-peak-setup-bytes: {}", stack_peak());
    paint_stack();

    measure(0, || {});

    // Bytes 1..7 of the digital inputs from the host (byte 0 is IN0..IN7: CFG0 is high).
    let telegram = [0x30, 0x08, 0xAA, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77];
    let (answers, n) = measure(1, || host_exchange(chip, &telegram, &mut out));
    expect_bytes("write TPDO1 data: answer", out.get(..n).unwrap_or(&[]), &[0x30, 0x00]);
    expect("write TPDO1 data: TPDO1", &answers, &[(0x180 + u16::from(NODE_ID), &[0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77])]);

    let rpdo = frame(0x200 + u16::from(NODE_ID), &[0x99, 0, 0, 0, 0, 0, 0, 0x01]);
    let (answers, n) = measure(2, || {
        let answers = exchange(chip, &rpdo, NOW_US);
        (answers, chip.host_output(NOW_MS, &mut out))
    });
    expect("RPDO1: nothing on CAN", &answers, &[]);
    expect_bytes("RPDO1: unsolicited 40 08", out.get(..n).unwrap_or(&[]), &[0x40, 0x08, 0x99, 0, 0, 0, 0, 0, 0, 0x01]);

    let request = frame(SDO_RX, &[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]);
    let answers = measure(3, || exchange(chip, &request, NOW_US));
    expect("SDO upload 1018.1", &answers, &[(SDO_TX, &[0x43, 0x18, 0x10, 0x01, 0x58, 0x00, 0x00, 0x00])]);

    let request = frame(SDO_RX, &[0x2B, 0x80, 0x21, 0x00, 0xF4, 0x01, 0, 0]);
    let answers = measure(4, || exchange(chip, &request, NOW_US));
    expect("SDO download 2180.0 = 500", &answers, &[(SDO_TX, &[0x60, 0x80, 0x21, 0x00, 0, 0, 0, 0])]);

    let telegram = [0x21, 0x03, 0x18, 0x10, 0x01];
    let (answers, n) = measure(5, || host_exchange(chip, &telegram, &mut out));
    expect("host read 1018h.1: nothing on CAN", &answers, &[]);
    expect_bytes("host read 1018h.1", out.get(..n).unwrap_or(&[]), &[0x21, 0x07, 0x18, 0x10, 0x01, 0x58, 0x00, 0x00, 0x00]);

    // IN0 active (pin low): 6000h.1 bit 0, a DS401 change event for TPDO1.
    chip.board_mut().input_levels = 0xFE;
    let answers = measure(6, || drain(chip, NOW_US));
    expect("IN0: TPDO1", &answers, &[(0x180 + u16::from(NODE_ID), &[0x01, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77])]);

    finish(&NAMES, stack_peak())
}
