//! The CR3101 CANmem data logger on an STM32F072CB (LQFP48, 128 KiB flash, 16 KiB RAM): the
//! image of `firmware/boards/stm32f072` is [`run`]. Pin map: `firmware/boards/stm32f072/PINS.md`.
//!
//! - CAN on bxCAN (PA12 TX, PA11 RX, AF4) at the bit rate of the stored 20F2h/20F3h pair, read
//!   when the device starts (all eight codes exact at 48 MHz, 87.5 % sample point: `can`).
//! - The memory card in an SD socket on SPI1 ([`sd`]: PA5 SCK, PA6 MISO, PA7 MOSI, PA4 card
//!   select), its card-detect switch on PB12 and write-protect switch on PB13 (to ground,
//!   pulled up). A card is taken once the slot has held it for [`CARD_SETTLE_MS`]; one that
//!   does not initialise is not tried again until it leaves the slot, and lights CARD ERROR.
//! - The clock at power-on from the RTC on the 32.768 kHz crystal (PC14/PC15) under the
//!   backup battery on VBAT, kept in step with 2010h ([`rtc`]).
//! - BATTERY GOOD (1002h bit 2; the LowBatt emergency while it is low) on PB14, high = good.
//! - The five status LEDs of the manual (CARD ERROR, CARD ACCESS, ON, ERROR, CAN) on PB11,
//!   PB10, PB2, PB1, PB0, active low, driven by the device (`Board::set_leds`).
//! - The node's parameters (20F0h..20F5h, the communication parameters, 1010h) in a 24C128 at
//!   0x50 on I2C1 (PB6 SCL, PB7 SDA), as CO401GW1's and CANopenIA's (`i2c::ParamEeprom`).
//! - No serial host (the CR3101 has none): USART2 is not used.
//! - Factory node-ID 20h (the manual's) until 20F0h/20F1h are written.

pub mod rtc;
pub mod sd;

use crate::i2c::{self, PARAM_EEPROM_BYTES, ParamEeprom};
use crate::serve::{NoHost, OwnIndicators, serve_started};
use crate::{clock, halt};
use coforge_stack::device::Device as _;
use coforge_stack::od::NodeDictionary;
use coforge_stack::store::BlockStore;
use cr3101::app::Typed;
use cr3101::card::record::TimeStamp;
use cr3101::logger::Logger;
use cr3101::{Board, CardSense, Cr3101, StatusLeds};
use embedded_hal_02::digital::v2::{InputPin, OutputPin};
use rtc::Rtc;
use sd::{CardSelect, SdBus, SdCard};
use stm32f0xx_hal::can::CanInstance;
use stm32f0xx_hal::can::bxcan::{self, filter::Mask32};
use stm32f0xx_hal::gpio::gpiob::{PB0, PB1, PB2, PB10, PB11, PB12, PB13, PB14};
use stm32f0xx_hal::gpio::{Input, Output, PullDown, PullUp, PushPull};
use stm32f0xx_hal::i2c::I2c;
use stm32f0xx_hal::pac;
use stm32f0xx_hal::prelude::*;

/// The manual's factory node-ID, what 20F0h/20F1h hold until they are written.
pub const NODE_ID: u8 = 0x20;
/// How long the card-detect switch must report a card before it is used: contact bounce, and
/// the card's power-up (at least 1 ms, and the supply ramp) after the insertion.
pub const CARD_SETTLE_MS: u32 = 250;
/// How often the RTC is compared with the device's clock.
const RTC_KEEP_MS: u32 = 1000;

/// The device of this image.
pub type Device = Cr3101<Stm32Cr3101Board, BlockStore<ParamEeprom>>;

// The ring's first two slots of the parameter block fit the EEPROM (the store takes as many
// slots as fit, up to 16).
const _: () = assert!(BlockStore::<ParamEeprom>::capacity_for(<cr3101::Od<Typed<Logger<SdCard>>> as NodeDictionary>::PERSISTENT_SIZE) <= PARAM_EEPROM_BYTES);

/// The five status LEDs, active low (push-pull; high = dark).
pub struct StatusPins {
    /// CARD ERROR, red.
    pub card_error: PB11<Output<PushPull>>,
    /// CARD ACCESS, green.
    pub card_access: PB10<Output<PushPull>>,
    /// ON, green.
    pub on: PB2<Output<PushPull>>,
    /// ERROR, red.
    pub error: PB1<Output<PushPull>>,
    /// CAN, green.
    pub can: PB0<Output<PushPull>>,
}

