//! The serial host protocol: each command of the datasheet's list with its acknowledge, on
//! the generated codecs. A known command with the wrong length gets its negative answer; a
//! frame with an unknown command nibble, or a malformed Read Status (which has no negative
//! form), gets none and is counted in [`Memory1::host_errors`].

use crate::board::Board;
use crate::device::Memory1;
use crate::index;
use crate::monitor::monitored_id;
use crate::serial::{DeviceToHost, HostToDevice};
use coforge_link::Frame;
use coforge_link::fields::DecodeError;
use coforge_stack::frame::CanFrame;
use coforge_stack::nmt::NmtState;
use coforge_stack::od::Side;
use embedded_storage::Storage;

/// The acknowledge byte.
const fn ack(ok: bool) -> u8 {
    ok as u8
}

/// The negative answer to a command nibble, where the protocol defines one.
fn negative(code: u8) -> Option<DeviceToHost<'static>> {
    Some(match code {
        0x1 => DeviceToHost::WriteCommandRegisterAck { ack: 0 },
        0x3 => DeviceToHost::ReadMemoryAnswer { ack: 0, data: 0 },
        0x4 => DeviceToHost::WriteMemoryAck { ack: 0 },
        0x8 => DeviceToHost::SetupCanMonitoringAck { ack: 0 },
        0xC => DeviceToHost::ReadCanDataAnswer { ack: 0, data: &[] },
        0xD => DeviceToHost::WriteCanDataAck { ack: 0 },
        _ => return None,
    })
}

impl<S: Storage, B: Board> Memory1<S, B> {
    /// Executes one frame from the host and queues the answer for it.
    pub(crate) fn answer(&mut self, frame: &Frame<'_>) {
        let mut can_data = [0_u8; 8];
        let answer = match HostToDevice::decode(frame) {
            Ok(command) => self.execute(command, &mut can_data),
            Err(DecodeError::Length { .. }) => negative(frame.code),
            Err(_) => None,
        };
        match answer {
            Some(a) => {
                self.host_out.push_with(|out| a.encode(out).ok());
            }
            None => self.host_rejects = self.host_rejects.wrapping_add(1),
        }
    }

    fn execute<'a>(&mut self, command: HostToDevice<'_>, can_data: &'a mut [u8; 8]) -> Option<DeviceToHost<'a>> {
        Some(match command {
            HostToDevice::ReadStatusRequest => {
                let app = &self.node.od().app;
                DeviceToHost::ReadStatusAnswer { ms1: app.status(0).bits(), ms2: app.status(1).bits(), sor: self.outputs().register(), reserved: 0 }
            }
            // ADR 1 = 6200h.1, ADR 2 = 6200h.2 (erratum MEM-23).
            HostToDevice::WriteCommandRegister { register, value } => {
                let ok = matches!(register, 1 | 2) && self.node.write(index::WRITE_MEMORY_BANK_COMMAND, register, &[value], Side::Device).is_ok();
                DeviceToHost::WriteCommandRegisterAck { ack: ack(ok) }
            }
            HostToDevice::ReadMemoryRequest { index, sub } => {
                let mut byte = [0];
                let ok = self.node.read(index, sub, 0, &mut byte, Side::Host).is_ok_and(|r| r.copied == 1);
                DeviceToHost::ReadMemoryAnswer { ack: ack(ok), data: if ok { byte[0] } else { 0 } }
            }
            HostToDevice::WriteMemoryCommand { index, sub, data } => {
                let ok = self.node.write(index, sub, &[data], Side::Host).is_ok();
                DeviceToHost::WriteMemoryAck { ack: ack(ok) }
            }
            HostToDevice::SetupCanMonitoring { reg, value } => DeviceToHost::SetupCanMonitoringAck { ack: ack(reg == 0 && self.set_monitoring(value)) },
            HostToDevice::ReadCanDataRequest => match self.monitor.take() {
                Some(data) => {
                    let n = data.len().min(8);
                    let dst = can_data.get_mut(..n).unwrap_or(&mut []);
                    dst.copy_from_slice(data.get(..n).unwrap_or(&[]));
                    DeviceToHost::ReadCanDataAnswer { ack: 1, data: dst }
                }
                None => DeviceToHost::ReadCanDataAnswer { ack: 0, data: &[] },
            },
            HostToDevice::WriteCanData { id, data } => DeviceToHost::WriteCanDataAck { ack: ack(self.transmit(id, data)) },
        })
    }

    /// Monitors `id` (0 stops). Identifiers the module's own stack receives are refused,
    /// where the datasheet only warns that they "might crash" it (erratum MEM-37).
    fn set_monitoring(&mut self, id: u16) -> bool {
        if id > 0x7FF || self.consumed_by_stack(id) {
            return false;
        }
        let current = self.node.od().rpdo2_comm.cob_id_used_by_rpdo.get();
        // CiA 301: a valid COB-ID is invalidated before it changes.
        let invalid = current | 0x8000_0000;
        if self.node.write(index::RPDO2_COMM, 1, &invalid.to_le_bytes(), Side::Device).is_err() {
            return false;
        }
        self.monitor.stop();
        id == 0 || self.node.write(index::RPDO2_COMM, 1, &u32::from(id).to_le_bytes(), Side::Device).is_ok()
    }

    /// NMT, SYNC, this node's SDO requests, RPDO1 and node guarding.
    fn consumed_by_stack(&self, id: u16) -> bool {
        let od = self.node.od();
        let node = u16::from(self.node.node_id());
        let sync = (od.cob_id_sync.get() & 0x7FF) as u16;
        let rpdo1 = monitored_id(od.rpdo1_comm.cob_id_used_by_rpdo.get());
        id != 0 && (id == sync || id == 0x600 + node || id == 0x700 + node || Some(id) == rpdo1)
    }

    /// Queues a frame for the bus; refused while stopped or bus-off, or with a full queue.
    fn transmit(&mut self, id: u16, data: &[u8]) -> bool {
        if self.node.state() == NmtState::Stopped || self.bus_off {
            return false;
        }
        CanFrame::data(id, data).is_some_and(|f| self.raw_tx.push_back(f).is_ok())
    }
}
