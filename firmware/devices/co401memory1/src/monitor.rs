//! The CAN monitoring channel. Its identifier is RPDO2's COB-ID (1401h.1), which the serial
//! host sets with Setup CAN Monitoring; every data frame on it is captured whole (0..8 bytes,
//! erratum MEM-36), copied into 5E00h, and held for Read Received CAN Data until the host
//! reads it.

/// The identifier RPDO2's COB-ID selects for monitoring, if it is valid (bit 31 clear).
pub fn monitored_id(cob_id: u32) -> Option<u16> {
    if cob_id & 0x8000_0000 != 0 {
        return None;
    }
    u16::try_from(cob_id & 0x7FF).ok().filter(|&id| id != 0)
}

/// The last frame seen on the monitored identifier.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Monitor {
    data: [u8; 8],
    len: usize,
    /// A frame the host has not read yet (STATE4#, 2105h bit 4).
    fresh: bool,
}

impl Monitor {
    pub fn capture(&mut self, payload: &[u8]) {
        let n = payload.len().min(8);
        if let (Some(dst), Some(src)) = (self.data.get_mut(..n), payload.get(..n)) {
            dst.copy_from_slice(src);
        }
        self.len = n;
        self.fresh = true;
    }

    /// The unread frame's data, marking it read.
    pub fn take(&mut self) -> Option<&[u8]> {
        if !core::mem::replace(&mut self.fresh, false) {
            return None;
        }
        self.data.get(..self.len)
    }

    pub fn is_fresh(&self) -> bool {
        self.fresh
    }

    /// Monitoring stopped: nothing unread remains.
    pub fn stop(&mut self) {
        self.fresh = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_is_read_once() {
        let mut m = Monitor::default();
        assert_eq!(m.take(), None);
        m.capture(&[0xB1, 0xB2]);
        assert!(m.is_fresh());
        assert_eq!(m.take(), Some(&[0xB1, 0xB2][..]));
        assert_eq!(m.take(), None);
        assert_eq!(monitored_id(0x123), Some(0x123));
        assert_eq!(monitored_id(0x8000_0123), None);
        assert_eq!(monitored_id(0), None);
    }
}
