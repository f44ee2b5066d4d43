//! CO401GW1 on QEMU's lm3s6965evb: node-ID 5 on the ID pins, CFG1 high (mixed mode), the
//! serial host protocol on UART0, the chip's CAN side as an SLCAN adapter on UART1 (see
//! `serve`), and the pin console on UART2: a line (`in <bits>`, `emy0 on|off`, `emy1 on|off`,
//! `enable [alt]`, `pins`) is answered `ok <what it did>` or `error <why>`, ended by "\n"
//! (the simulator's console, `co401gw1::console`). The parameters 1010h saves are kept in
//! the host file `co401gw1.params` (QEMU's working directory) through semihosting, so they
//! survive a restart of QEMU.
//!
//! ```text
//! qemu-system-arm -machine lm3s6965evb -nographic -monitor none \
//!     -semihosting-config enable=on,target=native -kernel co401gw1 \
//!     -serial tcp:127.0.0.1:P0,server=on,wait=off,nodelay=on \
//!     -serial tcp:127.0.0.1:P1,server=on,wait=off,nodelay=on \
//!     -serial tcp:127.0.0.1:P2,server=on,wait=off,nodelay=on
//! ```
#![no_std]
#![no_main]

use co401gw1::app::Typed;
use co401gw1::console::{self, Answer};
use co401gw1::{FixedBoard, Gw1, IoImage, Od};
use coforge_board_qemu::host_file::HostFileEeprom;
use coforge_board_qemu::line_console::LineConsole;
use coforge_board_qemu::serve::serve_with;
use coforge_board_qemu::uart::UART2;
use coforge_stack::od::NodeDictionary;
use coforge_stack::store::BlockStore;
use cortex_m_rt::entry;
use panic_semihosting as _;

type Store = BlockStore<HostFileEeprom<'static>>;
type Device = Gw1<FixedBoard, Store>;

/// The parameter file: the two slots of the persistent entries' block.
const PARAMS: usize = Store::capacity_for(<Od<Typed<IoImage>> as NodeDictionary>::PERSISTENT_SIZE);
/// The node-ID the board's ID pins select.
const NODE_ID: u8 = 5;
/// The longest console line, and the longest answer (`pins` answers in 80 bytes; an unknown
/// command's answer quotes the line).
const LINE: usize = 64;
const ANSWER: usize = 200;

#[entry]
fn main() -> ! {
    // The parameter file's RAM image, in .bss (cortex-m-rt makes it `&'static mut`, no unsafe).
    static mut PARAMS_IMAGE: [u8; PARAMS] = [0; PARAMS];
    let Ok(file) = HostFileEeprom::open("co401gw1.params\0", PARAMS_IMAGE) else { panic!("cannot open co401gw1.params (is semihosting enabled?)") };
    let mut pins = LineConsole::<LINE>::new(UART2);
    serve_with(mount(BlockStore::new(file, 0)), move |chip, _now_ms| {
        pins.poll(|line| {
            let mut answer = Answer::<ANSWER>::new();
            (console::run(chip, line, &mut answer), answer)
        })
    })
}

/// The chip in a static, built in a frame of its own so that its construction's temporaries
/// leave the stack before the loop starts (see `co401memory1`).
#[inline(never)]
fn mount(store: Store) -> &'static mut Device {
    let Some(device) = cortex_m::singleton!(: Device = Gw1::new(FixedBoard::new(NODE_ID, true), store)) else { panic!("started twice") };
    device
}
