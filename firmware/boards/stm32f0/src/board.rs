//! The board under CO401Memory1: configuration pins through two 74HC165, the supply on the
//! ADC, the status outputs on GPIOs. Pin map: the crate documentation and `PINS.md`.

use crate::clock;
use co401memory1::{Board, StatusOutputs};
use embedded_hal_02::adc::OneShot;
use embedded_hal_02::digital::v2::{InputPin, OutputPin};
use stm32f0xx_hal::adc::Adc;
use stm32f0xx_hal::gpio::gpioa::{PA0, PA4, PA5, PA6, PA7};
use stm32f0xx_hal::gpio::gpiob::{PB3, PB4, PB5};
use stm32f0xx_hal::gpio::{Analog, Input, Output, PullUp, PushPull};

/// VDDA, the ADC reference: the board's 3.3 V regulator.
pub const VDDA_MV: u32 = 3300;
/// The supply divider: 110 kOhm over 10 kOhm, so PA0 sees 1/12 of the supply (39.6 V full
/// scale for the 18..36 V range).
pub const DIVIDER: u32 = 12;
/// How long a supply reading is reused: `supply_mv` is asked after every input.
const SUPPLY_REFRESH_MS: u32 = 10;

/// The 16 configuration inputs, as shifted in from the 74HC165 chain (first bit = bit 15).
/// U1 (its QH at PB5): A..G = ID0..ID6 (bits 8..14), H = CFG2 (bit 15); U2 (its QH into U1's
/// SER): A..C = BD0..BD2 (bits 0..2), D..F = RSBD0..RSBD2 (bits 3..5), G = CFG0, H = CFG1
/// (bits 6, 7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConfigWord(pub u16);

impl ConfigWord {
    pub const fn node_id(self) -> u16 {
        (self.0 >> 8) & 0x7F
    }
    pub const fn can_bitrate(self) -> u16 {
        self.0 & 0x7
    }
    pub const fn serial_bitrate(self) -> u16 {
        (self.0 >> 3) & 0x7
    }
    pub const fn config(self) -> u16 {
        (self.0 >> 6) & 0x3 | (self.0 >> 13) & 0x4
    }
}

/// The 74HC165 chain: PB3 = CLK, PB4 = SH/LD#, PB5 = QH (pulled up: no chain reads all pins
/// high, i.e. unconnected, and the reserved node-ID code 0 keeps the module from starting).
/// CLK INH is tied low on the board.
pub struct ConfigChain {
    pub clk: PB3<Output<PushPull>>,
    pub load: PB4<Output<PushPull>>,
    pub data: PB5<Input<PullUp>>,
}

/// About 1 us at 48 MHz: far above the 74HC165's pulse widths and set-up times at 3.3 V.
fn settle() {
    cortex_m::asm::delay(48);
}

impl ConfigChain {
    /// Latches the 16 inputs and shifts them in.
    pub fn read(&mut self) -> ConfigWord {
        let _ = self.clk.set_low();
        let _ = self.load.set_low();
        settle();
        let _ = self.load.set_high();
        settle();
        let mut word = 0_u16;
        for _ in 0..16 {
            word = word << 1 | u16::from(self.data.is_high().unwrap_or(true));
            let _ = self.clk.set_high();
            settle();
            let _ = self.clk.set_low();
            settle();
        }
        ConfigWord(word)
    }
}

/// The status outputs, active low (push-pull; high = inactive).
pub struct StatusPins {
    pub mem1_error: PA4<Output<PushPull>>,
    pub mem2_error: PA5<Output<PushPull>>,
    pub new_can_data: PA6<Output<PushPull>>,
    pub voltage_low: PA7<Output<PushPull>>,
}

/// Drives an active-low pin.
fn drive(pin: &mut impl OutputPin, active: bool) {
    let _ = if active { pin.set_low() } else { pin.set_high() };
}

/// The STM32F042 board: the configuration read once at power-on, the supply, the outputs.
pub struct Stm32Board {
    config: ConfigWord,
    adc: Adc,
    supply_pin: PA0<Analog>,
    /// The last reading and when it was taken.
    supply: Option<(u16, u32)>,
    outputs: StatusPins,
}

impl Stm32Board {
    /// Starts with every status output inactive (high).
    pub fn new(config: ConfigWord, adc: Adc, supply_pin: PA0<Analog>, outputs: StatusPins) -> Self {
        let mut board = Stm32Board { config, adc, supply_pin, supply: None, outputs };
        board.set_outputs(StatusOutputs::default());
        board
    }

    fn measure(&mut self) -> u16 {
        // The HAL's conversion cannot fail (its error type is `()` and it always returns Ok);
        // 0 mV would read as a supply too low to write, the safe side.
        let raw: u16 = self.adc.read(&mut self.supply_pin).unwrap_or(0);
        let mv = u32::from(raw) * VDDA_MV * DIVIDER / 4095;
        u16::try_from(mv).unwrap_or(u16::MAX)
    }
}

impl Board for Stm32Board {
    fn node_id_pins(&mut self) -> u16 {
        self.config.node_id()
    }

    fn can_bitrate_pins(&mut self) -> u16 {
        self.config.can_bitrate()
    }

    fn serial_bitrate_pins(&mut self) -> u16 {
        self.config.serial_bitrate()
    }

    fn config_pins(&mut self) -> u16 {
        self.config.config()
    }

    /// A new conversion (about 20 us with 239.5-cycle sampling for the divider's 9 kOhm
    /// source) at most every 10 ms.
    fn supply_mv(&mut self) -> u16 {
        // The low 32 bits: a wrapping difference is all this needs.
        let now = clock::millis() as u32;
        match self.supply {
            Some((mv, at)) if now.wrapping_sub(at) < SUPPLY_REFRESH_MS => mv,
            _ => {
                let mv = self.measure();
                self.supply = Some((mv, now));
                mv
            }
        }
    }

    fn set_outputs(&mut self, outputs: StatusOutputs) {
        drive(&mut self.outputs.mem1_error, outputs.mem1_error);
        drive(&mut self.outputs.mem2_error, outputs.mem2_error);
        drive(&mut self.outputs.new_can_data, outputs.new_can_data);
        drive(&mut self.outputs.voltage_low, outputs.voltage_low);
    }
}
