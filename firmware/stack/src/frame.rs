//! The CAN frame the stack exchanges with a board: 11-bit identifiers only (CiA 301's
//! predefined connection set), implementing [`embedded_can::Frame`] so a board converts it to
//! and from its driver's frame type with `Frame::new` / `Frame::new_remote`.

use embedded_can::{Id, StandardId};

/// A classic CAN data or remote frame with a standard identifier.
///
/// Word-aligned: its 12 bytes then copy as three words, where a 2-aligned frame costs a
/// `memcpy` call on Cortex-M (every queued and polled frame is copied).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(align(4))]
pub struct CanFrame {
    /// 11-bit identifier (COB-ID).
    pub id: u16,
    pub rtr: bool,
    /// Data length code, 0..=8 (for a remote frame, the requested length).
    pub dlc: u8,
    /// Payload; bytes from `dlc` on are zero.
    pub data: [u8; 8],
}

impl CanFrame {
    /// A data frame; `None` if `id` needs more than 11 bits or `data` more than 8 bytes.
    pub fn data(id: u16, data: &[u8]) -> Option<CanFrame> {
        if id > 0x7FF || data.len() > 8 {
            return None;
        }
        let mut bytes = [0; 8];
        bytes.get_mut(..data.len())?.copy_from_slice(data);
        Some(CanFrame { id, rtr: false, dlc: data.len() as u8, data: bytes })
    }

    /// A data frame of the first `len` bytes of `data` (the rest are cleared); `None` if `id`
    /// needs more than 11 bits or `len` is over 8. A fixed-size copy: what PDOs are built from.
    pub fn from_payload(id: u16, data: [u8; 8], len: u8) -> Option<CanFrame> {
        if id > 0x7FF || len > 8 {
            return None;
        }
        // The low `len` bytes of the little-endian word; a shift by 64 (len 0) keeps none.
        let keep = u64::MAX.checked_shr(8 * u32::from(8 - len)).unwrap_or(0);
        Some(CanFrame { id, rtr: false, dlc: len, data: (u64::from_le_bytes(data) & keep).to_le_bytes() })
    }

    /// A remote frame requesting `dlc` bytes.
    pub fn remote(id: u16, dlc: u8) -> Option<CanFrame> {
        (id <= 0x7FF && dlc <= 8).then_some(CanFrame { id, rtr: true, dlc, data: [0; 8] })
    }

    /// The first `dlc` bytes (empty for a remote frame).
    pub fn payload(&self) -> &[u8] {
        if self.rtr { &[] } else { self.data.get(..usize::from(self.dlc)).unwrap_or(&self.data) }
    }

    /// Converts any `embedded-can` frame; extended identifiers are not CANopen traffic.
    pub fn from_frame(frame: &impl embedded_can::Frame) -> Option<CanFrame> {
        let Id::Standard(id) = frame.id() else { return None };
        if frame.is_remote_frame() { CanFrame::remote(id.as_raw(), u8::try_from(frame.dlc()).ok()?) } else { CanFrame::data(id.as_raw(), frame.data()) }
    }
}

impl embedded_can::Frame for CanFrame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        match id.into() {
            Id::Standard(id) => CanFrame::data(id.as_raw(), data),
            Id::Extended(_) => None,
        }
    }

    fn new_remote(id: impl Into<Id>, dlc: usize) -> Option<Self> {
        match id.into() {
            Id::Standard(id) => CanFrame::remote(id.as_raw(), u8::try_from(dlc).ok()?),
            Id::Extended(_) => None,
        }
    }

    fn is_extended(&self) -> bool {
        false
    }

    fn is_remote_frame(&self) -> bool {
        self.rtr
    }

    fn id(&self) -> Id {
        // `id` is at most 0x7FF by construction; the fallback is unreachable.
        Id::Standard(StandardId::new(self.id).unwrap_or(StandardId::ZERO))
    }

    fn dlc(&self) -> usize {
        usize::from(self.dlc)
    }

    fn data(&self) -> &[u8] {
        self.payload()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_can::Frame as _;

    #[test]
    fn a_payload_frame_is_the_data_frame_of_its_prefix() {
        let bytes = [1, 2, 3, 4, 5, 6, 7, 8];
        for len in 0..=8_u8 {
            let f = CanFrame::from_payload(0x181, bytes, len).unwrap();
            assert_eq!(Some(f), CanFrame::data(0x181, &bytes[..usize::from(len)]), "len {len}");
        }
        assert_eq!(CanFrame::from_payload(0x181, bytes, 9), None);
        assert_eq!(CanFrame::from_payload(0x800, bytes, 1), None);
    }

    #[test]
    fn frames_keep_only_what_a_can_frame_can_carry() {
        let f = CanFrame::data(0x601, &[0x40, 0x00, 0x10, 0x00]).unwrap();
        assert_eq!((f.dlc, f.payload()), (4, &[0x40, 0x00, 0x10, 0x00][..]));
        assert_eq!(f.data[4..], [0; 4]);
        assert_eq!(CanFrame::data(0x800, &[]), None);
        assert_eq!(CanFrame::data(0x100, &[0; 9]), None);
        let r = CanFrame::remote(0x705, 1).unwrap();
        assert!(r.is_remote_frame());
        assert_eq!(r.payload(), &[] as &[u8]);
        assert_eq!(CanFrame::remote(0x705, 9), None);
        let ext = embedded_can::ExtendedId::new(0x1234).unwrap();
        assert_eq!(CanFrame::new(ext, &[1]), None);
        let round = CanFrame::from_frame(&f).unwrap();
        assert_eq!(round, f);
        assert_eq!(round.id(), Id::Standard(StandardId::new(0x601).unwrap()));
    }
}
