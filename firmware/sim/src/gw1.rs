//! CO401GW1's console in the simulator: the real chip on a [`FixedBoard`] whose ID pins give
//! the node-ID and whose CFG1 the mode; the console drives its input and emergency pins, shows
//! its outputs, and can enable CAN as the host would (`coforge sim --enable-can`).

use crate::devices::Console;
use crate::storage::Eeprom;
use co401gw1::{FixedBoard, Gw1};
use coforge_stack::device::NodeAccess;
use coforge_stack::store::BlockStore;

impl Console for Gw1<FixedBoard, BlockStore<Eeprom>> {
    fn console(&mut self, command: &str) -> Result<String, String> {
        let words: Vec<&str> = command.split_whitespace().collect();
        let byte = |s: &str| -> Result<u8, String> {
            let parsed = match s.strip_prefix("0x") {
                Some(hex) => u8::from_str_radix(hex, 16),
                None => s.parse(),
            };
            parsed.map_err(|_| format!("`{s}` is not a byte"))
        };
        let active = |s: &str| match s {
            "on" | "low" => Ok(true),
            "off" | "high" => Ok(false),
            _ => Err(format!("`{s}`: say on (pin low) or off (pin high)")),
        };
        match words.as_slice() {
            // Bit n set: INn active (pin low).
            ["in", bits] => {
                let bits = byte(bits)?;
                self.board_mut().input_levels = !bits;
                Ok(format!("inputs {bits:#04x} (pins {:#04x})", !bits))
            }
            [pin @ ("emy0" | "emy1"), state] => {
                let bit = if *pin == "emy0" { 1 } else { 2 };
                let levels = &mut self.board_mut().emergency_levels;
                *levels = if active(state)? { *levels & !bit } else { *levels | bit };
                Ok(format!("{pin} {state}"))
            }
            ["enable"] | ["enable", "alt"] => {
                let alternate = words.len() == 2;
                let now = self.now_us();
                if self.enable(alternate, now) {
                    Ok(format!("CAN enabled in mode {}", NodeAccess::mode_name(self.node())))
                } else {
                    Err("enable refused: enabled already, no valid node-ID, or `alt` in mixed mode".into())
                }
            }
            ["pins"] => {
                let b = self.board();
                let lit = |on: bool| if on { "lit" } else { "dark" };
                Ok(format!(
                    "outputs {:#04x} (pins {:#04x}), run LED {}, error LED {}, watchdog {}",
                    !b.output_levels,
                    b.output_levels,
                    lit(b.run_lit),
                    lit(b.error_lit),
                    if b.watchdog { "high" } else { "low" }
                ))
            }
            _ => Err(format!("unknown command `{command}`; commands: in <bits>, emy0 on|off, emy1 on|off, enable [alt], pins")),
        }
    }
}
