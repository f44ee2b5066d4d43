//! A polled I2C1 master on the PAC, implementing embedded-hal 1.0's `I2c` for eeprom24x.
//!
//! Why not the HAL's: stm32f0xx-hal 0.18 computes SCLL as `max(.., 255)`, so its bus runs at
//! about 8 kHz (100 kHz asked) or 16 kHz (400 kHz asked), and its waits never time out. Here
//! TIMINGR is the reference manual's 400 kHz setting for an 8 MHz I2C clock (I2C1SW = HSI, the
//! reset value, independent of the 48 MHz system clock), every wait is bounded, and a bus
//! error or time-out resets the peripheral (PE off/on) so that the next transfer starts clean.
//! A bank that does not answer reads as an access error, which the banks report and survive.
//!
//! Transfers are limited to 255 bytes per direction (one NBYTES load; the banks never move
//! more than a 132-byte block slot, eeprom24x at most a 66-byte page write).

use crate::clock::MsDelay;
use eeprom24x::{Eeprom24x, SlaveAddr, addr_size::TwoBytes, page_size::B64, unique_serial::No};
use embedded_hal::i2c::{ErrorKind, ErrorType, NoAcknowledgeSource, Operation, SevenBitAddress};
use stm32f0xx_hal::pac::I2C1;

/// RM0091 table "timing settings for fI2CCLK = 8 MHz", Fast-mode 400 kHz: PRESC 0, SCLL 0x09,
/// SCLH 0x03, SDADEL 0x1, SCLDEL 0x3.
const PRESC: u8 = 0;
const SCLL: u8 = 0x09;
const SCLH: u8 = 0x03;
const SDADEL: u8 = 0x1;
const SCLDEL: u8 = 0x3;

/// Status polls before a wait gives up: about 10 cycles each at 48 MHz, so some 20 ms, far
/// above one byte (25 us at 400 kHz) even with clock stretching.
const POLLS: u32 = 100_000;

/// Why a transfer failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Error {
    /// The device did not acknowledge (absent, or busy with its write cycle).
    Nack,
    /// Bus error or arbitration lost.
    Bus,
    /// A flag did not come in time (bus held low, no pull-ups).
    Timeout,
    /// More than 255 bytes, or an operation sequence this master does not issue.
    Unsupported,
}

impl embedded_hal::i2c::Error for Error {
    fn kind(&self) -> ErrorKind {
        match self {
            Error::Nack => ErrorKind::NoAcknowledge(NoAcknowledgeSource::Unknown),
            Error::Bus => ErrorKind::Bus,
            Error::Timeout | Error::Unsupported => ErrorKind::Other,
        }
    }
}

/// A parameter EEPROM, the only device on the bus: a 24C128 (16 KiB, 64-byte pages, two
/// address bytes) at 0x50 (A2..A0 = 000). CO401GW1's and CANopenIA's 1010h/1011h store.
pub type ParamEeprom = eeprom24x::Storage<I2cBus, B64, TwoBytes, No, MsDelay>;

/// The 24C128's size.
pub const PARAM_EEPROM_BYTES: usize = 16 * 1024;

/// The parameter EEPROM on I2C1, taken as [`I2cBus::new`] takes it.
pub fn param_eeprom(regs: I2C1) -> ParamEeprom {
    eeprom24x::Storage::new(Eeprom24x::new_24x128(I2cBus::new(regs), SlaveAddr::Default), MsDelay)
}

/// I2C1 as a bus master.
pub struct I2cBus {
    regs: I2C1,
}

impl I2cBus {
    /// Takes I2C1 with its clock enabled and its pins in their alternate function (what
    /// `stm32f0xx_hal::i2c::I2c::i2c1(..).release()` leaves) and sets the 400 kHz timing.
    pub fn new(regs: I2C1) -> Self {
        regs.cr1.modify(|_, w| w.pe().clear_bit());
        regs.timingr.write(|w| w.presc().bits(PRESC).scll().bits(SCLL).sclh().bits(SCLH).sdadel().bits(SDADEL).scldel().bits(SCLDEL));
        regs.cr1.modify(|_, w| w.pe().set_bit());
        I2cBus { regs }
    }

