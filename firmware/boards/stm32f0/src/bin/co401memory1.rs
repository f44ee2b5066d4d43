//! CO401Memory1 on the STM32F042K6 board: CAN on bxCAN at the BD pins' bit rate, the serial
//! host protocol on USART2 at the RSBD pins' baud rate, the two banks in two 24C128 EEPROMs.
//! Pin map: the `coforge_board_stm32f0` crate documentation and `PINS.md`.
//!
//! `cargo build --release` here, then `cargo xtask flash --device co401memory1 --board stm32f0
//! --chip STM32F042K6Tx` (or `probe-rs run --chip STM32F042K6Tx <elf>`).
#![no_std]
#![no_main]
#![deny(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used)]

use co401memory1::{ConfigError, Memory1};
use coforge_board_stm32f0::board::{ConfigChain, StatusPins, Stm32Board};
use coforge_board_stm32f0::serve::serve;
use coforge_board_stm32f0::{can, clock, i2c::I2cBus};
use core::cell::RefCell;
use core::mem::MaybeUninit;
use cortex_m_rt::entry;
use eeprom24x::{Eeprom24x, SlaveAddr, Storage};
use embedded_hal_02::digital::v2::OutputPin;
use embedded_hal_bus::i2c::RefCellDevice;
use panic_halt as _;
use stm32f0xx_hal::can::CanInstance;
use stm32f0xx_hal::can::bxcan::{self, filter::Mask32};
use stm32f0xx_hal::i2c::I2c;
use stm32f0xx_hal::pac;
use stm32f0xx_hal::prelude::*;
use stm32f0xx_hal::serial::Serial;

/// One bank: a 24C128 (16 KiB, 64-byte pages, two address bytes) on the shared bus.
type Bank = Storage<RefCellDevice<'static, I2cBus>, eeprom24x::page_size::B64, eeprom24x::addr_size::TwoBytes, eeprom24x::unique_serial::No, clock::MsDelay>;
type Device = Memory1<Bank, Stm32Board>;

#[entry]
fn main() -> ! {
    // cortex-m-rt turns these into `&'static mut` (no unsafe): the bus and the module live in
    // .bss, so nothing large is built on the 6 KiB stack. `MaybeUninit` rather than `Option`:
    // `None` of the module is not all zeros, which would put its 1.9 KiB in .data, i.e. also
    // in flash; `MaybeUninit::write` is safe and hands out the `&'static mut`.
    static mut BUS: MaybeUninit<RefCell<I2cBus>> = MaybeUninit::uninit();
    static mut DEVICE: MaybeUninit<Result<Device, ConfigError>> = MaybeUninit::uninit();
    let (Some(core), Some(mut p)) = (cortex_m::Peripherals::take(), pac::Peripherals::take()) else { panic!("peripherals taken twice") };

    let mut rcc = clock::start_core(p.RCC, &mut p.FLASH, core.SYST);

    let gpioa = p.GPIOA.split(&mut rcc);
    let gpiob = p.GPIOB.split(&mut rcc);
    let (can_pins, host_pins, i2c_pins, supply_pin, status, mut leds, mut chain) = cortex_m::interrupt::free(|cs| {
        (
            (gpioa.pa12.into_alternate_af4(cs), gpioa.pa11.into_alternate_af4(cs)),
            (gpioa.pa2.into_alternate_af1(cs), gpioa.pa3.into_alternate_af1(cs)),
            (gpiob.pb6.into_alternate_af1(cs).set_open_drain(cs), gpiob.pb7.into_alternate_af1(cs).set_open_drain(cs)),
            gpioa.pa0.into_analog(cs),
            StatusPins {
                mem1_error: gpioa.pa4.into_push_pull_output(cs),
                mem2_error: gpioa.pa5.into_push_pull_output(cs),
                new_can_data: gpioa.pa6.into_push_pull_output(cs),
                voltage_low: gpioa.pa7.into_push_pull_output(cs),
            },
            (gpiob.pb0.into_push_pull_output(cs), gpiob.pb1.into_push_pull_output(cs)),
            ConfigChain { clk: gpiob.pb3.into_push_pull_output(cs), load: gpiob.pb4.into_push_pull_output(cs), data: gpiob.pb5.into_pull_up_input(cs) },
        )
    });
    let _ = leds.0.set_high();
    let _ = leds.1.set_high();

    // The HAL enables and resets I2C1; its timing is replaced (see `i2c`).
    let (i2c1, _pins) = I2c::i2c1(p.I2C1, i2c_pins, 400.khz(), &mut rcc).release();
    let bus: &'static RefCell<I2cBus> = BUS.write(RefCell::new(I2cBus::new(i2c1)));
    let bank = |a0| Storage::new(Eeprom24x::new_24x128(RefCellDevice::new(bus), SlaveAddr::Alternative(false, false, a0)), clock::MsDelay);
    let board = Stm32Board::new(chain.read(), stm32f0xx_hal::adc::Adc::new(p.ADC, &mut rcc), supply_pin, status);
    let Some(device) = mount(DEVICE, [bank(false), bank(true)], board) else {
        // Reserved configuration pins: the module does not start. The error LED says so.
        let _ = leds.1.set_low();
        loop {
            cortex_m::asm::wfi();
        }
    };
    let config = device.config();

    let host = Serial::usart2(p.USART2, host_pins, config.serial_baud.bps(), &mut rcc);
    let mut bxcan = bxcan::Can::builder(CanInstance::new(p.CAN, can_pins.0, can_pins.1, &mut rcc))
        .set_bit_timing(can::bit_timing(config.can_bitrate_kbit))
        .leave_disabled();
    bxcan.modify_filters().enable_bank(0, Mask32::accept_all());
    // `serve` enables the controller once the device's CAN side is active (at once here).

    serve(device, host, bxcan, leds)
}

/// Builds the module (reading the configuration, mounting the banks) right in `slot`, not on
/// the stack to be moved there (about 100 bytes less code). Not inlined:
/// the module's construction moves some kilobytes of temporaries, and in `main` they would keep
/// that much of the 6 KiB stack for ever; here they are gone when it returns.
#[inline(never)]
fn mount(slot: &'static mut MaybeUninit<Result<Device, ConfigError>>, banks: [Bank; 2], board: Stm32Board) -> Option<&'static mut Device> {
    slot.write(Memory1::new(banks, board)).as_mut().ok()
}
