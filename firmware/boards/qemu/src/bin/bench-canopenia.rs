//! Measured scenarios of CANopenIA for `cargo xtask bench`, as `bench-gw1` does for CO401GW1:
//! no UART, no clock, only the coprocessor's code between the marker functions of
//! [`coforge_board_qemu::bench`], every answer checked after the end marker (a wrong one fails
//! the run through semihosting, so the image doubles as a self-test), and the stack peak.
//!
//! Set up as the QEMU image runs it (node-ID 2, a parameter block in RAM), with node 3 on the
//! bus scanned by the manager (its boot-up, then answers to every scan transfer: 1000h and
//! 1018h, no PDOs) and the scan cache on for remote reads (5F01h.04 bit 4). The figures are
//! the issue's: an R command from its frame in to its answer queued; a U answered from the
//! scan cache; a U through the SDO client, in two parts that leave out the remote node's
//! time: the command until the SDO request is on the bus, and the SDO answer until the U
//! answer is queued.
#![no_std]
#![no_main]

use canopenia::Canopenia;
use canopenia::serial::{DeviceToHost, HostToDevice};
use coforge_board_qemu::bench::{Answers, drain, exchange, expect, expect_bytes, fail, finish, frame, measure, paint_stack, stack_peak};
use coforge_stack::device::{Device, HostPort};
use coforge_stack::store::BlockStore;
use coforge_storage::ram::RamEeprom;
use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use panic_semihosting as _;

/// Room for the two slots of the coprocessor's parameter block.
const PARAMS: usize = 2048;
type Chip = Canopenia<BlockStore<RamEeprom<&'static mut [u8; PARAMS]>>>;

const NODE_ID: u8 = 2;
/// The scanned node and what it answers.
const REMOTE: u8 = 3;
const REMOTE_TYPE: u32 = 0x0003_0191;
const REMOTE_VENDOR: u32 = 0x0145_5341;
const NOW_US: u64 = 10_000;
const NOW_MS: u64 = NOW_US / 1000;

const NAMES: [&str; 5] = [
    "calibration (empty)",
    "host R 1000h (frame in, answer queued)",
    "host U 1018h.1 of node 3 from the scan cache",
    "host U 1001h of node 3: command until the SDO request is sent",
    "host U 1001h of node 3: SDO answer until the U answer is queued",
];

/// A command's frame (start byte 11h).
fn command(c: &HostToDevice<'_>, out: &mut [u8; 40]) -> usize {
    c.encode(out).unwrap_or_else(|_| fail("encode a command", &Answers::NONE))
}

/// The frame of the answer `a`.
fn answer(a: &DeviceToHost<'_>, out: &mut [u8; 40]) -> usize {
    a.encode(out).unwrap_or_else(|_| fail("encode an answer", &Answers::NONE))
}

fn host_bytes(chip: &mut Chip, bytes: &[u8]) {
    for &byte in bytes {
        chip.on_host_byte(byte, NOW_MS);
    }
}

/// Node 3 answers the manager's scan: 1000h and 1018h.1..4 expedited, the heartbeat time a
/// scan writes (1017h) confirmed, everything else (its PDO parameters) "object does not
/// exist", which a scan takes as no PDO. NMT frames (KEEP_OP starts the node) need no answer.
fn scan_remote(chip: &mut Chip, first: Answers) {
    let mut answers = first;
    for _ in 0..64 {
        let request = (0..answers.n.min(4)).filter_map(|i| answers.get(i)).find(|f| f.id == 0x600 + u16::from(REMOTE)).copied();
        let Some(request) = request else { return };
        let [command, lo, hi, sub, ..] = request.data;
        let value = match (u16::from_le_bytes([lo, hi]), sub) {
            (0x1000, 0) => Some(REMOTE_TYPE),
            (0x1018, 1) => Some(REMOTE_VENDOR),
            (0x1018, 2..=4) => Some(u32::from(sub)),
            _ => None,
        };
        let response = match value {
            // A download (the 1017h write): confirmed.
            _ if command & 0xE0 == 0x20 => [0x60, lo, hi, sub, 0, 0, 0, 0],
            Some(v) => {
                let [a, b, c, d] = v.to_le_bytes();
                [0x43, lo, hi, sub, a, b, c, d]
            }
            None => [0x80, lo, hi, sub, 0x00, 0x00, 0x02, 0x06],
        };
        answers = exchange(chip, &frame(0x580 + u16::from(REMOTE), &response), NOW_US);
    }
    fail("scan: more than 64 transfers", &answers);
}