    /// Waits for `done`, failing on a NACK, a bus error or the time-out.
    fn wait(&self, done: impl Fn(&stm32f0xx_hal::pac::i2c1::isr::R) -> bool) -> Result<(), Error> {
        for _ in 0..POLLS {
            let isr = self.regs.isr.read();
            if isr.nackf().bit_is_set() {
                return Err(Error::Nack);
            }
            if isr.berr().bit_is_set() || isr.arlo().bit_is_set() {
                return Err(Error::Bus);
            }
            if done(&isr) {
                return Ok(());
            }
        }
        Err(Error::Timeout)
    }

    /// Leaves the peripheral ready for the next transfer after `e`: after a NACK the hardware
    /// sends STOP by itself; anything else, or a STOP that does not come, resets it.
    fn recover(&mut self, e: Error) -> Error {
        let stopped = e == Error::Nack && self.wait(|isr| isr.stopf().bit_is_set()).is_ok();
        if !stopped {
            // PE = 0 releases the lines and clears the state machine (RM0091 "software reset";
            // the read back gives it the three APB cycles it needs).
            self.regs.cr1.modify(|_, w| w.pe().clear_bit());
            while self.regs.cr1.read().pe().bit_is_set() {}
            self.regs.cr1.modify(|_, w| w.pe().set_bit());
        }
        self.regs.icr.write(|w| w.nackcf().set_bit().stopcf().set_bit().berrcf().set_bit().arlocf().set_bit().ovrcf().set_bit());
        e
    }

    /// START (or repeated START) for `len` bytes in one direction; `stop`: STOP after them.
    fn start(&mut self, addr: u8, read: bool, len: usize, stop: bool) -> Result<(), Error> {
        let n = u8::try_from(len).map_err(|_| Error::Unsupported)?;
        self.regs.cr2.write(|w| w.sadd().bits(u16::from(addr) << 1).rd_wrn().bit(read).nbytes().bits(n).autoend().bit(stop).start().set_bit());
        Ok(())
    }

    fn send(&mut self, addr: u8, bytes: &[u8], stop: bool) -> Result<(), Error> {
        self.start(addr, false, bytes.len(), stop)?;
        for &b in bytes {
            self.wait(|isr| isr.txis().bit_is_set())?;
            self.regs.txdr.write(|w| w.txdata().bits(b));
        }
        if stop { self.finish() } else { self.wait(|isr| isr.tc().bit_is_set()) }
    }

    fn receive(&mut self, addr: u8, buf: &mut [u8]) -> Result<(), Error> {
        self.start(addr, true, buf.len(), true)?;
        for b in buf.iter_mut() {
            self.wait(|isr| isr.rxne().bit_is_set())?;
            *b = self.regs.rxdr.read().rxdata().bits();
        }
        self.finish()
    }

    fn finish(&mut self) -> Result<(), Error> {
        self.wait(|isr| isr.stopf().bit_is_set())?;
        self.regs.icr.write(|w| w.stopcf().set_bit());
        Ok(())
    }

    fn checked(&mut self, result: Result<(), Error>) -> Result<(), Error> {
        result.map_err(|e| self.recover(e))
    }
}

impl ErrorType for I2cBus {
    type Error = Error;
}

impl embedded_hal::i2c::I2c<SevenBitAddress> for I2cBus {
    fn read(&mut self, address: u8, read: &mut [u8]) -> Result<(), Error> {
        let r = self.receive(address, read);
        self.checked(r)
    }

    fn write(&mut self, address: u8, write: &[u8]) -> Result<(), Error> {
        let r = self.send(address, write, true);
        self.checked(r)
    }

    fn write_read(&mut self, address: u8, write: &[u8], read: &mut [u8]) -> Result<(), Error> {
        let r = self.send(address, write, false).and_then(|()| self.receive(address, read));
        self.checked(r)
    }

    /// The three shapes above; longer sequences are not needed by eeprom24x.
    fn transaction(&mut self, address: u8, operations: &mut [Operation<'_>]) -> Result<(), Error> {
        match operations {
            [Operation::Write(w)] => self.write(address, w),
            [Operation::Read(r)] => self.read(address, r),
            [Operation::Write(w), Operation::Read(r)] => self.write_read(address, w, r),
            _ => Err(Error::Unsupported),
        }
    }
}