/// The socket's switches, closing to ground: card detect (closed = a card is in) and write
/// protect (closed = the card's tab is in its writable position; open, i.e. high, = locked).
pub struct SlotPins {
    pub detect: PB12<Input<PullUp>>,
    pub write_protect: PB13<Input<PullUp>>,
}

/// The CR3101 board on the STM32F072CB.
pub struct Stm32Cr3101Board {
    /// The card's driver while the device does not hold it.
    card: Option<SdCard>,
    /// The card in the slot did not initialise: not tried again until it leaves.
    dead: bool,
    slot: SlotPins,
    /// When (low 32 bits of the milliseconds) the detect switch closed, until the card counts
    /// as in the slot (`None` then, and while the slot is empty: `settled` tells which).
    present_since: Option<u32>,
    settled: bool,
    battery_good: PB14<Input<PullDown>>,
    pub rtc: Rtc,
    pins: StatusPins,
    leds: StatusLeds,
}

/// Drives an active-low LED.
fn light(pin: &mut impl OutputPin, lit: bool) {
    let _ = if lit { pin.set_low() } else { pin.set_high() };
}

impl Stm32Cr3101Board {
    /// The board with every LED dark but ON.
    pub fn new(card: SdCard, slot: SlotPins, battery_good: PB14<Input<PullDown>>, rtc: Rtc, pins: StatusPins) -> Self {
        let leds = StatusLeds { on: true, ..StatusLeds::default() };
        let mut board = Stm32Cr3101Board { card: Some(card), dead: false, slot, present_since: None, settled: false, battery_good, rtc, pins, leds };
        board.show();
        board
    }

    /// The device's LEDs, CARD ERROR also for a card that did not initialise (which the
    /// device never sees).
    fn show(&mut self) {
        let (leds, pins) = (self.leds, &mut self.pins);
        light(&mut pins.card_error, leds.card_error || self.dead);
        light(&mut pins.card_access, leds.card_access);
        light(&mut pins.on, leds.on);
        light(&mut pins.error, leds.error);
        light(&mut pins.can, leds.can);
    }
}

impl Board for Stm32Cr3101Board {
    type Card = SdCard;

    /// A card once the detect switch has been closed for [`CARD_SETTLE_MS`].
    fn sense_card(&mut self) -> Option<CardSense> {
        if self.slot.detect.is_high().unwrap_or(true) {
            (self.present_since, self.settled) = (None, false);
            if self.dead {
                self.dead = false;
                self.show();
            }
            return None;
        }
        if !self.settled {
            let now = clock::millis() as u32;
            let since = *self.present_since.get_or_insert(now);
            if now.wrapping_sub(since) < CARD_SETTLE_MS {
                return None;
            }
            (self.present_since, self.settled) = (None, true);
        }
        Some(CardSense { write_protected: self.slot.write_protect.is_high().unwrap_or(true) })
    }

    /// Initialises the card at 375 kHz (after its 74 power-up clocks), then runs the bus at
    /// 12 MHz. A card that does not answer stays here, and is not tried again while it is in
    /// the slot.
    fn take_card(&mut self) -> Option<SdCard> {
        if self.dead {
            return None;
        }
        let card = self.card.take()?;
        card.mark_card_uninit();
        let woke = card.spi(|device| {
            let bus = device.bus_mut();
            bus.set_rate(sd::INIT_HZ);
            bus.idle_clocks()
        });
        if woke.is_ok() && card.num_bytes().is_ok() {
            card.spi(|device| device.bus_mut().set_rate(sd::DATA_HZ));
            return Some(card);
        }
        self.card = Some(card);
        self.dead = true;
        self.show();
        None
    }

    fn return_card(&mut self, card: SdCard) {
        self.card = Some(card);
    }

    fn battery_ok(&mut self) -> bool {
        self.battery_good.is_high().unwrap_or(false)
    }

    fn clock_at_power_on(&mut self) -> TimeStamp {
        self.rtc.at_power_on()
    }

    fn set_leds(&mut self, leds: StatusLeds) {
        self.leds = leds;
        self.show();
    }
}

