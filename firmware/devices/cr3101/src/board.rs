//! What a CR3101 board provides: the card slot, the battery-backed clock, the status LEDs.

use crate::card::record::TimeStamp;
use embedded_sdmmc::BlockDevice;

/// What the slot senses of the card in it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CardSense {
    pub write_protected: bool,
}

/// The five status LEDs of the manual's section 8.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StatusLeds {
    /// Red: a card is in the slot that the device cannot use, or a card access failed.
    pub card_error: bool,
    /// Green: lit while the card is written (a pulse per record: it flashes while logging).
    pub card_access: bool,
    /// Green: power.
    pub on: bool,
    /// Red: on = bus off; flashing = CAN errors or another error (an emergency active).
    pub error: bool,
    /// Green: on in operational; off otherwise.
    pub can: bool,
}

/// A CR3101 board.
pub trait Board {
    /// The card's block device (SPI SD card, an image file).
    type Card: BlockDevice;

    /// The card in the slot now, if any (polled: the slot may have no card-detect pin, and
    /// then the board probes the card).
    fn sense_card(&mut self) -> Option<CardSense>;

    /// The block device of the card just sensed; `None` if it does not answer.
    fn take_card(&mut self) -> Option<Self::Card>;

    /// The device of a card that left the device's use (removed, or unmounted).
    fn return_card(&mut self, card: Self::Card);

    /// The backup battery is good (1002h bit 2).
    fn battery_ok(&mut self) -> bool {
        true
    }

    /// The battery-backed clock's date and time at power-on.
    fn clock_at_power_on(&mut self) -> TimeStamp;

    /// Shows the status LEDs (called when they change).
    fn set_leds(&mut self, leds: StatusLeds);
}

/// CAN bit rate code (20F2h) to kbit/s, as the spec's `hardware.can_bitrate` lists them.
pub const fn bitrate_kbit(code: u8) -> Option<u16> {
    Some(match code {
        0 => 1000,
        1 => 500,
        2 => 250,
        3 => 125,
        4 => 100,
        5 => 50,
        6 => 20,
        7 => 10,
        _ => return None,
    })
}
