//! The SD card on SPI1 (PA5 SCK, PA6 MISO, PA7 MOSI, PA4 card select) as embedded-sdmmc's
//! block device: `embedded_sdmmc::SdCard` over embedded-hal-bus's `ExclusiveDevice`.
//!
//! embedded-sdmmc 0.10 takes an embedded-hal 1.0 `SpiDevice` and `DelayNs`; stm32f0xx-hal 0.18's
//! SPI driver implements embedded-hal 0.2's blocking `Transfer`/`Write`. [`SdBus`] is the
//! adapter: an embedded-hal 1.0 `SpiBus` over the HAL's driver, which `ExclusiveDevice` turns
//! into the `SpiDevice` with the card select ([`CardSelect`]). Why not embedded-hal-compat's
//! `Forward` (the ecosystem's 0.2 -> 1.0 bridge): its `read` clocks out 00h where a card needs
//! FFh on MOSI, its `transfer` slices `write` by `read`'s length (a panic when shorter), and
//! neither it nor the HAL can change the clock rate, which an SD card needs (at most 400 kHz
//! until it is initialised, then fast). [`SdBus`] clocks out FFh, follows embedded-hal 1.0's
//! `transfer` for any two lengths, and changes the rate by making the HAL's driver anew
//! ([`SdBus::set_rate`]: the driver has no setter, so the bus keeps the HAL's `Rcc` for it).
//!
//! The card's 74 start-up clocks with its select high (the physical layer's power-up
//! sequence, which embedded-sdmmc leaves to the caller) are [`SdBus::idle_clocks`].

use crate::clock::CORE_HZ;
use core::convert::Infallible;
use embedded_hal::spi::{ErrorKind, ErrorType, SpiBus};
use embedded_hal_02::blocking::spi::{Transfer, Write};
use embedded_hal_02::digital::v2::OutputPin as OutputPin02;
use embedded_hal_bus::spi::ExclusiveDevice;
use embedded_sdmmc::sdcard::spi::AcquireOpts;
use stm32f0xx_hal::gpio::gpioa::{PA4, PA5, PA6, PA7};
use stm32f0xx_hal::gpio::{AF0, Alternate, Output, PushPull};
use stm32f0xx_hal::pac::SPI1;
use stm32f0xx_hal::prelude::*;
use stm32f0xx_hal::rcc::Rcc;
use stm32f0xx_hal::spi::{EightBit, Mode, Phase, Polarity, Spi};

/// SCK, MISO, MOSI: PA5, PA6, PA7 in AF0.
pub type SpiPins = (PA5<Alternate<AF0>>, PA6<Alternate<AF0>>, PA7<Alternate<AF0>>);
/// SPI1 on [`SpiPins`], 8-bit frames.
pub type Spi1 = Spi<SPI1, PA5<Alternate<AF0>>, PA6<Alternate<AF0>>, PA7<Alternate<AF0>>, EightBit>;

/// The card as the logger's block device.
pub type SdCard = embedded_sdmmc::SdCard<ExclusiveDevice<SdBus, CardSelect, UsDelay>, UsDelay>;

/// SPI mode 0 (clock idle low, data sampled on the rising edge): what SD cards use.
pub const MODE: Mode = Mode { polarity: Polarity::IdleLow, phase: Phase::CaptureOnFirstTransition };
/// The clock until the card is initialised (at most 400 kHz): 48 MHz / 128 = 375 kHz.
pub const INIT_HZ: u32 = 400_000;
/// The clock after: 48 MHz / 4 = 12 MHz (a card in SPI mode takes up to 25 MHz; SCK and MOSI
/// are set to high-speed outputs for it).
pub const DATA_HZ: u32 = 12_000_000;

/// The bus failed (an overrun or mode fault the HAL reported; not seen in master mode with
/// polled transfers), or its driver is gone (a rate change that could not finish: never, the
/// driver is only moved out and straight back).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BusError;

impl embedded_hal::spi::Error for BusError {
    fn kind(&self) -> ErrorKind {
        ErrorKind::Other
    }
}

/// SPI1 as an embedded-hal 1.0 bus.
pub struct SdBus {
    spi: Option<Spi1>,
    /// The HAL's clock tree handle, needed to make the driver anew at another rate. It is the
    /// image's last user: everything else is set up before the bus is made.
    rcc: Rcc,
}

impl SdBus {
    /// The bus at [`INIT_HZ`].
    pub fn new(spi1: SPI1, pins: SpiPins, mut rcc: Rcc) -> Self {
        let spi = Spi::spi1(spi1, pins, MODE, INIT_HZ.hz(), &mut rcc);
        SdBus { spi: Some(spi), rcc }
    }

