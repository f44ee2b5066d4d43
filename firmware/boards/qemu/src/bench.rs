//! What the bench images (`bench-*`, run by `cargo xtask bench`) share: the marker functions
//! the instruction-counting QEMU plugin (`bench/insn-count`) watches, the answers a device
//! gave to one input, the checks that end a run with a failure exit code, and the painted
//! stack whose deepest use the images report.
//!
//! The plugin numbers scenarios by the order `bench_begin` is hit; each image prints
//! `bench <id> <name>` for every scenario at the end (a print between scenarios would go
//! deeper into the stack than the device and spoil the stack peak).

use coforge_stack::device::Device;
use coforge_stack::frame::CanFrame;
use cortex_m_semihosting::{debug, hprintln};

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

/// Runs `work` between the markers as scenario `id`.
pub fn measure<R>(id: u32, work: impl FnOnce() -> R) -> R {
    bench_begin(id);
    let result = work();
    bench_end();
    result
}

/// The frames a device sent for one input (the first few, and how many in all).
pub struct Answers {
    pub frames: [CanFrame; 4],
    pub n: usize,
}

impl Answers {
    pub const NONE: Answers = Answers { frames: [CanFrame { id: 0, rtr: false, dlc: 0, data: [0; 8] }; 4], n: 0 };

    pub fn get(&self, i: usize) -> Option<&CanFrame> {
        self.frames.get(..self.n.min(self.frames.len()))?.get(i)
    }
}

/// A data frame (an empty one at `id` if `data` is longer than 8 bytes).
pub fn frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::data(id, data).unwrap_or(CanFrame { id, rtr: false, dlc: 0, data: [0; 8] })
}

/// Hands one frame to the device and polls until it is quiet. Inlined, as the images' own
/// loops were: the figures count the device, not a call more.
#[inline(always)]
pub fn exchange(device: &mut impl Device, input: &CanFrame, now_us: u64) -> Answers {
    device.on_frame(input, now_us);
    drain(device, now_us)
}

/// Polls the device until it has nothing more to send.
#[inline(always)]
pub fn drain(device: &mut impl Device, now_us: u64) -> Answers {
    let mut answers = Answers::NONE;
    while let Some(f) = device.poll(now_us) {
        if let Some(slot) = answers.frames.get_mut(answers.n) {
            *slot = f;
        }
        answers.n += 1;
    }
    answers
}

/// Prints what went wrong and ends the run with a failure exit code.
pub fn fail(what: &str, answers: &Answers) -> ! {
    hprintln!("bench: FAILED: {}", what);
    for i in 0..answers.n.min(answers.frames.len()) {
        if let Some(f) = answers.get(i) {
            hprintln!("bench:   frame {}: id {:#05x} data {:02x?}", i, f.id, f.payload());
        }
    }
    hprintln!("bench:   ({} frame(s) in all)", answers.n);
    exit(false)
}

/// Checks that exactly `expected` frames came back, each with its COB-ID and payload.
pub fn expect(what: &str, answers: &Answers, expected: &[(u16, &[u8])]) {
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

/// Checks a serial answer; prints it and fails if it is not `expected`.
pub fn expect_bytes(what: &str, got: &[u8], expected: &[u8]) {
    if got != expected {
        hprintln!("bench: serial answer {:02x?}, expected {:02x?}", got, expected);
        fail(what, &Answers::NONE);
    }
}

/// Prints the scenario names and the stack peak, then ends the run successfully.
pub fn finish(names: &[&str], peak: usize) -> ! {
    for (id, name) in names.iter().enumerate() {
        hprintln!("bench {} {}", id, name);
    }
    hprintln!("stack-peak-bytes: {}", peak);
    hprintln!("bench: all answers as expected");
    exit(true)
}

fn exit(success: bool) -> ! {
    debug::exit(if success { debug::EXIT_SUCCESS } else { debug::EXIT_FAILURE });
    #[allow(clippy::empty_loop)]
    loop {}
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
pub fn paint_stack() {
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
pub fn stack_peak() -> usize {
    let (bottom, top) = stack_bounds();
    let mut at = bottom;
    // SAFETY: as in `paint_stack`, word-aligned addresses of free RAM below the live stack
    // (the scan stops at the first word that is no longer the pattern).
    while at < top && unsafe { core::ptr::read_volatile(at as *const u32) } == PAINT {
        at += 4;
    }
    top - at
}

/// An expedited SDO download to node `node_id` done during setup (not measured); fails on
/// anything but the confirmation.
pub fn sdo_write(device: &mut impl Device, node_id: u8, index: u16, sub: u8, value: &[u8], now_us: u64) {
    let [lo, hi] = index.to_le_bytes();
    let command = 0x23 | ((4 - value.len().min(4) as u8) << 2);
    let mut request = [command, lo, hi, sub, 0, 0, 0, 0];
    for (dst, &b) in request.iter_mut().skip(4).zip(value) {
        *dst = b;
    }
    let answers = exchange(device, &frame(0x600 + u16::from(node_id), &request), now_us);
    expect("setup SDO download", &answers, &[(0x580 + u16::from(node_id), &[0x60, lo, hi, sub, 0, 0, 0, 0])]);
}
