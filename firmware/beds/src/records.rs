//! The record kinds of the tables, each decoded from exactly its own bytes (and encoded back,
//! which the writer and the tests use).

use crate::layout::Dsat;

fn u16_at(b: &[u8], at: usize) -> u16 {
    match b.get(at..at + 2) {
        Some(&[lo, hi]) => u16::from_le_bytes([lo, hi]),
        _ => 0,
    }
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    match b.get(at..at + 4) {
        Some(&[a, b, c, d]) => u32::from_le_bytes([a, b, c, d]),
        _ => 0,
    }
}

/// A constant entry of 1..4 bytes, stored as the whole expedited SDO upload response the
/// device gives for it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SdoReply {
    /// The response's command byte: 0x43, 0x47, 0x4B or 0x4F for 4, 3, 2 or 1 bytes.
    pub command: u8,
    pub index: u16,
    pub sub: u8,
    pub data: [u8; 4],
}

impl SdoReply {
    pub const LEN: usize = 8;

    /// The reply of a value of `len` (1..=4) bytes, which are the first `len` of `data`.
    pub fn new(index: u16, sub: u8, data: [u8; 4], len: u8) -> Self {
        let unused = 4_u8.saturating_sub(len.clamp(1, 4));
        SdoReply { command: 0x43 | (unused << 2), index, sub, data }
    }

    pub fn decode(r: &[u8; Self::LEN]) -> Self {
        SdoReply { command: r[0], index: u16_at(r, 1), sub: r[3], data: [r[4], r[5], r[6], r[7]] }
    }

    pub fn encode(&self) -> [u8; Self::LEN] {
        let [i0, i1] = self.index.to_le_bytes();
        let [d0, d1, d2, d3] = self.data;
        [self.command, i0, i1, self.sub, d0, d1, d2, d3]
    }

    /// The value's size in bytes, if the command byte is an expedited upload response with
    /// the size indicated.
    pub fn size(&self) -> Option<u8> {
        (self.command & 0xF3 == 0x43).then(|| 4 - ((self.command >> 2) & 3))
    }

    /// The value's bytes.
    pub fn value(&self) -> &[u8] {
        let len = usize::from(self.size().unwrap_or(0));
        self.data.get(..len).unwrap_or(&[])
    }
}

/// An entry of at most 4 bytes that lives in the process image.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OdEntry {
    pub index: u16,
    pub sub: u8,
    pub dsat: Dsat,
    /// Where its value is in the process image.
    pub offset: u16,
}

impl OdEntry {
    pub const LEN: usize = 6;

    pub fn decode(r: &[u8; Self::LEN]) -> Self {
        OdEntry { index: u16_at(r, 0), sub: r[2], dsat: Dsat(r[3]), offset: u16_at(r, 4) }
    }

    pub fn encode(&self) -> [u8; Self::LEN] {
        let [i0, i1] = self.index.to_le_bytes();
        let [o0, o1] = self.offset.to_le_bytes();
        [i0, i1, self.sub, self.dsat.0, o0, o1]
    }

    pub fn size(&self) -> u16 {
        u16::from(self.dsat.size())
    }
}

/// A process-image entry of more than 4 bytes (strings, domains).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GenericEntry {
    pub index: u16,
    pub sub: u8,
    /// Access bits 4..7 as in [`Dsat`]; bits 0..3 are zero.
    pub access: Dsat,
    pub size: u16,
    pub offset: u16,
}

impl GenericEntry {
    pub const LEN: usize = 8;

    pub fn decode(r: &[u8; Self::LEN]) -> Self {
        GenericEntry { index: u16_at(r, 0), sub: r[2], access: Dsat(r[3]), size: u16_at(r, 4), offset: u16_at(r, 6) }
    }

    pub fn encode(&self) -> [u8; Self::LEN] {
        let [i0, i1] = self.index.to_le_bytes();
        let [s0, s1] = self.size.to_le_bytes();
        let [o0, o1] = self.offset.to_le_bytes();
        [i0, i1, self.sub, self.access.0, s0, s1, o0, o1]
    }
}

