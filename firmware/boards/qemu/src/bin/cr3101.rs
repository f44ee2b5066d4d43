//! CR3101 CANmem on QEMU's lm3s6965evb: factory node-ID 20h (20F0h/20F1h), the node's CAN
//! side as an SLCAN adapter on UART1 (see `serve`; SLCAN over a UART has no bit rate, so
//! 20F2h/20F3h choose nothing here), a console on UART2 (`leds`, `battery low|ok`; each line
//! answered `ok ...` or `error ...`), the memory card QEMU's SD card on SSI0 (see
//! `cr3101_board`: polled, taken out and put back with the QEMU monitor's `eject -f sd0` and
//! `change sd0 FILE raw`; QEMU needs a card image whose size is a power of two, such as
//! `coforge card FILE --mib 16` makes). UART0 is not used (the CR3101 has no serial host
//! line). The node's parameters (20F0h..20F5h, the communication parameters; 1010h) are kept
//! in the host file `cr3101.params` (QEMU's working directory) through semihosting, so they
//! survive a restart of QEMU. The clock starts at 2026-01-01 00:00 (no RTC on this board).
//!
//! ```text
//! qemu-system-arm -machine lm3s6965evb -nographic -monitor tcp:127.0.0.1:PM,server=on,wait=off \
//!     -semihosting-config enable=on,target=native -kernel cr3101 \
//!     -drive if=sd,format=raw,file=card.img \
//!     -serial tcp:127.0.0.1:P0,server=on,wait=off,nodelay=on \
//!     -serial tcp:127.0.0.1:P1,server=on,wait=off,nodelay=on \
//!     -serial tcp:127.0.0.1:P2,server=on,wait=off,nodelay=on
//! ```
#![no_std]
#![no_main]

use coforge_board_qemu::cr3101_board::{self, QemuBoard, QemuCard};
use coforge_board_qemu::host_file::HostFileEeprom;
use coforge_board_qemu::line_console::LineConsole;
use coforge_board_qemu::serve::serve_with;
use coforge_board_qemu::uart::UART2;
use coforge_stack::od::NodeDictionary;
use coforge_stack::store::{BlockStore, MAX_SLOTS};
use cortex_m_rt::entry;
use cr3101::Cr3101;
use cr3101::app::Typed;
use cr3101::logger::Logger;
use panic_semihosting as _;

type Store = BlockStore<HostFileEeprom<'static>>;
type Device = Cr3101<QemuBoard, Store>;

/// The parameter file: a ring of slots of the persistent entries' block, as many as the
/// simulator's (the CR3101 saves at every write of a parameter; the ring spreads the wear).
const PARAMS: usize = Store::capacity_for_slots(<cr3101::Od<Typed<Logger<QemuCard>>> as NodeDictionary>::PERSISTENT_SIZE, MAX_SLOTS);
/// 20F0h/20F1h until they are written: the manual's factory setting.
const NODE_ID: u8 = 0x20;
/// The longest console line, and the longest answer (an unknown command's quotes the line).
const LINE: usize = 64;
const ANSWER: usize = 160;

#[entry]
fn main() -> ! {
    // The parameter file's RAM image, in .bss (cortex-m-rt makes it `&'static mut`, no unsafe).
    static mut PARAMS_IMAGE: [u8; PARAMS] = [0; PARAMS];
    let Ok(file) = HostFileEeprom::open("cr3101.params\0", PARAMS_IMAGE) else { panic!("cannot open cr3101.params (is semihosting enabled?)") };
    let mut console = LineConsole::<LINE>::new(UART2);
    serve_with(mount(BlockStore::new(file, 0)), move |device, _now_ms| console.poll(|line| cr3101_board::console::<_, ANSWER>(device, line)))
}

/// The logger in a static, built in a frame of its own so that its construction's temporaries
/// leave the stack before the loop starts (see `co401memory1`).
#[inline(never)]
fn mount(store: Store) -> &'static mut Device {
    let Some(device) = cortex_m::singleton!(: Device = Cr3101::new(QemuBoard::new(), store, NODE_ID)) else { panic!("started twice") };
    device
}
