//! What the module needs from its board: the configuration pins, the supply voltage, and the
//! status output pins.

use crate::hardware;

/// The status output pins (true = active, i.e. driven low on the active-low pins).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StatusOutputs {
    /// MEM1ERR#: an error on memory bank 1 (6000h.1 not zero).
    pub mem1_error: bool,
    /// MEM2ERR#: an error on memory bank 2.
    pub mem2_error: bool,
    /// STATE4#: a monitored CAN frame the host has not read yet.
    pub new_can_data: bool,
    /// STATE7#: supply voltage low, memory writes refused.
    pub voltage_low: bool,
}

impl StatusOutputs {
    /// The status output register (serial SOR, object 2105h): bit 0 MEM1ERR#, bit 1
    /// MEM2ERR#, bit 4 STATE4#, bit 7 STATE7#.
    pub const fn register(self) -> u8 {
        (self.mem1_error as u8) | (self.mem2_error as u8) << 1 | (self.new_can_data as u8) << 4 | (self.voltage_low as u8) << 7
    }
}

/// The board under the module. Pin levels are raw (bit n = level of the n-th pin, 1 = high);
/// the datasheet's inversions are applied by the generated [`hardware`] decoders.
pub trait Board {
    /// ID0..ID6.
    fn node_id_pins(&mut self) -> u16;
    /// BD0..BD2.
    fn can_bitrate_pins(&mut self) -> u16;
    /// RSBD0..RSBD2.
    fn serial_bitrate_pins(&mut self) -> u16;
    /// CFG0..CFG2.
    fn config_pins(&mut self) -> u16;
    /// The supply voltage behind the input diodes, in mV (5F00h).
    fn supply_mv(&mut self) -> u16;
    /// Drives the status outputs.
    fn set_outputs(&mut self, outputs: StatusOutputs);
}

/// A board with fixed pins: a node-ID (its pins set as the inverted ID0..ID6 read it), 1 Mbit/s,
/// 9600 baud, the only defined CFG setting, and a supply reading that can be changed. The
/// simulator, the QEMU image and the tests use it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FixedBoard {
    pub node_id: u8,
    /// The supply in mV (24 V nominal).
    pub supply_mv: u16,
    /// What the module last drove on its status outputs.
    pub outputs: StatusOutputs,
}

impl FixedBoard {
    pub const fn new(node_id: u8) -> Self {
        FixedBoard { node_id, supply_mv: 24_000, outputs: StatusOutputs { mem1_error: false, mem2_error: false, new_can_data: false, voltage_low: false } }
    }
}

impl Board for FixedBoard {
    fn node_id_pins(&mut self) -> u16 {
        // Read through an inverter: a node-ID bit of 1 is a low pin.
        !u16::from(self.node_id) & 0x7F
    }
    fn can_bitrate_pins(&mut self) -> u16 {
        0b111
    }
    fn serial_bitrate_pins(&mut self) -> u16 {
        0b111
    }
    fn config_pins(&mut self) -> u16 {
        0b111
    }
    fn supply_mv(&mut self) -> u16 {
        self.supply_mv
    }
    fn set_outputs(&mut self, outputs: StatusOutputs) {
        self.outputs = outputs;
    }
}

/// The configuration the pins select at power-on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Config {
    pub node_id: u8,
    pub can_bitrate_kbit: u32,
    pub serial_baud: u32,
    /// 2101h: the inverted CFG pins.
    pub system_configuration: u32,
}

/// Pin settings the datasheet reserves: the module does not start with them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConfigError {
    /// ID0..ID6 all high (node-ID code 0).
    ReservedNodeId,
    /// RSBD2..RSBD0 = 100, 011 or 000.
    ReservedSerialBitrate { code: u16 },
}

impl Config {
    /// Reads and decodes the configuration pins.
    pub fn read(board: &mut impl Board) -> Result<Config, ConfigError> {
        let node_id = hardware::node_id(board.node_id_pins()).and_then(|id| u8::try_from(id).ok()).ok_or(ConfigError::ReservedNodeId)?;
        let serial = board.serial_bitrate_pins();
        let serial_baud = hardware::serial_bitrate(serial).ok_or(ConfigError::ReservedSerialBitrate { code: !serial & 0x07 })?;
        // Every BD code has a bit rate, so this cannot fail; 1 Mbit/s is the unconnected default.
        let can_bitrate_kbit = hardware::can_bitrate(board.can_bitrate_pins()).unwrap_or(1000);
        Ok(Config { node_id, can_bitrate_kbit, serial_baud, system_configuration: hardware::config(board.config_pins()) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pins_decode_as_the_datasheet_tables_say() {
        // ID0 low, ID1..ID6 high: node-ID 1. ID6..ID0 = 0000010: node-ID 125 (erratum MEM-30).
        assert_eq!(hardware::node_id(0b111_1110), Some(1));
        assert_eq!(hardware::node_id(0b000_0010), Some(125));
        assert_eq!(hardware::node_id(0x7F), None);
        assert_eq!(hardware::can_bitrate(0b111), Some(1000));
        assert_eq!(hardware::can_bitrate(0b000), Some(10));
        assert_eq!(hardware::serial_bitrate(0b111), Some(9600));
        assert_eq!(hardware::serial_bitrate(0b011), None);
        assert_eq!(hardware::config(0b111), 0);
        assert_eq!(StatusOutputs { mem1_error: true, voltage_low: true, ..Default::default() }.register(), 0x81);
    }
}