/// One PDO's configuration: 12 bytes for an RPDO, 16 for a TPDO (with its timers).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdoRecord {
    pub number: u8,
    pub transmission_type: u8,
    /// Bytes of process data the PDO carries.
    pub length: u8,
    pub cob_id: u32,
    /// Process-image offset of the first mapped entry (the PDO's data is contiguous there).
    pub offset: u32,
    /// TPDOs only (zero in an RPDO record).
    pub event_time: u16,
    pub inhibit_time: u16,
}

impl PdoRecord {
    pub const RPDO_LEN: usize = 12;
    pub const TPDO_LEN: usize = 16;

    /// Decodes a 12-byte RPDO or 16-byte TPDO record (other lengths give the RPDO fields).
    pub fn decode(r: &[u8]) -> Self {
        PdoRecord {
            number: r.first().copied().unwrap_or(0),
            transmission_type: r.get(1).copied().unwrap_or(0),
            length: r.get(2).copied().unwrap_or(0),
            cob_id: u32_at(r, 4),
            offset: u32_at(r, 8),
            event_time: u16_at(r, 12),
            inhibit_time: u16_at(r, 14),
        }
    }

    pub fn encode_rpdo(&self) -> [u8; Self::RPDO_LEN] {
        let mut r = [0; Self::RPDO_LEN];
        let (head, tail) = r.split_at_mut(4);
        head.copy_from_slice(&[self.number, self.transmission_type, self.length, 0]);
        let (cob, offset) = tail.split_at_mut(4);
        cob.copy_from_slice(&self.cob_id.to_le_bytes());
        offset.copy_from_slice(&self.offset.to_le_bytes());
        r
    }

    pub fn encode_tpdo(&self) -> [u8; Self::TPDO_LEN] {
        let mut r = [0; Self::TPDO_LEN];
        let (rpdo, timers) = r.split_at_mut(Self::RPDO_LEN);
        rpdo.copy_from_slice(&self.encode_rpdo());
        let (event, inhibit) = timers.split_at_mut(2);
        event.copy_from_slice(&self.event_time.to_le_bytes());
        inhibit.copy_from_slice(&self.inhibit_time.to_le_bytes());
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sdo_reply_command_bytes_give_the_value_size() {
        for (len, cmd) in [(1, 0x4F), (2, 0x4B), (3, 0x47), (4, 0x43)] {
            let r = SdoReply::new(0x1000, 0, [1, 2, 3, 4], len);
            assert_eq!(r.command, cmd);
            assert_eq!(r.size(), Some(len));
            assert_eq!(r.value(), &[1, 2, 3, 4][..usize::from(len)]);
            assert_eq!(SdoReply::decode(&r.encode()), r);
        }
        // A segmented-upload or download command byte is not a reply.
        assert_eq!(SdoReply { command: 0x41, index: 0, sub: 0, data: [0; 4] }.size(), None);
        assert_eq!(SdoReply { command: 0x60, index: 0, sub: 0, data: [0; 4] }.value(), &[] as &[u8]);
    }

    #[test]
    fn records_encode_what_they_decode() {
        let od = OdEntry { index: 0x6200, sub: 1, dsat: Dsat::new(1, Dsat::READ | Dsat::WRITE | Dsat::RPDO), offset: 7 };
        assert_eq!(od.encode(), [0x00, 0x62, 1, 0xB1, 7, 0]);
        assert_eq!(OdEntry::decode(&od.encode()), od);
        let g = GenericEntry { index: 0x1008, sub: 0, access: Dsat(Dsat::READ), size: 21, offset: 90 };
        assert_eq!(GenericEntry::decode(&g.encode()), g);
        let t = PdoRecord { number: 2, transmission_type: 0xFF, length: 8, cob_id: 0x4000_0283, offset: 40, event_time: 1000, inhibit_time: 200 };
        assert_eq!(t.encode_tpdo(), [2, 0xFF, 8, 0, 0x83, 0x02, 0, 0x40, 40, 0, 0, 0, 0xE8, 0x03, 0xC8, 0]);
        assert_eq!(PdoRecord::decode(&t.encode_tpdo()), t);
        let r = PdoRecord { event_time: 0, inhibit_time: 0, ..t };
        assert_eq!(PdoRecord::decode(&r.encode_rpdo()), r);
    }
}
