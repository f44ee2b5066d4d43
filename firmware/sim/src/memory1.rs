//! CO401Memory1 in the simulator: the real device code over two EEPROM images, on a
//! [`FixedBoard`] whose pins give the node-ID and whose supply voltage the console sets.

use crate::devices::{SimNode, StoreAt, eeprom};
use crate::storage::MemStorage;
use co401memory1::{BANK_SIZE, FixedBoard, Memory1};
use coforge_stack::frame::CanFrame;
use coforge_stack::node::{BusState, NodeEvent};
use coforge_stack::od::{ReadLen, SdoAbort, Side};
use embedded_storage::{ReadStorage, Storage};

/// The module on a board whose pins give `--node-id` and whose supply the console sets.
pub type SimMemory1 = Memory1<MemStorage, FixedBoard>;

/// Builds the module: banks in memory, or in `<store>.bank1` and `<store>.bank2`.
pub fn build(mode: Option<&str>, node_id: u8, store: &StoreAt) -> Result<Box<dyn SimNode>, String> {
    if let Some(mode) = mode.filter(|m| *m != co401memory1::Mode::Default.name()) {
        return Err(format!("co401memory1 has no mode `{mode}`; its modes are: {}", co401memory1::Mode::Default.name()));
    }
    let banks = [eeprom(store, BANK_SIZE, ".bank1")?, eeprom(store, BANK_SIZE, ".bank2")?];
    let device = Memory1::new(banks, FixedBoard::new(node_id)).map_err(|e| format!("co401memory1: {e:?}"))?;
    Ok(Box::new(device))
}

impl SimNode for SimMemory1 {
    fn start(&mut self, now_us: u64) {
        Memory1::start(self, now_us);
    }
    fn on_frame(&mut self, frame: &CanFrame, now_us: u64) {
        Memory1::on_frame(self, frame, now_us);
    }
    fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        Memory1::poll(self, now_us)
    }
    fn state(&self) -> coforge_stack::nmt::NmtState {
        Memory1::state(self)
    }
    fn node_id(&self) -> u8 {
        self.node().node_id()
    }
    fn read(&mut self, index: u16, sub: u8, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        self.node_mut().read(index, sub, 0, buf, Side::Device)
    }
    fn write(&mut self, index: u16, sub: u8, data: &[u8], side: Side) -> Result<(), SdoAbort> {
        self.node_mut().write(index, sub, data, side)
    }
    fn raise(&mut self, name: &str) -> bool {
        let found = co401memory1::emcy::by_name(co401memory1::Mode::Default, name);
        found.map(|e| self.node_mut().raise(&e)).is_some()
    }
    fn clear(&mut self, name: &str) -> bool {
        let found = co401memory1::emcy::by_name(co401memory1::Mode::Default, name);
        found.map(|e| self.node_mut().clear(&e)).is_some()
    }
    fn on_bus_state(&mut self, bus: BusState, now_us: u64) {
        Memory1::on_bus_state(self, bus, now_us);
    }
    fn take_event(&mut self) -> Option<NodeEvent> {
        Memory1::take_event(self)
    }
    fn trigger_tpdo(&mut self, number: u16) {
        self.node_mut().trigger_tpdo(number);
    }
    fn leds(&self) -> coforge_stack::leds::Leds {
        self.node().leds()
    }
    fn has_serial(&self) -> bool {
        true
    }
    fn serial_byte(&mut self, byte: u8, now_ms: u32, out: &mut [u8]) -> usize {
        self.on_serial_byte(byte, now_ms, out)
    }
    fn control(&mut self, command: &str) -> Result<String, String> {
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
