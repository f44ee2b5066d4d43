//! CO401GW1's console in the simulator: the real chip on a [`FixedBoard`] whose ID pins give
//! the node-ID and whose CFG1 the mode; the console drives its input and emergency pins, shows
//! its outputs, and can enable CAN as the host would (`coforge sim --enable-can`). The
//! commands and their answers are the chip crate's pin console ([`co401gw1::console`]), which
//! the QEMU image serves on its third UART.

use crate::devices::Console;
use crate::storage::Eeprom;
use co401gw1::{FixedBoard, Gw1, console};
use coforge_stack::store::BlockStore;

impl Console for Gw1<FixedBoard, BlockStore<Eeprom>> {
    fn console(&mut self, command: &str) -> Result<String, String> {
        let mut answer = String::new();
        if console::run(self, command.as_bytes(), &mut answer) { Ok(answer) } else { Err(answer) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coforge_stack::device::Device;

    /// The answers `coforge sim` prints after `coforge sim: ok` / `coforge sim: error`.
    #[test]
    fn console_answers_as_before() {
        let mut chip = Gw1::new(FixedBoard::new(5, true), BlockStore::new(Eeprom::new(1024), 0));
        chip.start(0);
        assert_eq!(chip.console("in 0x01"), Ok("inputs 0x01 (pins 0xfe)".to_string()));
        assert_eq!(chip.console("emy0 on"), Ok("emy0 on".to_string()));
        assert_eq!(chip.console("enable"), Ok("CAN enabled in mode mixed".to_string()));
        assert!(chip.console("pins").is_ok_and(|a| a.starts_with("outputs 0x")));
        assert_eq!(chip.console("in x"), Err("`x` is not a byte".to_string()));
        assert_eq!(chip.console("hello"), Err("unknown command `hello`; commands: in <bits>, emy0 on|off, emy1 on|off, enable [alt], pins".to_string()));
    }
}
