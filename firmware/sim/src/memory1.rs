//! CO401Memory1's console in the simulator: the real device code over two EEPROM images, on
//! a [`FixedBoard`] whose pins give the node-ID and whose supply voltage the console sets.

use crate::devices::Console;
use crate::storage::Eeprom;
use co401memory1::{FixedBoard, Memory1};
use embedded_storage::{ReadStorage, Storage};

impl Console for Memory1<Eeprom, FixedBoard> {
    fn console(&mut self, command: &str) -> Result<String, String> {
        let words: Vec<&str> = command.split_whitespace().collect();
        let number = |s: &str| -> Result<u32, String> {
            let parsed = match s.strip_prefix("0x") {
                Some(hex) => u32::from_str_radix(hex, 16),
                None => s.parse(),
            };
            parsed.map_err(|_| format!("`{s}` is not a number"))
        };
        match words.as_slice() {
            ["supply", mv] => {
                let mv = u16::try_from(number(mv)?).map_err(|_| "the supply is at most 65535 mV".to_string())?;
                self.board_mut().supply_mv = mv;
                Ok(format!("supply {mv} mV"))
            }
            ["corrupt", bank, offset, value] => {
                let bank = match number(bank)? {
                    1 => 0,
                    2 => 1,
                    _ => return Err("banks are 1 and 2".into()),
                };
                let offset = number(offset)?;
                let value = u8::try_from(number(value)?).map_err(|_| "a byte is 0..=255".to_string())?;
                let eeprom = self.node_mut().od_mut().app.banks_mut().banks_mut().get_mut(bank).ok_or("no such bank")?;
                let mut old = [0];
                eeprom.read(offset, &mut old).map_err(|e| format!("offset {offset}: {e:?}"))?;
                eeprom.write(offset, &[value]).map_err(|e| format!("offset {offset}: {e:?}"))?;
                Ok(format!("bank {} offset {offset}: {:#04x} -> {value:#04x}", bank + 1, old[0]))
            }
            ["outputs"] => Ok(format!("{:?}", self.outputs())),
            _ => Err(format!("unknown command `{command}`; commands: supply <mV>, corrupt <bank 1|2> <offset> <value>, outputs")),
        }
    }
}