    /// Sets the clock to at most `hz` (the HAL picks the next prescaler down from 48 MHz): the
    /// driver is released and made again, which also resets SPI1 (between transactions only).
    pub fn set_rate(&mut self, hz: u32) {
        if let Some(spi) = self.spi.take() {
            let (spi1, pins) = spi.release();
            self.spi = Some(Spi::spi1(spi1, pins, MODE, hz.hz(), &mut self.rcc));
        }
    }

    /// 80 clocks with MOSI high: with the card's select high, the power-up clocks a card needs
    /// before its first command.
    pub fn idle_clocks(&mut self) -> Result<(), BusError> {
        self.write(&[0xFF; 10])
    }

    fn spi(&mut self) -> Result<&mut Spi1, BusError> {
        self.spi.as_mut().ok_or(BusError)
    }
}

impl ErrorType for SdBus {
    type Error = BusError;
}

impl SpiBus<u8> for SdBus {
    /// Clocks out FFh (MOSI high), as a card expects while it answers.
    fn read(&mut self, words: &mut [u8]) -> Result<(), BusError> {
        words.fill(0xFF);
        self.transfer_in_place(words)
    }

    fn write(&mut self, words: &[u8]) -> Result<(), BusError> {
        self.spi()?.write(words).map_err(|_| BusError)
    }

    /// `max(read, write)` bytes: FFh after the end of `write`, what comes after the end of
    /// `read` dropped.
    fn transfer(&mut self, read: &mut [u8], write: &[u8]) -> Result<(), BusError> {
        if read.len() == write.len() {
            read.copy_from_slice(write);
            return self.transfer_in_place(read);
        }
        for i in 0..read.len().max(write.len()) {
            let mut byte = [write.get(i).copied().unwrap_or(0xFF)];
            self.transfer_in_place(&mut byte)?;
            if let (Some(r), [b]) = (read.get_mut(i), byte) {
                *r = b;
            }
        }
        Ok(())
    }

    fn transfer_in_place(&mut self, words: &mut [u8]) -> Result<(), BusError> {
        self.spi()?.transfer(words).map(|_| ()).map_err(|_| BusError)
    }

    /// Nothing in flight: the HAL's `write` returns once SPI1 is no longer busy, its
    /// `transfer` once the last byte came back.
    fn flush(&mut self) -> Result<(), BusError> {
        Ok(())
    }
}

/// The card select, PA4, active low, as an embedded-hal 1.0 output for `ExclusiveDevice`.
pub struct CardSelect(pub PA4<Output<PushPull>>);

impl embedded_hal::digital::ErrorType for CardSelect {
    type Error = Infallible;
}

impl embedded_hal::digital::OutputPin for CardSelect {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.0.set_low()
    }

    fn set_high(&mut self) -> Result<(), Infallible> {
        self.0.set_high()
    }
}

/// Busy-waits of microsecond resolution: embedded-sdmmc retries every 10 us (up to 10,000
/// times for a read, 50,000 for a write), which [`crate::clock::MsDelay`] would stretch to
/// 2 ms each (time-outs of 20 and 100 s instead of 0.1 and 0.5 s).
#[derive(Debug, Clone, Copy, Default)]
pub struct UsDelay;

impl embedded_hal::delay::DelayNs for UsDelay {
    fn delay_ns(&mut self, ns: u32) {
        // Whole microseconds; at most 4.3 s (u32 nanoseconds), 206 million clocks: no overflow.
        cortex_m::asm::delay(ns.div_ceil(1000).saturating_mul(CORE_HZ / 1_000_000));
    }
}

/// CMD0 attempts before a card counts as absent. Each attempt that gets no answer waits out
/// the driver's command time-out (10,000 bytes at 375 kHz, some 0.35 s): embedded-sdmmc's 50
/// would block the main loop (and CAN) for some 18 s when the detect switch reports a card that
/// does not answer; 5 keep that under 2 s, and a card answers its first or second CMD0.
pub const ACQUIRE_RETRIES: u32 = 5;

/// The card on `bus` and `select`: embedded-sdmmc's driver (CRC on), which initialises it at
/// its first access. The select goes high at once.
pub fn card(bus: SdBus, select: CardSelect) -> SdCard {
    // `CardSelect` cannot fail (`Infallible`): the `Err` arm is never taken.
    let device = match ExclusiveDevice::new(bus, select, UsDelay) {
        Ok(device) => device,
        Err(never) => match never {},
    };
    embedded_sdmmc::SdCard::new_with_options(device, UsDelay, AcquireOpts { use_crc: true, acquire_retries: ACQUIRE_RETRIES })
}