/// Builds the coprocessor right in a `MaybeUninit` static, in a frame of its own (see
/// `bench-memory1`).
#[inline(never)]
fn mount(params: RamEeprom<&'static mut [u8; PARAMS]>) -> &'static mut Chip {
    let Some(chip) = cortex_m::singleton!(: Chip = Canopenia::new(NODE_ID, BlockStore::new(params, 0))) else { panic!("mounted twice") };
    chip
}

#[entry]
fn main() -> ! {
    static mut PARAMETERS: [u8; PARAMS] = [0; PARAMS];
    paint_stack();
    let chip = mount(RamEeprom::erased(PARAMETERS));
    let (mut cmd, mut want, mut out) = ([0_u8; 40], [0_u8; 40], [0_u8; 128]);

    // Unmeasured setup: start, node 3 boots and is scanned, the scan cache on.
    chip.start(0);
    let _ = drain(chip, NOW_US);
    let first = exchange(chip, &frame(0x700 + u16::from(REMOTE), &[0x00]), NOW_US);
    scan_remote(chip, first);
    if chip.manager().scanned(REMOTE).is_none() {
        fail("node 3 was not scanned", &Answers::NONE);
    }
    let n = command(&HostToDevice::WriteLocalRequest { index: 0x5F01, sub: 4, data: &[0x10, 0, 0, 0] }, &mut cmd);
    host_bytes(chip, &cmd[..n]);
    let _ = chip.host_output(NOW_MS, &mut out);

    hprintln!("stack-peak-setup-bytes: {}", stack_peak());
    paint_stack();

    measure(0, || {});

    let n = command(&HostToDevice::ReadLocalRequest { index: 0x1000, sub: 0 }, &mut cmd);
    let got = measure(1, || {
        host_bytes(chip, &cmd[..n]);
        chip.host_output(NOW_MS, &mut out)
    });
    let m = answer(&DeviceToHost::ReadLocalResponse { index: 0x1000, sub: 0, err: 0, data: &0x000F_0191_u32.to_le_bytes() }, &mut want);
    expect_bytes("R 1000h", &out[..got], &want[..m]);

    let n = command(&HostToDevice::ReadRemoteRequest { node_id: REMOTE, index: 0x1018, sub: 1 }, &mut cmd);
    let (answers, got) = measure(2, || {
        host_bytes(chip, &cmd[..n]);
        (drain(chip, NOW_US), chip.host_output(NOW_MS, &mut out))
    });
    expect("U from the cache: nothing on CAN", &answers, &[]);
    let m = answer(&DeviceToHost::ReadRemoteResponse { node_id: REMOTE, index: 0x1018, sub: 1, err: 0, data: &REMOTE_VENDOR.to_le_bytes() }, &mut want);
    expect_bytes("U 1018h.1 from the cache", &out[..got], &want[..m]);

    // The scan does not read 1001h: this U goes to the node.
    let n = command(&HostToDevice::ReadRemoteRequest { node_id: REMOTE, index: 0x1001, sub: 0 }, &mut cmd);
    let answers = measure(3, || {
        host_bytes(chip, &cmd[..n]);
        drain(chip, NOW_US)
    });
    expect("U 1001h: the SDO request", &answers, &[(0x600 + u16::from(REMOTE), &[0x40, 0x01, 0x10, 0x00, 0, 0, 0, 0])]);
    let response = frame(0x580 + u16::from(REMOTE), &[0x4F, 0x01, 0x10, 0x00, 0x00, 0, 0, 0]);
    let (answers, got) = measure(4, || (exchange(chip, &response, NOW_US), chip.host_output(NOW_MS, &mut out)));
    expect("U 1001h: nothing more on CAN", &answers, &[]);
    let m = answer(&DeviceToHost::ReadRemoteResponse { node_id: REMOTE, index: 0x1001, sub: 0, err: 0, data: &[0x00] }, &mut want);
    expect_bytes("U 1001h", &out[..got], &want[..m]);

    finish(&NAMES, stack_peak())
}
