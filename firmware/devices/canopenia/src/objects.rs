//! The coprocessor's own part of its dictionary (the generated `app::Hooks`): 1F50h/1F51h, the
//! configuration loading interface ([`Program`]), and every write the rest of the device acts
//! on, kept until the device takes it after the input that caused it:
//! - writes from the bus (an SDO download, an RPDO) of any entry: indications `D` to the host;
//! - writes of the manager's command entries from any side: 5F0Ah.1 (an NMT master message),
//!   5F01h.1 (a reset of the coprocessor), 5F01h.0Ah (scan a node again).

use crate::app::Hooks;
use crate::config::program::Program;
use crate::config::slots::{ConfigMemory, NoMemory};
use crate::index;
use coforge_stack::od::{ReadLen, SdoAbort, WriteSource};
use heapless::Deque;

/// Bytes of a written value kept: the most a PDO carries, and more than the node's largest
/// SDO-writable entry (`od::MAX_WRITE_SIZE`).
pub const WRITTEN_MAX: usize = 8;
/// Writes kept between two inputs: every entry of two full RPDOs.
const WRITES: usize = 16;

/// A write that took effect.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Written {
    pub index: u16,
    pub sub: u8,
    pub data: heapless::Vec<u8, WRITTEN_MAX>,
    pub by: WriteSource,
}

impl Written {
    /// Whether the host is told of it: it came from the bus.
    pub fn from_bus(&self) -> bool {
        from_bus(self.by)
    }
}

fn from_bus(by: WriteSource) -> bool {
    matches!(by, WriteSource::Sdo | WriteSource::Rpdo)
}

/// Whether the device acts on writes of this entry (whoever writes it but the device itself).
pub(crate) fn is_command_entry(index: u16, sub: u8) -> bool {
    matches!((index, sub), (index::NMT_MASTER_MESSAGE, 1) | (index::DEVICE_CONTROL, 1 | 0x0A))
}

/// The app side of the dictionary, with configuration memory `M`.
#[derive(Debug)]
pub struct Coprocessor<M = NoMemory> {
    writes: Deque<Written, WRITES>,
    /// Writes not kept: the queue was full, or the value longer than [`WRITTEN_MAX`].
    pub writes_dropped: u32,
    pub program: Program<M>,
}

impl<M: ConfigMemory> Coprocessor<M> {
    pub fn new(memory: M) -> Self {
        let entries = crate::od::entries(crate::Mode::Default);
        Coprocessor { writes: Deque::new(), writes_dropped: 0, program: Program::new(memory, entries) }
    }

    /// The oldest write not taken yet.
    pub fn take_write(&mut self) -> Option<Written> {
        self.writes.pop_front()
    }
}

impl<M: ConfigMemory> Hooks for Coprocessor<M> {
    /// Program data is write-only: the dictionary refuses reads before this hook.
    fn read_program_data(&mut self, _sub: u8, _offset: usize, _buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        Err(SdoAbort::WriteOnly)
    }

    fn write_program_data(&mut self, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        match sub {
            1 => self.program.write_key(data),
            _ => self.program.write_whole(data),
        }
    }

    fn read_program_control(&mut self, _sub: u8) -> Result<u8, SdoAbort> {
        Ok(self.program.control())
    }

    fn write_program_control(&mut self, _sub: u8, value: u8) -> Result<(), SdoAbort> {
        self.program.write_control(value)
    }

    const STREAMING: bool = true;

    /// The configuration file streams into its slot.
    fn streams(&mut self, index: u16, sub: u8) -> bool {
        (index, sub) == (index::PROGRAM_DATA, 2)
    }

    fn write_part(&mut self, index: u16, sub: u8, offset: usize, data: &[u8], last: bool) -> Result<(), SdoAbort> {
        if (index, sub) != (index::PROGRAM_DATA, 2) {
            return Err(SdoAbort::UnsupportedAccess);
        }
        self.program.write_part(offset, data, last)
    }

    fn abort_stream(&mut self, _index: u16, _sub: u8) {
        self.program.abort_download();
    }

    fn written(&mut self, index: u16, sub: u8, data: &[u8], by: WriteSource) {
        // The device's own writes (a loaded configuration's values) are not commands.
        let command = is_command_entry(index, sub) && by != WriteSource::Device;
        if !from_bus(by) && !command {
            return;
        }
        let kept = heapless::Vec::from_slice(data).ok().is_some_and(|data| self.writes.push_back(Written { index, sub, data, by }).is_ok());
        if !kept {
            self.writes_dropped = self.writes_dropped.saturating_add(1);
        }
    }
}
