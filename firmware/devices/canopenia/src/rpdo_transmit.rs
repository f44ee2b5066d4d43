//! "RPDO transmit all" (manual chapter 5, 5F01h.04 bit 3): the host's writes to entries a
//! scanned node maps into one of its RPDOs are collected in that PDO's data and sent as the
//! PDO, not as SDO downloads. A small engine: [`RpdoTransmit::on_host_write`] and
//! [`RpdoTransmit::forget`] are its inputs, [`RpdoTransmit::check`] says which PDO is due.
//!
//! - A PDO is sent only once every entry it maps was written at least once (no uninitialised
//!   data reaches a device).
//! - With the default event time 5F01h.08 zero, a PDO goes out when the update time 5F01h.07
//!   has passed since the host's last write to it (five times as long before its first
//!   transmission), or at once when the host writes its last mapped entry; the default inhibit
//!   time 5F01h.09 keeps transmissions of one PDO that far apart.
//! - With a non-zero event time the PDO goes out every event time, written or not, and the
//!   update time is not used (section 9.2, erratum COIA-22).

use coforge_stack::frame::CanFrame;
use coforge_stack::manager::scan::Scanned;

/// Which PDOs the engine keeps: as many as the manager's cached scans hold.
const SLOTS: usize = crate::device::SCANS * crate::device::SCAN_PDOS;
/// The update time counts 5 times before a PDO's first transmission (chapter 5).
const FIRST_USE: u64 = 5;

/// The manager's default PDO times (5F01h.07..09).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Times {
    /// 5F01h.07, in ms (erratum COIA-66).
    pub update_ms: u8,
    /// 5F01h.08, in ms.
    pub event_ms: u16,
    /// 5F01h.09, in 100 us.
    pub inhibit_100us: u16,
}

/// A host write the engine could not take.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// The value's length is not the mapped entry's.
    Length,
}

/// One RPDO of a scanned node, as the host has written it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Outgoing {
    node: u8,
    /// Its place among the node's scanned RPDOs.
    pdo: u8,
    cob: u16,
    data: [u8; 8],
    len: u8,
    /// Bit k: mapping entry k was written; `all` when every one was.
    written: u8,
    all: u8,
    sent_once: bool,
    /// When a host-triggered transmission is due.
    due_us: Option<u64>,
    last_sent_us: Option<u64>,
}

#[derive(Debug)]
pub struct RpdoTransmit {
    slots: [Option<Outgoing>; SLOTS],
}

impl Default for RpdoTransmit {
    fn default() -> Self {
        RpdoTransmit { slots: [None; SLOTS] }
    }
}

/// Where entry (`index`, `sub`) lies in `mapping`: its place, bit offset and size in bits.
fn locate(mapping: &[u32], index: u16, sub: u8) -> Option<(usize, u32, u32)> {
    let mut at = 0;
    for (k, &m) in mapping.iter().enumerate() {
        let bits = m & 0xFF;
        if (m >> 16) as u16 == index && (m >> 8) as u8 == sub {
            return Some((k, at, bits));
        }
        at += bits;
    }
    None
}

impl RpdoTransmit {
    /// The host writes `data` to (`index`, `sub`) of `scan`'s node: `Ok(true)` if an RPDO of
    /// the node maps the entry and the value went into it, `Ok(false)` if none does (an SDO
    /// download is the way).
    pub fn on_host_write<const P: usize>(&mut self, scan: &Scanned<P>, index: u16, sub: u8, data: &[u8], times: Times, now_us: u64) -> Result<bool, Refusal> {
        let found = scan.rpdos.iter().enumerate().find_map(|(p, info)| {
            let (k, at, bits) = locate(info.mapping(), index, sub).filter(|_| info.is_valid())?;
            Some((p, info, k, at, bits))
        });
        let Some((p, info, k, at, bits)) = found else { return Ok(false) };
        // Whole bytes only (what the host protocol carries), inside 8 bytes.
        let total: u32 = info.mapping().iter().map(|m| m & 0xFF).sum();
        if bits % 8 != 0 || at % 8 != 0 || data.len() as u32 * 8 != bits || total > 64 {
            return Err(Refusal::Length);
        }
        let Some(slot) = self.slot(scan.node, p as u8, info.cob_id as u16 & 0x7FF, info.mapping().len(), total) else { return Ok(false) };
        let start = (at / 8) as usize;
        if let Some(dst) = slot.data.get_mut(start..start + data.len()) {
            dst.copy_from_slice(data);
        }
        slot.written |= 1 << k;
        let last = k + 1 == info.mapping().len();
        let update = u64::from(times.update_ms) * 1000 * if slot.sent_once { 1 } else { FIRST_USE };
        slot.due_us = Some(if last { now_us } else { now_us + update });
        Ok(true)
    }

    /// The slot of `node`'s RPDO `pdo`, made if it is new (`None`: every slot is taken).
    fn slot(&mut self, node: u8, pdo: u8, cob: u16, entries: usize, bits: u32) -> Option<&mut Outgoing> {
        let at = self.slots.iter().position(|s| s.is_some_and(|s| s.node == node && s.pdo == pdo)).or_else(|| self.slots.iter().position(Option::is_none))?;
        let slot = self.slots.get_mut(at)?;
        let all = (1_u16 << entries.min(8)).wrapping_sub(1) as u8;
        let len = bits.div_ceil(8) as u8;
        let fresh = Outgoing { node, pdo, cob, data: [0; 8], len, written: 0, all, sent_once: false, due_us: None, last_sent_us: None };
        slot.get_or_insert(fresh);
        slot.as_mut()
    }

    /// `node` was scanned again or booted: what the host wrote for it is void.
    pub fn forget(&mut self, node: u8) {
        for slot in &mut self.slots {
            if slot.is_some_and(|s| s.node == node) {
                *slot = None;
            }
        }
    }

    /// The next PDO due at `now_us`, if any.
    pub fn check(&mut self, times: Times, now_us: u64) -> Option<CanFrame> {
        let inhibit_us = u64::from(times.inhibit_100us) * 100;
        let event_us = u64::from(times.event_ms) * 1000;
        for slot in self.slots.iter_mut().flatten() {
            if slot.written != slot.all {
                continue;
            }
            let since_sent = slot.last_sent_us.map(|t| now_us.saturating_sub(t));
            let due = if event_us != 0 {
                since_sent.is_none_or(|s| s >= event_us)
            } else {
                slot.due_us.is_some_and(|d| d <= now_us) && since_sent.is_none_or(|s| s >= inhibit_us)
            };
            if due {
                slot.due_us = None;
                slot.last_sent_us = Some(now_us);
                slot.sent_once = true;
                return CanFrame::data(slot.cob, slot.data.get(..usize::from(slot.len)).unwrap_or(&[]));
            }
        }
        None
    }
}
