//! The CO401GW1 image's start-up and run loop, for every chip that carries the gateway's board
//! (the STM32F042C6 of this crate and the pin-compatible STM32F072CB of
//! `firmware/boards/stm32f072`): CAN on bxCAN at the BD pins' bit rate, the gateway's host
//! protocol on USART2 at the RSBD pins' baud rate, the parameters of 1010h/1011h in a 24C128
//! EEPROM on I2C1.

use super::{Gw1Board, Ports};
use crate::board::ConfigChain;
use crate::i2c::{self, PARAM_EEPROM_BYTES, ParamEeprom as Eeprom};
use crate::serve::{OwnIndicators, serve};
use crate::{can, clock, halt};
use co401gw1::app::Typed;
use co401gw1::{Board, Gw1, IoImage, Od, hardware};
use coforge_stack::od::NodeDictionary;
use coforge_stack::store::BlockStore;
use core::mem::MaybeUninit;
use stm32f0xx_hal::can::CanInstance;
use stm32f0xx_hal::can::bxcan::{self, filter::Mask32};
use stm32f0xx_hal::i2c::I2c;
use stm32f0xx_hal::pac;
use stm32f0xx_hal::prelude::*;
use stm32f0xx_hal::serial::Serial;

/// The whole chip: the gateway on this board, its parameters in the EEPROM.
pub type Chip = Gw1<Gw1Board, BlockStore<Eeprom>>;

// Both slots of the parameter block fit the EEPROM (1,106 bytes today).
const _: () = assert!(BlockStore::<Eeprom>::capacity_for(<Od<Typed<IoImage>> as NodeDictionary>::PERSISTENT_SIZE) <= PARAM_EEPROM_BYTES);
// The node (dictionary, every protocol engine, SDO buffer, queues, the store's handle) within
// the 2 KiB of the MCU family the original chip ran on, measured on this target: 1,928 bytes
// today (the whole chip with its process image, host protocol and pins: 2,712).
const _: () = assert!(core::mem::size_of::<co401gw1::Node<Typed<IoImage>, BlockStore<Eeprom>>>() <= 2048);

/// Starts the chip in `slot` and runs it for ever. The image's `#[entry]` owns `slot` as a
/// `static mut` (cortex-m-rt hands it over as `&'static mut`, no unsafe), so the chip lives in
/// .bss and nothing large is built on the stack. `MaybeUninit` rather than `Option`: `None`
/// of the chip is not all zeros, which would put its 2.7 KiB in .data, i.e. also in flash.
///
/// `#[inline]` so it is compiled with the image rather than in this library: optimised here
/// first, the node's code came out 644 bytes larger.
#[inline]
pub fn run(slot: &'static mut MaybeUninit<Chip>) -> ! {
    let (Some(core), Some(mut p)) = (cortex_m::Peripherals::take(), pac::Peripherals::take()) else { halt() };

    let mut rcc = clock::start_core(p.RCC, &mut p.FLASH, core.SYST);

    let gpioa = p.GPIOA.split(&mut rcc);
    let gpiob = p.GPIOB.split(&mut rcc);
    // The HAL configures its peripherals' pins and the chain's; `Ports` the plain ones.
    let (can_pins, host_pins, i2c_pins, mut chain) = cortex_m::interrupt::free(|cs| {
        (
            (gpioa.pa12.into_alternate_af4(cs), gpioa.pa11.into_alternate_af4(cs)),
            (gpioa.pa2.into_alternate_af1(cs), gpioa.pa3.into_alternate_af1(cs)),
            (gpiob.pb6.into_alternate_af1(cs).set_open_drain(cs), gpiob.pb7.into_alternate_af1(cs).set_open_drain(cs)),
            ConfigChain { clk: gpiob.pb3.into_push_pull_output(cs), load: gpiob.pb4.into_push_pull_output(cs), data: gpiob.pb5.into_pull_up_input(cs) },
        )
    });
    let ports = Ports::take();
    ports.configure();

    // The pins read at reset: CFG0..CFG2 directly, ID, BD and RSBD through the chain. Then
    // CFG0/R, CFG1/E and CFG2/WD become outputs (high: LEDs dark).
    let cfg = ports.cfg_levels();
    let levels = chain.read();
    ports.cfg_to_outputs();
    let mut board = Gw1Board::new(levels, cfg, ports);

    // BD0..BD2: every code is a bit rate. RSBD0..RSBD2 = 000 and 100 are reserved: the chip
    // does not start, the error LED says so.
    let can_kbit = hardware::can_bitrate(levels.can_bitrate()).unwrap_or(1000);
    let Some(baud) = hardware::serial_bitrate(levels.serial_bitrate()) else {
        board.set_indicators(false, true, true);
        halt()
    };

    // The HAL enables and resets I2C1; its timing is replaced (see `i2c`).
    let (i2c1, _pins) = I2c::i2c1(p.I2C1, i2c_pins, 400.khz(), &mut rcc).release();
    let chip = build(slot, board, BlockStore::new(i2c::param_eeprom(i2c1), 0));

    let host = Serial::usart2(p.USART2, host_pins, baud.bps(), &mut rcc);
    let mut bxcan = bxcan::Can::builder(CanInstance::new(p.CAN, can_pins.0, can_pins.1, &mut rcc)).set_bit_timing(can::bit_timing(can_kbit)).leave_disabled();
    bxcan.modify_filters().enable_bank(0, Mask32::accept_all());
    // `serve` enables the controller once the device's CAN side is active: for the chip, when
    // the host enables CAN. Until then the controller stays off the bus (it neither
    // acknowledges nor sends), as the chip's CAN side is off.

    serve(chip, host, bxcan, OwnIndicators)
}

/// Builds the chip (reading its pins at reset) right in `slot`, not on the stack to be moved
/// there. Not inlined: its temporaries would otherwise keep their share of the 6 KiB stack in
/// `run` for ever.
#[inline(never)]
fn build(slot: &'static mut MaybeUninit<Chip>, board: Gw1Board, store: BlockStore<Eeprom>) -> &'static mut Chip {
    slot.write(Gw1::new(board, store))
}
