//! Measured scenarios of CO401Memory1 for `cargo xtask bench`: no UART, no clock, only the
//! module's code between two marker functions that the instruction-counting QEMU plugin
//! (`bench/insn-count`) watches.
//!
//! The image sets the module up as the real image does (banks in statics, node-ID 5), makes
//! TPDO1 and TPDO2 synchronous over SDO, starts the node and then runs each scenario once:
//! `bench_begin(id)`, the input, `poll` until the module is quiet, `bench_end()`. Each
//! answer is checked after `bench_end`; a wrong one prints what was wrong and exits through
//! semihosting with a failure code, so the image doubles as a self-test
//! (`qemu-system-arm ... -semihosting-config enable=on,target=native -kernel bench-memory1`).
//!
//! It also paints the free stack at start and reports the deepest use: of construction and
//! setup (`stack-peak-setup-bytes: N`), and, painted again, of the scenarios
//! (`stack-peak-bytes: N`, which includes `main`'s frame and the semihosting prints between
//! scenarios, so it is an upper bound of what the module's code needs). The plugin numbers scenarios by the order `bench_begin` is hit;
//! the image prints `bench <id> <name>` for each at the end, ids in the same order from 0.
#![no_std]
#![no_main]

use co401memory1::{BANK_SIZE, ConfigError, FixedBoard, Memory1};
use coforge_board_qemu::bench::{Answers, drain, exchange, expect, expect_bytes, fail, finish, frame, measure, paint_stack, sdo_write, stack_peak};
use coforge_stack::device::{Device, HostPort};
use coforge_stack::od::Side;
use coforge_storage::ram::RamEeprom;
use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use panic_semihosting as _;

type Bank = RamEeprom<&'static mut [u8; BANK_SIZE]>;
type Module = Memory1<Bank, FixedBoard>;

const NODE_ID: u8 = 5;
const SDO_RX: u16 = 0x600 + NODE_ID as u16;
const SDO_TX: u16 = 0x580 + NODE_ID as u16;
/// One fixed time for every input: no timer (scrub at 1 s, event timers) runs in between.
const NOW_US: u64 = 10_000;

/// The scenarios' names by id, printed at the end: a print between scenarios would go deeper
/// into the stack than the module and spoil the stack peak.
const NAMES: [&str; 9] = [
    "calibration (empty)",
    "sdo-expedited-upload 1018.1",
    "sdo-expedited-download 2180.0 (u16)",
    "sdo-expedited-download 5012.4 (memory byte, both banks)",
    "sdo-segmented-upload 1008.0 first segment",
    "rpdo1 6200.1/6200.2 = 0x91 (clear bank status)",
    "sync (two synchronous TPDOs)",
    "serial read-memory 33 12 50 04",
    "rpdo1 6200.1/6200.2 = 0x00 (no command: the RPDO path alone)",
];

/// Builds the module right in a `MaybeUninit` static (not moved in), in a frame of its own:
/// the construction's temporaries are gone when it returns, instead of staying in `main`'s
/// frame for ever.
#[inline(never)]
fn mount(banks: [Bank; 2]) -> &'static mut Module {
    let Some(Ok(device)) = cortex_m::singleton!(: Result<Module, ConfigError> = Memory1::new(banks, FixedBoard::new(NODE_ID))) else {
        panic!("mounted twice, or reserved configuration pins")
    };
    device
}

