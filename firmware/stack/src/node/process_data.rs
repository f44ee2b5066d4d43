//! PDOs at run time: received PDOs written to the dictionary (at once or at SYNC), transmit
//! PDOs sent on SYNC, on RTR and on events, and the filter that keeps writes cheap.

use super::{Core, NodeEvent};
use crate::emcy::EmcyEvent;
use crate::od::{AppObjects, NodeDictionary, WriteSource};
use crate::pdo::Rpdo;
use crate::store::ParamStore;

impl<D: NodeDictionary, S: ParamStore, const P: usize> Core<D, S, P> {
    pub(super) fn on_rpdo(&mut self, i: usize, data: &[u8]) {
        let Some(r) = self.rpdos.get(i).copied() else { return };
        if data.len() < usize::from(r.mapping.len()) || r.mapping.is_empty() {
            // CiA 301: a PDO shorter than its mapping is not processed.
            self.rpdo_length_error = true;
            self.raise_event(EmcyEvent::RpdoLength);
            return;
        }
        // A PDO of the right length ends the length error.
        if core::mem::take(&mut self.rpdo_length_error) {
            self.clear_event(EmcyEvent::RpdoLength);
        }
        let now = self.now_us;
        if let Some(slot) = self.rpdos.get_mut(i)
            && slot.received(now)
        {
            self.clear_event(EmcyEvent::RpdoTimeout);
        }
        if r.comm.synchronous() {
            let mut buf = [0_u8; 8];
            let n = data.len().min(8);
            if let (Some(dst), Some(src)) = (buf.get_mut(..n), data.get(..n)) {
                dst.copy_from_slice(src);
            }
            if let Some(slot) = self.rpdos.get_mut(i) {
                slot.latched = Some((buf, n as u8));
            }
        } else {
            self.apply_rpdo(&r, data);
        }
    }

    /// Writes a received payload to the mapped objects. An entry the dictionary refuses (a
    /// value out of range) keeps its value; the others are written, with their side effects,
    /// and indicated one by one in mapping order (dummy entries write nothing).
    pub(super) fn apply_rpdo(&mut self, r: &Rpdo, data: &[u8]) {
        let entries = self.od.entries();
        let mut at = 0;
        for m in r.mapping.entries() {
            let end = at + usize::from(m.bytes());
            if let (Some(src), Some(info)) = (data.get(at..end), m.info(entries))
                && self.od.write_entry(info, m.index(info), m.sub, src).is_ok()
            {
                self.after_write(m.index(info), m.sub);
                self.od.app().written(m.index(info), m.sub, src, WriteSource::Rpdo);
            }
            at = end;
        }
        self.event(NodeEvent::RpdoReceived(r.offset));
    }

    pub(super) fn on_sync(&mut self, counter: Option<u8>) {
        for i in 0..self.rpdos.len() {
            let Some(r) = self.rpdos.get_mut(i) else { continue };
            if let Some((buf, n)) = r.latched.take() {
                let r = *r;
                self.apply_rpdo(&r, buf.get(..usize::from(n)).unwrap_or(&[]));
            }
        }
        let now = self.now_us;
        for i in 0..self.tpdos.len() {
            let Some(t) = self.tpdos.get_mut(i) else { continue };
            if !t.comm.valid() || !t.comm.synchronous() && t.comm.transmission_type != 252 {
                continue;
            }
            if t.comm.transmission_type == 252 {
                if let Ok(sample) = t.mapping.pack(&mut self.od) {
                    t.sampled = Some(sample);
                }
            } else if t.on_sync(counter) {
                self.send_tpdo(i, now);
            }
        }
    }

    pub(super) fn on_tpdo_rtr(&mut self, i: usize, now_us: u64) {
        let Some(t) = self.tpdos.get(i) else { return };
        if t.comm.transmission_type == 252 {
            if let Some((data, len)) = t.sampled {
                self.send_payload(t.comm.id(), data, len);
            }
        } else {
            self.send_tpdo(i, now_us);
        }
    }

    pub(super) fn send_tpdo(&mut self, i: usize, now_us: u64) {
        let Some(t) = self.tpdos.get_mut(i) else { return };
        let packed = t.mapping.pack(&mut self.od);
        t.sent(now_us);
        let id = t.comm.id();
        if let Ok((data, len)) = packed {
            self.send_payload(id, data, len);
        }
    }

    /// Marks every valid TPDO that maps `index`/`sub` (sent as its transmission type says).
    pub(super) fn trigger_mapped(&mut self, index: u16, sub: u8) {
        if self.tpdo_mapped & Self::filter_bit(index, sub) == 0 {
            return;
        }
        let entries = self.od.entries();
        for t in &mut self.tpdos {
            if t.comm.valid() && t.mapping.contains(entries, index, sub) {
                t.trigger();
            }
        }
    }

    /// The filter bit of one object; a set bit means "maybe mapped".
    pub(super) const fn filter_bit(index: u16, sub: u8) -> u64 {
        1 << ((index ^ index >> 6 ^ (sub as u16).wrapping_mul(7)) & 63)
    }

    pub(super) fn refresh_tpdo_filter(&mut self) {
        let entries = self.od.entries();
        self.tpdo_mapped = self
            .tpdos
            .iter()
            .filter(|t| t.comm.valid())
            .flat_map(|t| t.mapping.entries())
            .filter_map(|m| m.info(entries).map(|i| Self::filter_bit(m.index(i), m.sub)))
            .fold(0, |acc, bit| acc | bit);
    }
}
