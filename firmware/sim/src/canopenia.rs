//! CANopenIA in the simulator: the real coprocessor over a parameter store in memory or a
//! file; its host talks to it through the serial port (`coforge sim canopenia --serial`).

use crate::devices::Console;
use crate::storage::Eeprom;
use canopenia::Canopenia;
use coforge_stack::store::BlockStore;

/// The coprocessor has no pins to drive: everything goes through its host protocol.
impl Console for Canopenia<BlockStore<Eeprom>> {}
