//! The STM32F091RC's last 16 KiB of flash as CANopenIA's configuration memory: the two 8 KiB
//! slots of `canopenia::config::slots` (four 2 KiB erase pages each), erased by pages,
//! programmed by half-words, and read in place (`ConfigMemory::mapped`).
//!
//! The image links into the first 240 KiB (`firmware/boards/stm32f091/build.rs`), so code never
//! shares a page with a configuration. While a page is erased (about 20-40 ms) or a half-word
//! programmed, the CPU stalls on its next flash fetch: the first segment of a download takes the
//! erase of one slot, and CAN frames arriving meanwhile wait in bxCAN's two 3-frame FIFOs.

use canopenia::config::slots::ConfigMemory;
use embedded_storage::{ReadStorage, Storage};
use stm32f0xx_hal::pac::FLASH;

/// Where the configuration memory starts, and its length.
pub const BASE: u32 = 0x0803_C000;
pub const LEN: usize = 16 * 1024;
const PAGE: u32 = 2048;
const KEY1: u32 = 0x4567_0123;
const KEY2: u32 = 0xCDEF_89AB;
/// Status polls before a flash operation counts as hung (over 50 ms at 48 MHz).
const POLLS: u32 = 1_000_000;

/// Why a flash operation failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlashError {
    /// Outside the configuration memory, or not whole half-words.
    Range,
    /// A half-word was not erased (PGERR) or the page is write-protected (WRPRTERR), or what
    /// was programmed does not read back.
    Program,
    /// The controller stayed busy.
    Timeout,
}

/// The configuration memory, owning the flash controller.
pub struct ConfigFlash {
    flash: FLASH,
}

impl ConfigFlash {
    /// The clock set-up has set the flash wait states already; the controller stays locked
    /// between operations.
    pub fn new(flash: FLASH) -> Self {
        ConfigFlash { flash }
    }

    fn unlock(&mut self) {
        if self.flash.cr.read().lock().bit_is_set() {
            self.flash.keyr.write(|w| w.fkeyr().bits(KEY1));
            self.flash.keyr.write(|w| w.fkeyr().bits(KEY2));
        }
    }

    /// Waits for the running operation; its errors are cleared and reported.
    fn finish(&mut self) -> Result<(), FlashError> {
        let mut polls = 0;
        while self.flash.sr.read().bsy().bit_is_set() {
            polls += 1;
            if polls > POLLS {
                return Err(FlashError::Timeout);
            }
        }
        let sr = self.flash.sr.read();
        let failed = sr.pgerr().bit_is_set() || sr.wrprt().bit_is_set();
        // The flags clear by writing 1.
        self.flash.sr.write(|w| w.eop().set_bit().pgerr().set_bit().wrprt().set_bit());
        if failed { Err(FlashError::Program) } else { Ok(()) }
    }

    fn erase_page(&mut self, address: u32) -> Result<(), FlashError> {
        self.flash.cr.modify(|_, w| w.per().set_bit());
        self.flash.ar.write(|w| w.far().bits(address));
        self.flash.cr.modify(|_, w| w.strt().set_bit());
        let done = self.finish();
        self.flash.cr.modify(|_, w| w.per().clear_bit());
        done
    }

    fn program(&mut self, address: u32, halfword: u16) -> Result<(), FlashError> {
        self.flash.cr.modify(|_, w| w.pg().set_bit());
        // SAFETY: `address` is a half-word-aligned address inside the configuration memory
        // (checked by the caller), flash the image never executes from; with PG set the
        // controller turns this store into one half-word program operation.
        #[allow(unsafe_code)]
        unsafe {
            core::ptr::write_volatile(address as *mut u16, halfword);
        }
        let done = self.finish();
        self.flash.cr.modify(|_, w| w.pg().clear_bit());
        done
    }

    fn lock(&mut self) {
        self.flash.cr.modify(|_, w| w.lock().set_bit());
    }

    /// `offset..offset + len` inside the memory, as an absolute address.
    fn address(offset: u32, len: usize) -> Result<u32, FlashError> {
        let end = (offset as usize).checked_add(len).ok_or(FlashError::Range)?;
        if end > LEN { Err(FlashError::Range) } else { Ok(BASE + offset) }
    }
}

impl ReadStorage for ConfigFlash {
    type Error = FlashError;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), FlashError> {
        let start = offset as usize;
        let src = self.mapped().get(start..start + bytes.len()).ok_or(FlashError::Range)?;
        bytes.copy_from_slice(src);
        Ok(())
    }

    fn capacity(&self) -> usize {
        LEN
    }
}

impl Storage for ConfigFlash {
    /// Programs whole half-words into erased flash (what the configuration slots write:
    /// aligned 8- and 16-byte blocks), each checked by reading it back.
    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), FlashError> {
        let start = Self::address(offset, bytes.len())?;
        if !start.is_multiple_of(2) || !bytes.len().is_multiple_of(2) {
            return Err(FlashError::Range);
        }
        self.unlock();
        let mut result = Ok(());
        for (address, pair) in (start..).step_by(2).zip(bytes.chunks_exact(2)) {
            let halfword = u16::from_le_bytes([pair.first().copied().unwrap_or(0xFF), pair.get(1).copied().unwrap_or(0xFF)]);
            result = self.program(address, halfword);
            if result.is_err() {
                break;
            }
        }
        self.lock();
        result?;
        let written = self.mapped().get((offset as usize)..(offset as usize + bytes.len())).ok_or(FlashError::Range)?;
        if written == bytes { Ok(()) } else { Err(FlashError::Program) }
    }
}

impl ConfigMemory for ConfigFlash {
    fn mapped(&self) -> &[u8] {
        // SAFETY: the configuration memory is LEN bytes of memory-mapped flash at BASE, outside
        // the image (the linker script ends FLASH before it) and never written but through this
        // driver, which needs `&mut self` and so cannot run while this borrow lives; flash is
        // readable at any time (a read during an operation stalls, it does not fault).
        #[allow(unsafe_code)]
        unsafe {
            core::slice::from_raw_parts(BASE as *const u8, LEN)
        }
    }

    fn erase(&mut self, offset: u32, len: u32) -> Result<(), FlashError> {
        let start = Self::address(offset, len as usize)?;
        if !start.is_multiple_of(PAGE) || !len.is_multiple_of(PAGE) {
            return Err(FlashError::Range);
        }
        self.unlock();
        let mut result = Ok(());
        for page in (start..start + len).step_by(PAGE as usize) {
            result = self.erase_page(page);
            if result.is_err() {
                break;
            }
        }
        self.lock();
        result
    }
}
