//! App-backed objects of a simulated device (EEPROM banks, memory-card files): plain RAM
//! here, holding whatever the bus or host last wrote, until the device's own behaviour
//! replaces it. Reads of a never-written entry give zeros of the entry's size.

use coforge_stack::od::{AppObjects, EntryInfo, ReadLen, SdoAbort, read_slice};
use std::collections::HashMap;

#[derive(Debug, Clone, Default)]
pub struct RamApp {
    values: HashMap<(u16, u8), Vec<u8>>,
}

impl AppObjects for RamApp {
    fn read(&mut self, entry: &EntryInfo, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        let zeros;
        let value = match self.values.get(&(index, sub)) {
            Some(v) => v.as_slice(),
            None => {
                // Variable-length entries start empty; fixed-size ones read as zero.
                let len = if entry.data_type().bits().is_some() { usize::from(entry.size) } else { 0 };
                zeros = vec![0; len];
                zeros.as_slice()
            }
        };
        read_slice(value, offset, buf)
    }

    fn write(&mut self, _: &EntryInfo, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.values.insert((index, sub), data.to_vec());
        Ok(())
    }
}
