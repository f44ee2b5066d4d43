//! What the chip needs from its board: the pins read at reset (ID, CFG), the digital inputs
//! and emergency inputs, and the outputs (OUT0..OUT7, the LEDs on CFG0/R and CFG1/E, the
//! watchdog on CFG2/WD). Levels are raw (1 = high); the datasheet's inversions are applied
//! by the chip, as the real one does.

use crate::hardware;

/// The board under the chip.
pub trait Board {
    /// ID0..ID6, bit n = pin IDn.
    fn node_id_pins(&mut self) -> u16;
    /// CFG0..CFG2, read at reset only.
    fn config_pins(&mut self) -> u16;
    /// IN0..IN7 (active low).
    fn input_pins(&mut self) -> u8;
    /// Bit 0 EMY0#, bit 1 EMY1# (active low).
    fn emergency_pins(&mut self) -> u8;
    /// Drives OUT0..OUT7 (active low: the chip has already inverted the data).
    fn set_output_pins(&mut self, levels: u8);
    /// Drives CFG0/R, CFG1/E and CFG2/WD after reset: `true` = LED lit (pin low), and the
    /// watchdog pin level.
    fn set_indicators(&mut self, run_lit: bool, error_lit: bool, watchdog: bool);
}

/// The configuration read from the pins at reset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PinConfig {
    /// The node-ID the ID pins select; `None`: all pins high, the host sets 100Bh.
    pub node_id: Option<u8>,
    /// CFG1 high: Analog/Digital Mixed mode; low: digital only.
    pub mixed: bool,
    /// CFG0 high: the digital hardware inputs are enabled by default.
    pub hardware_inputs: bool,
    /// What 2101h shows: the inverted CFG0..CFG2.
    pub system_configuration: u32,
}

impl PinConfig {
    pub fn read(board: &mut impl Board) -> Self {
        let cfg = board.config_pins();
        PinConfig {
            node_id: hardware::node_id(board.node_id_pins()).and_then(|id| u8::try_from(id).ok()),
            mixed: cfg & 0b010 != 0,
            hardware_inputs: cfg & 0b001 != 0,
            system_configuration: hardware::config(cfg),
        }
    }
}

/// A board whose pins the simulator, the QEMU image and the tests set, and whose outputs they
/// read back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FixedBoard {
    /// ID0..ID6 levels.
    pub id_levels: u16,
    /// CFG0..CFG2 levels.
    pub cfg_levels: u16,
    /// IN0..IN7 levels (all high: no input active).
    pub input_levels: u8,
    /// EMY0#/EMY1# levels (both high: no emergency).
    pub emergency_levels: u8,
    /// OUT0..OUT7 as last driven.
    pub output_levels: u8,
    pub run_lit: bool,
    pub error_lit: bool,
    pub watchdog: bool,
}

impl FixedBoard {
    /// ID pins that select `node_id` (0: all high, the programmable node-ID), CFG0 high
    /// (hardware inputs enabled) and CFG1 as `mixed` says, CFG2 high.
    pub const fn new(node_id: u8, mixed: bool) -> Self {
        FixedBoard {
            id_levels: !(node_id as u16) & 0x7F,
            cfg_levels: 0b101 | if mixed { 0b010 } else { 0 },
            input_levels: 0xFF,
            emergency_levels: 0b11,
            output_levels: 0xFF,
            run_lit: false,
            error_lit: false,
            watchdog: false,
        }
    }
}

impl Board for FixedBoard {
    fn node_id_pins(&mut self) -> u16 {
        self.id_levels
    }
    fn config_pins(&mut self) -> u16 {
        self.cfg_levels
    }
    fn input_pins(&mut self) -> u8 {
        self.input_levels
    }
    fn emergency_pins(&mut self) -> u8 {
        self.emergency_levels
    }
    fn set_output_pins(&mut self, levels: u8) {
        self.output_levels = levels;
    }
    fn set_indicators(&mut self, run_lit: bool, error_lit: bool, watchdog: bool) {
        (self.run_lit, self.error_lit, self.watchdog) = (run_lit, error_lit, watchdog);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pins_decode_as_the_datasheet_tables_say() {
        let mut board = FixedBoard::new(5, true);
        let cfg = PinConfig::read(&mut board);
        assert_eq!((cfg.node_id, cfg.mixed, cfg.hardware_inputs), (Some(5), true, true));
        // 2101h is the inverted CFG0..CFG2: all high reads 0.
        assert_eq!(cfg.system_configuration, 0);
        let mut board = FixedBoard::new(0, false);
        board.cfg_levels = 0b000;
        let cfg = PinConfig::read(&mut board);
        assert_eq!((cfg.node_id, cfg.mixed, cfg.hardware_inputs, cfg.system_configuration), (None, false, false, 0b111));
        // ID pins 1111110 (ID0 low) select node-ID 1, 0000000 node-ID 127.
        board.id_levels = 0b111_1110;
        assert_eq!(PinConfig::read(&mut board).node_id, Some(1));
        board.id_levels = 0;
        assert_eq!(PinConfig::read(&mut board).node_id, Some(127));
    }
}
