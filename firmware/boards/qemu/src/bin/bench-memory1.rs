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
use coforge_stack::device::{Device, HostPort};
use coforge_stack::frame::CanFrame;
use coforge_stack::od::Side;
use coforge_storage::ram::RamEeprom;
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use panic_semihosting as _;

type Bank = RamEeprom<&'static mut [u8; BANK_SIZE]>;
type Module = Memory1<Bank, FixedBoard>;

const NODE_ID: u8 = 5;
const SDO_RX: u16 = 0x600 + NODE_ID as u16;
const SDO_TX: u16 = 0x580 + NODE_ID as u16;
/// One fixed time for every input: no timer (scrub at 1 s, event timers) runs in between.
const NOW_US: u64 = 10_000;
/// Stack words painted with this pattern count as never used.
const PAINT: u32 = 0xC0DE_57AC;
/// Bytes below the stack pointer at painting time that are left alone (the painting loop's
/// own frame and anything an exception would push).
const PAINT_MARGIN: usize = 256;

/// Marks the start of a measured scenario. Never inlined and kept by name, so that its
/// address in the symbol table is where the plugin starts counting.
#[inline(never)]
#[unsafe(no_mangle)]
pub extern "C" fn bench_begin(id: u32) {
    core::hint::black_box(id);
}

/// Marks the end of a measured scenario.
#[inline(never)]
#[unsafe(no_mangle)]
pub extern "C" fn bench_end() {
    core::hint::black_box(());
}

/// The frames the module sent for one input (the first few, and how many in all).
struct Answers {
    frames: [CanFrame; 4],
    n: usize,
}

impl Answers {
    fn get(&self, i: usize) -> Option<&CanFrame> {
        self.frames.get(..self.n.min(self.frames.len()))?.get(i)
    }
}

fn frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::data(id, data).unwrap_or(CanFrame { id, rtr: false, dlc: 0, data: [0; 8] })
}

/// Hands one frame to the module and polls until it is quiet.
fn exchange(device: &mut Module, input: &CanFrame) -> Answers {
    device.on_frame(input, NOW_US);
    drain(device)
}

fn drain(device: &mut Module) -> Answers {
    let mut answers = Answers { frames: [frame(0, &[]); 4], n: 0 };
    while let Some(f) = device.poll(NOW_US) {
        if let Some(slot) = answers.frames.get_mut(answers.n) {
            *slot = f;
        }
        answers.n += 1;
    }
    answers
}

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

/// Runs `work` between the markers as scenario `id` (its name is `NAMES[id]`).
fn measure<R>(id: u32, work: impl FnOnce() -> R) -> R {
    bench_begin(id);
    let result = work();
    bench_end();
    result
}

