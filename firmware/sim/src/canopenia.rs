//! CANopenIA in the simulator: the real coprocessor over a parameter store in memory or a
//! file; its host talks to it through the serial port (`coforge sim canopenia --serial`).
//! The console sets its AUTORUN pin: `autorun on|off`, read at the next reset (5F01h.1, an
//! NMT reset of the coprocessor), and the chip's serial number: `serial-number HEX` (1018h.4
//! and the activation key of configuration loading, from the next reset on).

use crate::devices::Console;
use crate::storage::Eeprom;
use canopenia::Canopenia;
use coforge_stack::store::BlockStore;

impl Console for Canopenia<BlockStore<Eeprom>, Eeprom> {
    fn console(&mut self, command: &str) -> Result<String, String> {
        match command.split_whitespace().collect::<Vec<_>>().as_slice() {
            ["autorun", level @ ("on" | "off")] => {
                self.set_autorun(*level == "on");
                Ok(format!("AUTORUN pin {}, read at the next reset", if *level == "on" { "high" } else { "low" }))
            }
            ["serial-number", hex] => {
                let serial = u32::from_str_radix(hex.trim_start_matches("0x"), 16).map_err(|e| format!("serial number `{hex}`: {e}"))?;
                self.set_serial_number(serial);
                Ok(format!("serial number {serial:08X}h, in 1018h.4 from the next reset"))
            }
            _ => Err(format!("unknown command `{command}`; canopenia takes `autorun on|off`, `serial-number HEX`")),
        }
    }
}