#[entry]
fn main() -> ! {
    static mut BANK1: [u8; BANK_SIZE] = [0; BANK_SIZE];
    static mut BANK2: [u8; BANK_SIZE] = [0; BANK_SIZE];
    paint_stack();
    let device = mount([RamEeprom::erased(BANK1), RamEeprom::erased(BANK2)]);

    // Unmeasured setup. Boot-up, then the EMCYs of the freshly cleared banks (status 0x40).
    device.start(0);
    let _ = drain(device, NOW_US);
    // TPDO1 (6000.1, 6000.2) synchronous; TPDO2 mapped to 6000.1, 6000.2 and the error
    // register, synchronous, enabled (CiA 301: mapping only while the PDO is invalid).
    sdo_write(device, NODE_ID, 0x1800, 2, &[1], NOW_US);
    sdo_write(device, NODE_ID, 0x1801, 2, &[1], NOW_US);
    sdo_write(device, NODE_ID, 0x1A01, 0, &[0], NOW_US);
    sdo_write(device, NODE_ID, 0x1A01, 1, &0x6000_0108_u32.to_le_bytes(), NOW_US);
    sdo_write(device, NODE_ID, 0x1A01, 2, &0x6000_0208_u32.to_le_bytes(), NOW_US);
    sdo_write(device, NODE_ID, 0x1A01, 3, &0x1001_0008_u32.to_le_bytes(), NOW_US);
    sdo_write(device, NODE_ID, 0x1A01, 0, &[3], NOW_US);
    sdo_write(device, NODE_ID, 0x1801, 1, &0x0000_0285_u32.to_le_bytes(), NOW_US);
    // NMT Start Remote Node.
    let _ = exchange(device, &frame(0x000, &[0x01, NODE_ID]), NOW_US);
    if device.state() != coforge_stack::nmt::NmtState::Operational {
        fail("NMT start: not operational", &Answers::NONE);
    }

    // The stack peak so far (construction, start, setup), then a fresh paint for the scenarios.
    hprintln!("stack-peak-setup-bytes: {}", stack_peak());
    paint_stack();

    // 0: nothing between the markers: the markers' own cost, which xtask subtracts.
    measure(0, || {});

    let request = frame(SDO_RX, &[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]);
    let answers = measure(1, || exchange(device, &request, NOW_US));
    expect("SDO upload 1018.1 (vendor ID 0x58)", &answers, &[(SDO_TX, &[0x43, 0x18, 0x10, 0x01, 0x58, 0, 0, 0])]);

    let request = frame(SDO_RX, &[0x2B, 0x80, 0x21, 0x00, 0xF4, 0x01, 0, 0]);
    let answers = measure(2, || exchange(device, &request, NOW_US));
    expect("SDO download 2180.0 = 500", &answers, &[(SDO_TX, &[0x60, 0x80, 0x21, 0x00, 0, 0, 0, 0])]);

    let request = frame(SDO_RX, &[0x2F, 0x12, 0x50, 0x04, 0x23, 0, 0, 0]);
    let answers = measure(3, || exchange(device, &request, NOW_US));
    expect("SDO download 5012.4 = 0x23", &answers, &[(SDO_TX, &[0x60, 0x12, 0x50, 0x04, 0, 0, 0, 0])]);

    // 1008h Device Name, 12 bytes: the initiate is setup, the first segment is measured.
    let answers = exchange(device, &frame(SDO_RX, &[0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0]), NOW_US);
    expect("SDO initiate upload 1008.0", &answers, &[(SDO_TX, &[0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0])]);
    let request = frame(SDO_RX, &[0x60, 0, 0, 0, 0, 0, 0, 0]);
    let answers = measure(4, || exchange(device, &request, NOW_US));
    expect("SDO upload segment 1 of 1008.0", &answers, &[(SDO_TX, b"\x00CO401Me")]);
    let answers = exchange(device, &frame(SDO_RX, &[0x70, 0, 0, 0, 0, 0, 0, 0]), NOW_US);
    expect("SDO upload segment 2 of 1008.0", &answers, &[(SDO_TX, b"\x15mory1\0\0")]);

    // RPDO1 (COB-ID 0x205) maps 6200.1 and 6200.2: command 0x91 clears each bank's status,
    // which ends the two memory-bank emergencies: one EMCY per condition that ends, the
    // first still with the error register and the other bank's CO40xx bits, the second
    // all zero (codes combined with OR, `node_config`).
    let request = frame(0x200 + u16::from(NODE_ID), &[0x91, 0x91]);
    let answers = measure(5, || exchange(device, &request, NOW_US));
    let emcy = 0x080 + u16::from(NODE_ID);
    expect("RPDO1 0x91 0x91: two EMCY error resets", &answers, &[(emcy, &[0, 0, 0x01, 0, 0x20, 0, 0, 0]), (emcy, &[0; 8])]);
    if device.node().od().app.status(0).bits() != 0 || device.node().od().app.status(1).bits() != 0 {
        fail("RPDO1 0x91 0x91: bank status not cleared", &answers);
    }

    let request = frame(0x080, &[]);
    let answers = measure(6, || exchange(device, &request, NOW_US));
    expect("SYNC: TPDO1 and TPDO2", &answers, &[(0x185, &[0, 0]), (0x285, &[0, 0, 0])]);

    // The datasheet's example: Read Memory Array Data of 5012.04, written to 0x23 above.
    let command = [0x33, 0x12, 0x50, 0x04];
    let mut out = [0_u8; 16];
    let n = measure(7, || {
        for &byte in &command {
            device.on_host_byte(byte, NOW_US / 1000);
        }
        device.host_output(NOW_US / 1000, &mut out)
    });
    expect_bytes("serial Read Memory 5012.04", out.get(..n).unwrap_or(&[]), &[0x32, 0x01, 0x23]);

    // RPDO1 again with command bytes that mean nothing: the stack's RPDO path (match the
    // COB-ID, unpack the mapping, two app writes) without the banks' work; nothing is sent.
    let request = frame(0x200 + u16::from(NODE_ID), &[0x00, 0x00]);
    let answers = measure(8, || exchange(device, &request, NOW_US));
    expect("RPDO1 0x00 0x00: nothing to send", &answers, &[]);
    let mut command = [0xFF_u8; 1];
    for sub in [1, 2] {
        let read = device.node_mut().read(0x6200, sub, 0, &mut command, Side::Device);
        if read.is_err() || command != [0] {
            fail("RPDO1 0x00 0x00: command bytes not stored", &answers);
        }
    }

    finish(&NAMES, stack_peak())
}
