//! The host side of the gateway protocol: a decoded frame becomes an owned [`Request`] (the
//! decoder's buffer is free again before the chip acts on it), and what the host configured
//! before it enabled CAN is kept in a [`HostConfig`].

use crate::serial::HostToDevice;
use coforge_link::Frame;
use heapless::Vec;

/// A value or PDO payload from the host: no host-writable entry and no PDO is longer.
pub type Bytes = Vec<u8, 8>;

/// One host command.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Request {
    /// `02 00`, or `02 81` (`alternate`: the digital-only PDO5 identifiers of PDO2).
    Enable { alternate: bool },
    /// `20`: write an entry.
    WriteOd { index: u16, sub: u8, data: Bytes },
    /// `21`: read an entry.
    ReadOd { index: u16, sub: u8 },
    /// `3P`: the data of TPDO P+1.
    WriteTpdo { pdo: u8, data: Bytes },
    /// `4P`: the data of RPDO P+1.
    ReadRpdo { pdo: u8 },
    /// `50`.
    NmtState,
    /// `51 00`: the host's answer to an emergency report; it needs no answer.
    EmergencyAck,
}

impl Request {
    /// The command `frame` carries; `None` if it is none of the protocol's, or carries a value
    /// longer than any entry the host may write.
    pub fn parse(frame: &Frame<'_>) -> Option<Request> {
        Some(match HostToDevice::decode(frame).ok()? {
            HostToDevice::EnableCan => Request::Enable { alternate: false },
            HostToDevice::EnableCanAlternate => Request::Enable { alternate: true },
            HostToDevice::WriteOdRequest { index, sub, data } => Request::WriteOd { index, sub, data: Bytes::from_slice(data).ok()? },
            HostToDevice::ReadOdRequest { index, sub } => Request::ReadOd { index, sub },
            HostToDevice::WriteTpdoRequest { pdo, data } => Request::WriteTpdo { pdo, data: Bytes::from_slice(data).ok()? },
            HostToDevice::ReadRpdoRequest { pdo } => Request::ReadRpdo { pdo },
            HostToDevice::NmtStateRequest => Request::NmtState,
            HostToDevice::EmergencyReportAnswer => Request::EmergencyAck,
        })
    }
}

/// How many different entries the host's configuration before enable may set.
pub const CONFIG_ENTRIES: usize = 32;

/// One entry the host wrote before enable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Written {
    index: u16,
    sub: u8,
    len: u8,
    data: [u8; 4],
}

/// What the host wrote before it enabled CAN, newest value per entry. NMT resets reload the
/// spec defaults and the stored parameters; the chip then writes these again, so that the
/// host's configuration survives them as the datasheet's start-up sequence expects.
#[derive(Debug, Clone, Default)]
pub struct HostConfig {
    entries: Vec<Written, CONFIG_ENTRIES>,
    /// Writes that could not be kept (more than [`CONFIG_ENTRIES`] entries, or a value
    /// longer than 4 bytes): they hold until the next NMT reset only.
    pub overflows: u32,
}

impl HostConfig {
    pub fn record(&mut self, index: u16, sub: u8, value: &[u8]) {
        let mut data = [0; 4];
        let Some(dst) = data.get_mut(..value.len()) else {
            self.overflows = self.overflows.wrapping_add(1);
            return;
        };
        dst.copy_from_slice(value);
        let written = Written { index, sub, len: value.len() as u8, data };
        match self.entries.iter_mut().find(|w| (w.index, w.sub) == (index, sub)) {
            Some(slot) => *slot = written,
            None => {
                if self.entries.push(written).is_err() {
                    self.overflows = self.overflows.wrapping_add(1);
                }
            }
        }
    }

    /// Every kept write, oldest entry first.
    pub fn writes(&self) -> impl Iterator<Item = (u16, u8, &[u8])> {
        self.entries.iter().map(|w| (w.index, w.sub, w.data.get(..usize::from(w.len)).unwrap_or(&[])))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(code: u8, length_code: Option<u8>, data: &[u8]) -> Frame<'_> {
        Frame { code, length_code, network: None, data }
    }

    #[test]
    fn frames_parse_to_requests() {
        assert_eq!(Request::parse(&frame(0x02, None, &[])), Some(Request::Enable { alternate: false }));
        assert_eq!(Request::parse(&frame(0x02, Some(0x81), &[])), Some(Request::Enable { alternate: true }));
        let write = Request::parse(&frame(0x20, None, &[0x18, 0x10, 0x04, 0x78, 0x56, 0x34, 0x12]));
        assert_eq!(write, Some(Request::WriteOd { index: 0x1018, sub: 4, data: Bytes::from_slice(&[0x78, 0x56, 0x34, 0x12]).unwrap() }));
        assert_eq!(Request::parse(&frame(0x34, None, &[1, 2])), Some(Request::WriteTpdo { pdo: 4, data: Bytes::from_slice(&[1, 2]).unwrap() }));
        assert_eq!(Request::parse(&frame(0x41, None, &[])), Some(Request::ReadRpdo { pdo: 1 }));
        // Not commands: PDO3, a read with data, a value longer than any entry.
        assert_eq!(Request::parse(&frame(0x32, None, &[])), None);
        assert_eq!(Request::parse(&frame(0x50, None, &[1])), None);
        assert_eq!(Request::parse(&frame(0x20, None, &[0, 0x30, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9])), None);
    }

    #[test]
    fn the_configuration_keeps_the_newest_value_per_entry() {
        let mut config = HostConfig::default();
        config.record(0x100B, 0, &[5]);
        config.record(0x2E01, 2, &[1]);
        config.record(0x100B, 0, &[7]);
        let writes: std::vec::Vec<_> = config.writes().map(|(i, s, d)| (i, s, d.to_vec())).collect();
        assert_eq!(writes, [(0x100B, 0, std::vec![7]), (0x2E01, 2, std::vec![1])]);
        config.record(0x3000, 0, &[0; 5]);
        assert_eq!(config.overflows, 1);
        for i in 0..CONFIG_ENTRIES as u16 {
            config.record(0x6000, i as u8, &[1]);
        }
        assert_eq!(config.overflows, 3, "two entries did not fit");
    }
}
