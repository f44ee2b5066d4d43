//! CANopenIA on QEMU's lm3s6965evb: node-ID 2, the remote-access protocol of its host on
//! UART0, the coprocessor's CAN side as an SLCAN adapter on UART1 (see `serve`). QEMU's
//! UARTs have no bit rate, so the manual's 921600 8N1 is what a board's UART would be set to.
//! The parameters 1010h saves are kept in the host file `canopenia.params`, and the binary EDS
//! configurations loaded through 1F50h.2 (two slots) in `canopenia.config` (QEMU's working
//! directory), through semihosting, so both survive a restart of QEMU.
//!
//! ```text
//! qemu-system-arm -machine lm3s6965evb -nographic -monitor none \
//!     -semihosting-config enable=on,target=native -kernel canopenia \
//!     -serial tcp:127.0.0.1:P0,server=on,wait=off,nodelay=on \
//!     -serial tcp:127.0.0.1:P1,server=on,wait=off,nodelay=on
//! ```
#![no_std]
#![no_main]

use canopenia::app::Typed;
use canopenia::config::slots::ConfigSlots;
use canopenia::objects::Coprocessor;
use canopenia::{Canopenia, Od};
use coforge_board_qemu::host_file::HostFileEeprom;
use coforge_board_qemu::serve::serve;
use coforge_stack::od::NodeDictionary;
use coforge_stack::store::BlockStore;
use cortex_m_rt::entry;
use panic_semihosting as _;

type Store = BlockStore<HostFileEeprom<'static>>;
type Device = Canopenia<Store, HostFileEeprom<'static>>;

/// The parameter file: the two slots of the persistent entries' block.
const PARAMS: usize = Store::capacity_for(<Od<Typed<Coprocessor>> as NodeDictionary>::PERSISTENT_SIZE);
/// The configuration file: two slots of a binary EDS each.
const CONFIG: usize = ConfigSlots::<HostFileEeprom<'static>>::CAPACITY;
/// The chip's serial number (1018h.4, the activation key of configuration loading): the
/// lm3s6965 has no unique ID, so the board gives the manual's example chip's (section 4.2).
const SERIAL_NUMBER: u32 = 0x0404_0D41;
/// The node-ID without a loaded configuration.
const NODE_ID: u8 = 2;

#[entry]
fn main() -> ! {
    // The parameter file's RAM image, in .bss (cortex-m-rt makes it `&'static mut`, no unsafe).
    static mut PARAMS_IMAGE: [u8; PARAMS] = [0; PARAMS];
    static mut CONFIG_IMAGE: [u8; CONFIG] = [0; CONFIG];
    let Ok(file) = HostFileEeprom::open("canopenia.params\0", PARAMS_IMAGE) else { panic!("cannot open canopenia.params (is semihosting enabled?)") };
    let Ok(config) = HostFileEeprom::open("canopenia.config\0", CONFIG_IMAGE) else { panic!("cannot open canopenia.config") };
    serve(mount(BlockStore::new(file, 0), config))
}

/// The coprocessor in a static, built in a frame of its own so that its construction's
/// temporaries leave the stack before the loop starts (see `co401memory1`).
#[inline(never)]
fn mount(store: Store, config: HostFileEeprom<'static>) -> &'static mut Device {
    let Some(device) = cortex_m::singleton!(: Device = Canopenia::with_configuration(NODE_ID, store, config)) else { panic!("started twice") };
    device.set_serial_number(SERIAL_NUMBER);
    device
}
