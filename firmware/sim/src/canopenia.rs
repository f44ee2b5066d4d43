//! CANopenIA in the simulator: the real coprocessor over a parameter store in memory or a
//! file; its host talks to it through the serial port (`coforge sim canopenia --serial`).
//! The console sets its AUTORUN pin: `autorun on|off`, read at the next reset (5F01h.1, an
//! NMT reset of the coprocessor).

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
            _ => Err(format!("unknown command `{command}`; canopenia takes `autorun on|off`")),
        }
    }
}