/// Prints what went wrong and ends the run with a failure exit code.
fn fail(what: &str, answers: &Answers) -> ! {
    hprintln!("bench: FAILED: {}", what);
    for i in 0..answers.n.min(answers.frames.len()) {
        if let Some(f) = answers.get(i) {
            hprintln!("bench:   frame {}: id {:#05x} data {:02x?}", i, f.id, f.payload());
        }
    }
    hprintln!("bench:   ({} frame(s) in all)", answers.n);
    debug::exit(debug::EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}

/// Checks that exactly `expected` frames came back, each with its COB-ID and payload.
fn expect(what: &str, answers: &Answers, expected: &[(u16, &[u8])]) {
    if answers.n != expected.len() {
        fail(what, answers);
    }
    for (i, (id, data)) in expected.iter().enumerate() {
        match answers.get(i) {
            Some(f) if f.id == *id && f.payload() == *data => {}
            _ => fail(what, answers),
        }
    }
}

/// An expedited SDO download done during setup (not measured); fails on anything but the
/// confirmation.
fn sdo_write(device: &mut Module, index: u16, sub: u8, value: &[u8]) {
    let [lo, hi] = index.to_le_bytes();
    let command = 0x23 | ((4 - value.len() as u8) << 2);
    let mut request = [command, lo, hi, sub, 0, 0, 0, 0];
    for (dst, &b) in request.iter_mut().skip(4).zip(value) {
        *dst = b;
    }
    let answers = exchange(device, &frame(SDO_RX, &request));
    expect("setup SDO download", &answers, &[(SDO_TX, &[0x60, lo, hi, sub, 0, 0, 0, 0])]);
}

// The stack bounds cortex-m-rt's linker script defines: the initial stack pointer (top of
// RAM) and the end of .bss/.uninit, below which the stack must never grow.
unsafe extern "C" {
    static _stack_start: u32;
    static __sheap: u32;
}

fn stack_bounds() -> (usize, usize) {
    // Only the symbols' addresses are taken; nothing is read through them.
    let bottom = core::ptr::addr_of!(__sheap) as usize;
    let top = core::ptr::addr_of!(_stack_start) as usize;
    (bottom, top)
}

/// Fills the never-used stack, from the end of .bss up to a margin below the current stack
/// pointer, with [`PAINT`].
fn paint_stack() {
    let (bottom, _) = stack_bounds();
    let limit = (cortex_m::register::msp::read() as usize).saturating_sub(PAINT_MARGIN) & !3;
    let mut at = bottom;
    while at < limit {
        // SAFETY: `at` is word-aligned and lies between the end of .bss and a margin below the
        // live stack: RAM no Rust object occupies, and nothing else runs (no interrupts).
        unsafe { core::ptr::write_volatile(at as *mut u32, PAINT) };
        at += 4;
    }
}

/// The deepest the stack has been since [`paint_stack`], in bytes below its top.
fn stack_peak() -> usize {
    let (bottom, top) = stack_bounds();
    let mut at = bottom;
    // SAFETY: as in `paint_stack`, word-aligned addresses of free RAM below the live stack
    // (the scan stops at the first word that is no longer the pattern).
    while at < top && unsafe { core::ptr::read_volatile(at as *const u32) } == PAINT {
        at += 4;
    }
    top - at
}

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
    let _ = drain(device);
    // TPDO1 (6000.1, 6000.2) synchronous; TPDO2 mapped to 6000.1, 6000.2 and the error
    // register, synchronous, enabled (CiA 301: mapping only while the PDO is invalid).
    sdo_write(device, 0x1800, 2, &[1]);
    sdo_write(device, 0x1801, 2, &[1]);
    sdo_write(device, 0x1A01, 0, &[0]);
    sdo_write(device, 0x1A01, 1, &0x6000_0108_u32.to_le_bytes());
    sdo_write(device, 0x1A01, 2, &0x6000_0208_u32.to_le_bytes());
    sdo_write(device, 0x1A01, 3, &0x1001_0008_u32.to_le_bytes());
    sdo_write(device, 0x1A01, 0, &[3]);
    sdo_write(device, 0x1801, 1, &0x0000_0285_u32.to_le_bytes());
    // NMT Start Remote Node.
    let _ = exchange(device, &frame(0x000, &[0x01, NODE_ID]));
    if device.state() != coforge_stack::nmt::NmtState::Operational {
        fail("NMT start: not operational", &Answers { frames: [frame(0, &[]); 4], n: 0 });
    }

    // The stack peak so far (construction, start, setup), then a fresh paint for the scenarios.
    hprintln!("stack-peak-setup-bytes: {}", stack_peak());
    paint_stack();

    // 0: nothing between the markers: the markers' own cost, which xtask subtracts.
    measure(0, || {});

    let request = frame(SDO_RX, &[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]);
    let answers = measure(1, || exchange(device, &request));
    expect("SDO upload 1018.1 (vendor ID 0x58)", &answers, &[(SDO_TX, &[0x43, 0x18, 0x10, 0x01, 0x58, 0, 0, 0])]);

    let request = frame(SDO_RX, &[0x2B, 0x80, 0x21, 0x00, 0xF4, 0x01, 0, 0]);
    let answers = measure(2, || exchange(device, &request));
    expect("SDO download 2180.0 = 500", &answers, &[(SDO_TX, &[0x60, 0x80, 0x21, 0x00, 0, 0, 0, 0])]);

    let request = frame(SDO_RX, &[0x2F, 0x12, 0x50, 0x04, 0x23, 0, 0, 0]);
    let answers = measure(3, || exchange(device, &request));
    expect("SDO download 5012.4 = 0x23", &answers, &[(SDO_TX, &[0x60, 0x12, 0x50, 0x04, 0, 0, 0, 0])]);

    // 1008h Device Name, 12 bytes: the initiate is setup, the first segment is measured.
    let answers = exchange(device, &frame(SDO_RX, &[0x40, 0x08, 0x10, 0x00, 0, 0, 0, 0]));
    expect("SDO initiate upload 1008.0", &answers, &[(SDO_TX, &[0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0])]);
    let request = frame(SDO_RX, &[0x60, 0, 0, 0, 0, 0, 0, 0]);
    let answers = measure(4, || exchange(device, &request));
    expect("SDO upload segment 1 of 1008.0", &answers, &[(SDO_TX, b"\x00CO401Me")]);
    let answers = exchange(device, &frame(SDO_RX, &[0x70, 0, 0, 0, 0, 0, 0, 0]));
    expect("SDO upload segment 2 of 1008.0", &answers, &[(SDO_TX, b"\x15mory1\0\0")]);

    // RPDO1 (COB-ID 0x205) maps 6200.1 and 6200.2: command 0x91 clears each bank's status,
    // which ends the two memory-bank emergencies: one EMCY per condition that ends, the
    // first still with the error register and the other bank's CO40xx bits, the second
    // all zero (codes combined with OR, `node_config`).
    let request = frame(0x200 + u16::from(NODE_ID), &[0x91, 0x91]);
    let answers = measure(5, || exchange(device, &request));
    let emcy = 0x080 + u16::from(NODE_ID);
    expect("RPDO1 0x91 0x91: two EMCY error resets", &answers, &[(emcy, &[0, 0, 0x01, 0, 0x20, 0, 0, 0]), (emcy, &[0; 8])]);
    if device.node().od().app.status(0).bits() != 0 || device.node().od().app.status(1).bits() != 0 {
        fail("RPDO1 0x91 0x91: bank status not cleared", &answers);
    }

    let request = frame(0x080, &[]);
    let answers = measure(6, || exchange(device, &request));
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
    if out.get(..n) != Some(&[0x32, 0x01, 0x23][..]) {
        hprintln!("bench: serial answer {:02x?}", out.get(..n).unwrap_or(&[]));
        fail("serial Read Memory 5012.04: expected 32 01 23", &Answers { frames: [frame(0, &[]); 4], n: 0 });
    }

    // RPDO1 again with command bytes that mean nothing: the stack's RPDO path (match the
    // COB-ID, unpack the mapping, two app writes) without the banks' work; nothing is sent.
    let request = frame(0x200 + u16::from(NODE_ID), &[0x00, 0x00]);
    let answers = measure(8, || exchange(device, &request));
    expect("RPDO1 0x00 0x00: nothing to send", &answers, &[]);
    let mut command = [0xFF_u8; 1];
    for sub in [1, 2] {
        let read = device.node_mut().read(0x6200, sub, 0, &mut command, Side::Device);
        if read.is_err() || command != [0] {
            fail("RPDO1 0x00 0x00: command bytes not stored", &answers);
        }
    }

    let peak = stack_peak();
    for (id, name) in NAMES.iter().enumerate() {
        hprintln!("bench {} {}", id, name);
    }
    hprintln!("stack-peak-bytes: {}", peak);
    hprintln!("bench: all answers as expected");
    debug::exit(debug::EXIT_SUCCESS);
    #[allow(clippy::empty_loop)]
    loop {}
}
