//! CANopenIA on an STM32F0 with bxCAN: the image of the STM32F091RC (`firmware/boards/stm32f091`,
//! the coprocessor's own MCU family) and of the STM32F042K6 (this crate's `canopenia`, pending:
//! it does not fit the chip). Both run [`run`]; only the chip feature and the memory map differ.
//! Pin map: `firmware/boards/stm32f091/PINS.md`.
//!
//! - The host's remote-access protocol on USART2 (PA2 TX, PA3 RX) at 921600 8N1: 48 MHz / 52
//!   = 923,077 baud, 0.16 % fast.
//! - CAN on bxCAN (PA12 TX, PA11 RX, AF4) at the bit rate and node-ID of the loaded
//!   configuration file, or [`CAN_KBIT`] and [`NODE_ID`] without one (or when it leaves them to
//!   the hardware). The STM32F091RC keeps its files in its last 16 KiB of flash
//!   (`crate::config_flash`); the STM32F042K6 has no room for them (`NoMemory`).
//! - 1018h.4, the serial number and activation key of configuration loading: the chip's unique
//!   ID folded to 32 bits ([`serial_number`]).
//! - AUTORUN on PA8 (input with pull-down: open = no autostart), read once at reset.
//! - The parameters 1010h saves in a 24C128 at 0x50 on I2C1 (PB6 SCL, PB7 SDA), as CO401GW1's.
//! - The CiA 303-3 run and error LEDs on PB0 and PB1, active low.

use crate::i2c::{self, PARAM_EEPROM_BYTES, ParamEeprom};
use crate::serve::serve;
use crate::{can, clock, halt};
use canopenia::app::Typed;
#[cfg(not(feature = "stm32f091"))]
use canopenia::config::slots::NoMemory;
use canopenia::objects::Coprocessor as App;
use canopenia::{Canopenia, Od};
use coforge_stack::od::NodeDictionary;
use coforge_stack::store::BlockStore;
use embedded_hal_02::digital::v2::{InputPin, OutputPin};
use stm32f0xx_hal::can::CanInstance;
use stm32f0xx_hal::can::bxcan::{self, filter::Mask32};
use stm32f0xx_hal::i2c::I2c;
use stm32f0xx_hal::pac;
use stm32f0xx_hal::prelude::*;
use stm32f0xx_hal::serial::Serial;

/// Where configuration files live: the F091's own flash; none on the F042.
#[cfg(feature = "stm32f091")]
type Files = crate::config_flash::ConfigFlash;
#[cfg(not(feature = "stm32f091"))]
type Files = NoMemory;

/// The coprocessor with its parameter store and its configuration files.
pub type Coprocessor = Canopenia<BlockStore<ParamEeprom>, Files>;

/// The node-ID: the manual sets it only in a loaded configuration file (none yet), so the
/// QEMU image's and the simulator's.
pub const NODE_ID: u8 = 2;
/// The CAN bit rate, kbit/s: likewise the configuration file's, so a fixed default.
pub const CAN_KBIT: u32 = 125;
/// The host UART's baud rate, the manual's.
pub const HOST_BAUD: u32 = 921_600;

// Both slots of the parameter block fit the EEPROM.
const _: () = assert!(BlockStore::<ParamEeprom>::capacity_for(<Od<Typed<App>> as NodeDictionary>::PERSISTENT_SIZE) <= PARAM_EEPROM_BYTES);

/// Sets up the chip, builds the coprocessor and serves it for ever. Called once, from the
/// image's entry point (a second call finds the peripherals and the coprocessor taken and
/// halts).
///
/// `#[inline]`: compiled with the image rather than optimised in this library first, which
/// left it 396 bytes larger.
#[inline]
pub fn run() -> ! {
    let (Some(core), Some(mut p)) = (cortex_m::Peripherals::take(), pac::Peripherals::take()) else { halt() };
    let mut rcc = clock::start_core(p.RCC, &mut p.FLASH, core.SYST);

    let gpioa = p.GPIOA.split(&mut rcc);
    let gpiob = p.GPIOB.split(&mut rcc);
    let (can_pins, host_pins, i2c_pins, autorun, mut leds) = cortex_m::interrupt::free(|cs| {
        (
            (gpioa.pa12.into_alternate_af4(cs), gpioa.pa11.into_alternate_af4(cs)),
            (gpioa.pa2.into_alternate_af1(cs), gpioa.pa3.into_alternate_af1(cs)),
            (gpiob.pb6.into_alternate_af1(cs).set_open_drain(cs), gpiob.pb7.into_alternate_af1(cs).set_open_drain(cs)),
            gpioa.pa8.into_pull_down_input(cs),
            (gpiob.pb0.into_push_pull_output(cs), gpiob.pb1.into_push_pull_output(cs)),
        )
    });
    let _ = leds.0.set_high();
    let _ = leds.1.set_high();

    // The HAL enables and resets I2C1; its timing is replaced (see `i2c`).
    let (i2c1, _pins) = I2c::i2c1(p.I2C1, i2c_pins, 400.khz(), &mut rcc).release();
    #[cfg(feature = "stm32f091")]
    let files = crate::config_flash::ConfigFlash::new(p.FLASH);
    #[cfg(not(feature = "stm32f091"))]
    let files = NoMemory;
    let Some(device) = mount(BlockStore::new(i2c::param_eeprom(i2c1), 0), files) else { halt() };
    device.set_serial_number(serial_number());
    // Read once, before the coprocessor starts; building it took far longer than the
    // pull-down needs to settle an open pin.
    device.set_autorun(autorun.is_high().unwrap_or(false));

    let host = Serial::usart2(p.USART2, host_pins, HOST_BAUD.bps(), &mut rcc);
    let mut bxcan = bxcan::Can::builder(CanInstance::new(p.CAN, can_pins.0, can_pins.1, &mut rcc))
        .set_bit_timing(can::bit_timing(device.settings().bitrate_kbit.map_or(CAN_KBIT, u32::from)))
        .leave_disabled();
    bxcan.modify_filters().enable_bank(0, Mask32::accept_all());
    // `serve` enables the controller at once (the coprocessor's CAN side is always on).

    serve(device, host, bxcan, leds)
}

/// The coprocessor in a static (`.bss`), built in a frame of its own so that its
/// construction's temporaries leave the stack before the loop starts.
#[inline(never)]
fn mount(store: BlockStore<ParamEeprom>, files: Files) -> Option<&'static mut Coprocessor> {
    cortex_m::singleton!(: Coprocessor = Canopenia::with_configuration(NODE_ID, store, files))
}

/// The chip's serial number for 1018h.4: its 96-bit unique ID folded to 32 bits (XOR of its
/// three words), the same on every start.
pub fn serial_number() -> u32 {
    /// The unique device ID register of the STM32F0 family (reference manual RM0091, 33.1).
    const UID: usize = 0x1FFF_F7AC;
    // SAFETY: UID is three read-only words of system memory, present on every STM32F0 and
    // readable at any time; read by value, never referenced.
    #[allow(unsafe_code)]
    let words = unsafe { [0, 4, 8].map(|o| core::ptr::read_volatile((UID + o) as *const u32)) };
    words.iter().fold(0, |acc, w| acc ^ w)
}
