//! The SD card QEMU's lm3s6965evb has on SSI0 (`-drive if=sd,format=raw,file=card.img`), card
//! select on GPIO D0 (active low), as an `embedded-hal` 1.0 `SpiDevice` for `embedded-sdmmc`'s
//! SPI-mode card driver.
//!
//! QEMU 7.2's emulated card has two quirks this layer works around, harmless on a real card:
//! - it answers CMD58 (read OCR) with R1 = 01h (idle) where a card that finished its
//!   initialisation answers 00h; the driver takes 01h as an error, so R1 of CMD58 is passed on
//!   as 00h;
//! - it takes the data token of a block write only one byte after the command's R1; the layer
//!   sends one FFh before the token.

use crate::mmio::{read, write};
use core::convert::Infallible;
use embedded_hal::spi::{ErrorType, Operation, SpiDevice};

const SYSCTL_RCGC1: usize = 0x400F_E104;
const SYSCTL_RCGC2: usize = 0x400F_E108;
const RCGC1_SSI0: u32 = 1 << 4;
const RCGC2_GPIOA_D: u32 = (1 << 0) | (1 << 3);
const SSI0: usize = 0x4000_8000;
const CR0: usize = 0x000;
const CR1: usize = 0x004;
const DR: usize = 0x008;
const SR: usize = 0x00C;
const CPSR: usize = 0x010;
const SR_RNE: u32 = 1 << 2;
const SR_TNF: u32 = 1 << 1;
/// 8-bit frames, SPI mode 0 (SPO = SPH = 0), serial clock rate 0.
const CR0_8BIT_MODE0: u32 = 0x7;
const CR1_SSE: u32 = 1 << 1;
const GPIOD: usize = 0x4000_7000;
/// GPIODATA with address mask bit 0: reads and writes pin D0 only.
const GPIOD_DATA_D0: usize = GPIOD + (1 << 2);
const GPIODIR: usize = GPIOD + 0x400;
const GPIODEN: usize = GPIOD + 0x51C;

/// Command tokens: 40h | command index.
const CMD24: u8 = 0x40 | 24;
const CMD25: u8 = 0x40 | 25;
const CMD58: u8 = 0x40 | 58;
/// Data tokens of single- and multiple-block writes.
const DATA_START: u8 = 0xFE;
const WRITE_MULTIPLE_START: u8 = 0xFC;

/// Where the card is in the exchange of the command last sent (for the quirks).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Exchange {
    Idle,
    /// A command's six bytes are going out; the first byte.
    Command {
        token: u8,
        sent: u8,
    },
    /// Waiting for the R1 of command `token`.
    Response(u8),
    /// R1 of a block write came: its data token is next (`multiple`: CMD25, tokens until the
    /// stop token).
    WriteData {
        multiple: bool,
    },
    /// A block's data and CRC going out: bytes left.
    Data {
        multiple: bool,
        left: u16,
    },
}

/// A block and its CRC.
const BLOCK_AND_CRC: u16 = 512 + 2;
/// Stop token of a multiple-block write.
const STOP_TRAN: u8 = 0xFD;

/// SSI0 with the card select.
#[derive(Debug)]
pub struct SdSpi {
    exchange: Exchange,
}

impl SdSpi {
    /// Clocks SSI0 and GPIO A/D, makes D0 an output (card deselected) and SSI0 an 8-bit SPI
    /// master.
    pub fn new() -> SdSpi {
        write(SYSCTL_RCGC1, read(SYSCTL_RCGC1) | RCGC1_SSI0);
        write(SYSCTL_RCGC2, read(SYSCTL_RCGC2) | RCGC2_GPIOA_D);
        write(GPIODIR, read(GPIODIR) | 1);
        write(GPIODEN, read(GPIODEN) | 1);
        write(GPIOD_DATA_D0, 1);
        write(SSI0 + CR1, 0);
        write(SSI0 + CPSR, 2);
        write(SSI0 + CR0, CR0_8BIT_MODE0);
        write(SSI0 + CR1, CR1_SSE);
        SdSpi { exchange: Exchange::Idle }
    }

    fn select(&mut self, on: bool) {
        write(GPIOD_DATA_D0, u32::from(!on));
    }

    /// One byte out, one in, with the quirks applied.
    fn byte(&mut self, out: u8) -> u8 {
        if let Exchange::WriteData { multiple } = self.exchange
            && matches!(out, DATA_START | WRITE_MULTIPLE_START)
        {
            self.raw(0xFF);
            self.exchange = Exchange::Data { multiple, left: BLOCK_AND_CRC + 1 };
        }
        let got = self.raw(out);
        self.exchange = match self.exchange {
            Exchange::Data { multiple, left } if left > 1 => Exchange::Data { multiple, left: left - 1 },
            Exchange::Data { multiple: true, .. } => Exchange::WriteData { multiple: true },
            Exchange::Data { multiple: false, .. } => Exchange::Idle,
            Exchange::WriteData { .. } if out == STOP_TRAN => Exchange::Idle,
            Exchange::Idle | Exchange::WriteData { .. } if out & 0xC0 == 0x40 => Exchange::Command { token: out, sent: 1 },
            Exchange::Command { token, sent } if sent < 5 => Exchange::Command { token, sent: sent + 1 },
            Exchange::Command { token, .. } => Exchange::Response(token),
            Exchange::Response(token) if got & 0x80 == 0 => {
                return match token {
                    CMD58 => {
                        self.exchange = Exchange::Idle;
                        got & !0x01
                    }
                    CMD24 | CMD25 => {
                        self.exchange = Exchange::WriteData { multiple: token == CMD25 };
                        got
                    }
                    _ => {
                        self.exchange = Exchange::Idle;
                        got
                    }
                };
            }
            other => other,
        };
        got
    }

    fn raw(&mut self, out: u8) -> u8 {
        while read(SSI0 + SR) & SR_TNF == 0 {}
        write(SSI0 + DR, u32::from(out));
        while read(SSI0 + SR) & SR_RNE == 0 {}
        read(SSI0 + DR) as u8
    }
}

impl Default for SdSpi {
    fn default() -> Self {
        SdSpi::new()
    }
}

impl ErrorType for SdSpi {
    type Error = Infallible;
}

impl SpiDevice<u8> for SdSpi {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), Infallible> {
        self.select(true);
        for op in operations {
            match op {
                Operation::Read(buf) => buf.iter_mut().for_each(|b| *b = self.byte(0xFF)),
                Operation::Write(bytes) => bytes.iter().for_each(|&b| {
                    self.byte(b);
                }),
                Operation::Transfer(read, write) => {
                    for i in 0..read.len().max(write.len()) {
                        let got = self.byte(write.get(i).copied().unwrap_or(0xFF));
                        if let Some(r) = read.get_mut(i) {
                            *r = got;
                        }
                    }
                }
                Operation::TransferInPlace(buf) => buf.iter_mut().for_each(|b| *b = self.byte(*b)),
                Operation::DelayNs(ns) => cortex_m::asm::delay(*ns / 20 + 1),
            }
        }
        self.select(false);
        Ok(())
    }
}

/// Busy-wait delays for the card driver's retries (QEMU's time does not matter here).
#[derive(Debug, Default, Clone, Copy)]
pub struct SpinDelay;

impl embedded_hal::delay::DelayNs for SpinDelay {
    fn delay_ns(&mut self, ns: u32) {
        cortex_m::asm::delay(ns / 20 + 1);
    }
}
