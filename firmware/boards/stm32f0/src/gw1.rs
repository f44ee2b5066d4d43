//! The board under CO401GW1 on the STM32F042C6 (LQFP48): ID0..ID6, BD0..BD2 and RSBD0..RSBD2
//! through two 74HC165 (read once at reset, [`crate::board::ConfigChain`]), CFG0..CFG2 read at
//! reset and then driving the run LED, the error LED and the watchdog, IN0..IN7, EMY0#/EMY1#
//! and OUT0..OUT7 on plain GPIOs. Pin map: `PINS-co401gw1.md` and the crate documentation.
//!
//! The plain pins are driven through the port registers, a whole port at a time (one IDR
//! read for the inputs, one BSRR write for the outputs), not pin by pin through the HAL's
//! typed pins: 21 typed pins cost about 1 KiB of flash for their mode changes and accesses.
//! The HAL keeps the pins of its peripherals (USART2, bxCAN, I2C1) and the chain's three.

mod run;

pub use run::{Chip, run};

use crate::board::ConfigWord;
use co401gw1::Board;
use stm32f0xx_hal::pac::{self, gpioa, gpiof};

/// IN0..IN7: PA0, PA1, PA4..PA9 (IDR bits 0, 1, 4..9).
const IN_LOW: u32 = 0b11;
const IN_HIGH: u32 = 0b11_1111 << 4;
/// EMY0#: PA10, EMY1#: PA15.
const EMY0: u32 = 10;
const EMY1: u32 = 15;
/// CFG0/R, CFG1/E, CFG2/WD: PB0, PB1, PB2.
const CFG: u32 = 0b111;
/// OUT0..OUT7: PB8..PB15.
const OUT_SHIFT: u32 = 8;

/// The plain GPIOs of ports A and B.
pub struct Ports {
    a: &'static gpioa::RegisterBlock,
    b: &'static gpiof::RegisterBlock,
}

impl Ports {
    /// The port registers. Call once, after `split()` has enabled both ports' clocks.
    #[allow(unsafe_code)]
    pub fn take() -> Self {
        // SAFETY: the register blocks are memory-mapped for the whole run and only this
        // single-threaded program (no interrupt touches GPIO) accesses them. The HAL's typed
        // pins of these two ports change only their own pins' bits, by read-modify-write
        // before `configure`; `Ports` touches only the plain pins' bits (modify, IDR reads,
        // BSRR writes), whose HAL pin objects are never used.
        unsafe { Ports { a: &*pac::GPIOA::ptr(), b: &*pac::GPIOB::ptr() } }
    }

    /// Pull-ups on IN0..IN7 and EMY0#/EMY1# (inputs since reset: an open input reads
    /// inactive); CFG0..CFG2 stay inputs without pull until [`Ports::cfg_levels`] has read
    /// them; OUT0..OUT7 become outputs, inactive (high).
    pub fn configure(&self) {
        self.a.pupdr.modify(|_, w| {
            w.pupdr0().pull_up().pupdr1().pull_up().pupdr4().pull_up().pupdr5().pull_up().pupdr6().pull_up();
            w.pupdr7().pull_up().pupdr8().pull_up().pupdr9().pull_up().pupdr10().pull_up().pupdr15().pull_up()
        });
        self.set_outputs(0xFF);
        self.b.moder.modify(|_, w| {
            w.moder8().output().moder9().output().moder10().output().moder11().output();
            w.moder12().output().moder13().output().moder14().output().moder15().output()
        });
    }

    /// CFG0..CFG2 as the board's straps set them (bit n = CFGn, 1 = high).
    pub fn cfg_levels(&self) -> u16 {
        (self.b.idr.read().bits() & CFG) as u16
    }

    /// CFG0/R, CFG1/E and CFG2/WD become push-pull outputs, high (LEDs dark).
    pub fn cfg_to_outputs(&self) {
        self.bsrr_b(CFG);
        self.b.moder.modify(|_, w| w.moder0().output().moder1().output().moder2().output());
    }

    fn bsrr_b(&self, bits: u32) {
        // SAFETY: BSRR is write-only; every bit pattern sets or resets pins, nothing else.
        #[allow(unsafe_code)]
        self.b.bsrr.write(|w| unsafe { w.bits(bits) });
    }

    fn set_outputs(&self, levels: u8) {
        let high = u32::from(levels) << OUT_SHIFT;
        let low = u32::from(!levels) << OUT_SHIFT;
        self.bsrr_b(high | low << 16);
    }
}

/// The STM32F042C6 board under CO401GW1.
pub struct Gw1Board {
    /// ID0..ID6 (bits 8..14), BD0..BD2, RSBD0..RSBD2 as shifted in at reset.
    chain: ConfigWord,
    /// CFG0..CFG2 as read at reset.
    cfg: u16,
    ports: Ports,
}

impl Gw1Board {
    /// The board after reset: `chain` and `cfg` read, CFG0..CFG2 and OUT0..OUT7 outputs.
    /// Starts with both LEDs dark.
    pub fn new(chain: ConfigWord, cfg: u16, ports: Ports) -> Self {
        let mut board = Gw1Board { chain, cfg, ports };
        board.set_indicators(false, false, true);
        board
    }
}

impl Board for Gw1Board {
    fn node_id_pins(&mut self) -> u16 {
        self.chain.node_id()
    }

    fn config_pins(&mut self) -> u16 {
        self.cfg
    }

    fn input_pins(&mut self) -> u8 {
        let idr = self.ports.a.idr.read().bits();
        (idr & IN_LOW | (idr & IN_HIGH) >> 2) as u8
    }

    fn emergency_pins(&mut self) -> u8 {
        let idr = self.ports.a.idr.read().bits();
        (idr >> EMY0 & 1 | (idr >> EMY1 & 1) << 1) as u8
    }

    fn set_output_pins(&mut self, levels: u8) {
        self.ports.set_outputs(levels);
    }

    /// Active low: a lit LED is a low pin; the watchdog pin is driven as given.
    fn set_indicators(&mut self, run_lit: bool, error_lit: bool, watchdog: bool) {
        let high = u32::from(!run_lit) | u32::from(!error_lit) << 1 | u32::from(watchdog) << 2;
        self.ports.bsrr_b(high | (!high & CFG) << 16);
    }
}