/// Sets up the chip, builds the device, starts it, sets the CAN bit rate it chose and serves
/// it for ever. Called once, from the image's entry point (a second call finds the
/// peripherals and the device taken and halts).
///
/// `#[inline]`: compiled with the image rather than optimised in this library first, which
/// left it 92 bytes larger.
#[inline]
pub fn run() -> ! {
    let (Some(core), Some(mut p)) = (cortex_m::Peripherals::take(), pac::Peripherals::take()) else { halt() };
    rtc::start_backup_domain(&p.RCC, &p.PWR);
    // SCK (PA5) and MOSI (PA7) as high-speed outputs for 12 MHz, MISO (PA6) pulled up (the
    // card's DO floats while it is deselected or absent): the HAL's alternate-function set-up
    // leaves OSPEEDR and PUPDR at their reset values (low speed, about 2 MHz; no pull). Port
    // A's clock is needed for the writes; the HAL enables it again when it splits the port.
    p.RCC.ahbenr.modify(|_, w| w.iopaen().set_bit());
    p.GPIOA.ospeedr.modify(|_, w| w.ospeedr5().high_speed().ospeedr7().high_speed());
    p.GPIOA.pupdr.modify(|_, w| w.pupdr6().pull_up());
    let mut rcc = clock::start_core(p.RCC, &mut p.FLASH, core.SYST);

    let gpioa = p.GPIOA.split(&mut rcc);
    let gpiob = p.GPIOB.split(&mut rcc);
    let (can_pins, i2c_pins, spi_pins, mut select, slot, battery_good, pins) = cortex_m::interrupt::free(|cs| {
        (
            (gpioa.pa12.into_alternate_af4(cs), gpioa.pa11.into_alternate_af4(cs)),
            (gpiob.pb6.into_alternate_af1(cs).set_open_drain(cs), gpiob.pb7.into_alternate_af1(cs).set_open_drain(cs)),
            (gpioa.pa5.into_alternate_af0(cs), gpioa.pa6.into_alternate_af0(cs), gpioa.pa7.into_alternate_af0(cs)),
            gpioa.pa4.into_push_pull_output(cs),
            SlotPins { detect: gpiob.pb12.into_pull_up_input(cs), write_protect: gpiob.pb13.into_pull_up_input(cs) },
            gpiob.pb14.into_pull_down_input(cs),
            StatusPins {
                card_error: gpiob.pb11.into_push_pull_output(cs),
                card_access: gpiob.pb10.into_push_pull_output(cs),
                on: gpiob.pb2.into_push_pull_output(cs),
                error: gpiob.pb1.into_push_pull_output(cs),
                can: gpiob.pb0.into_push_pull_output(cs),
            },
        )
    });
    let _ = select.set_high();

    // The HAL enables and resets I2C1; its timing is replaced (see `i2c`).
    let (i2c1, _pins) = I2c::i2c1(p.I2C1, i2c_pins, 400.khz(), &mut rcc).release();
    let can = CanInstance::new(p.CAN, can_pins.0, can_pins.1, &mut rcc);
    // The SD bus keeps the HAL's clock tree handle (for its rate changes): last.
    let card = sd::card(SdBus::new(p.SPI1, spi_pins, rcc), CardSelect(select));
    let board = Stm32Cr3101Board::new(card, slot, battery_good, Rtc::new(p.RTC), pins);
    let Some(device) = mount(board, BlockStore::new(i2c::param_eeprom(i2c1), 0)) else { halt() };

    // The start loads 20F2h/20F3h: the controller is set up after it, at that bit rate.
    device.start(0);
    let mut bxcan = bxcan::Can::builder(can).set_bit_timing(crate::can::bit_timing(u32::from(device.bitrate_kbit()))).leave_disabled();
    bxcan.modify_filters().enable_bank(0, Mask32::accept_all());
    // `serve_started` enables the controller at once (the device's CAN side is on after its
    // start).

    let mut next_keep_ms = 0_u32;
    serve_started(device, NoHost, bxcan, OwnIndicators, move |device: &mut Device, now_us| {
        // The node's events: CR3101 reads its RPDOs' identifiers again after a reset; the rest
        // are for runtimes that restart controllers (bxCAN's ABOM does here).
        while device.take_event().is_some() {}
        let ms = (now_us / 1000) as u32;
        if ms.wrapping_sub(next_keep_ms) as i32 >= 0 {
            next_keep_ms = ms.wrapping_add(RTC_KEEP_MS);
            let now = device.logger().clock().now(now_us);
            device.board_mut().rtc.keep(&now, ms);
        }
    })
}

/// The device in a static (`.bss`), built in a frame of its own so that its construction's
/// temporaries leave the stack before the loop starts.
#[inline(never)]
fn mount(board: Stm32Cr3101Board, store: BlockStore<ParamEeprom>) -> Option<&'static mut Device> {
    cortex_m::singleton!(: Device = Cr3101::new(board, store, NODE_ID))
}
