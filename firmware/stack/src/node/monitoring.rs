//! Communication services the node configures from its dictionary (SYNC, EMCY, guarding,
//! heartbeat, PDO slots) and the monitors that run on them: guarding requests, the SYNC
//! cycle, RPDO deadlines.

use super::{Core, read_u32};
use crate::emcy::EmcyEvent;
use crate::heartbeat::Consumer;
use crate::nmt;
use crate::od::NodeDictionary;
use crate::pdo::{Dir, Rpdo, Tpdo};
use crate::store::ParamStore;
use heapless::Vec;

impl<D: NodeDictionary, S: ParamStore, const P: usize> Core<D, S, P> {
    pub(super) fn on_guard_request(&mut self, now_us: u64) {
        // CiA 301: a node with a heartbeat producer time does not answer guarding.
        if self.heartbeat.period_ms() != 0 {
            return;
        }
        let (byte, warned, lost) = self.guarding.on_request(nmt::state_code(self.state), now_us);
        self.send(self.guard_cob, &[byte]);
        if warned {
            self.clear_event(EmcyEvent::GuardingWarning);
        }
        if lost {
            self.clear_event(EmcyEvent::LifeGuarding);
        }
    }

    /// SYNC cycle (1006h) and RPDO deadline monitoring.
    pub(super) fn check_deadlines(&mut self, now_us: u64) {
        let period = u64::from(self.sync_period_us);
        if D::COMM.sync_cycle
            && period != 0
            && nmt::allows_emcy_and_sync(self.state)
            && !self.sync_lost
            // Before the first SYNC, `last_sync_us` is NEVER and the difference 0.
            && now_us.saturating_sub(self.last_sync_us) > period + period / 2
        {
            // Reported once; the next SYNC ends it.
            self.sync_lost = true;
            self.raise_event(EmcyEvent::SyncTimeout);
        }
        if self.cfg.rpdo_deadlines && nmt::allows_pdo(self.state) {
            // Every RPDO records its own timeout; one emergency covers them all.
            let mut overdue = false;
            for r in &mut self.rpdos {
                overdue |= r.overdue(now_us);
            }
            if overdue {
                self.raise_event(EmcyEvent::RpdoTimeout);
            }
        }
    }

    /// Re-reads every communication parameter the engines cache.
    pub(super) fn reload_all(&mut self, now_us: u64) {
        self.reload_services(now_us);
        self.rpdos.clear();
        self.tpdos.clear();
        // Every PDO communication object with a COB-ID (sub 1), in index order.
        let entries = self.od.entries();
        for e in entries.iter().filter(|e| e.covers(1)) {
            match Dir::of_index(e.index) {
                Some((Dir::Rx, false, offset)) if self.rpdos.len() < P => {
                    let r = Rpdo::load(&mut self.od, offset);
                    let _ = self.rpdos.push(r);
                }
                Some((Dir::Tx, false, offset)) if self.tpdos.len() < P => {
                    let t = Tpdo::load(&mut self.od, offset, now_us);
                    let _ = self.tpdos.push(t);
                }
                _ => {}
            }
        }
        self.refresh_tpdo_filter();
    }

    /// SYNC, EMCY, heartbeat, guarding and consumer parameters.
    pub(super) fn reload_services(&mut self, now_us: u64) {
        self.reload_sync();
        self.reload_emcy();
        self.reload_guarding();
        self.reload_heartbeat(now_us);
        self.reload_consumer();
    }

    pub(super) fn reload_sync(&mut self) {
        self.sync_cob = read_u32(&mut self.od, 0x1005, 0).map(|c| (c & 0x7FF) as u16).or(Some(0x080));
        self.sync_period_us = if D::COMM.sync_cycle { read_u32(&mut self.od, 0x1006, 0).unwrap_or(0) } else { 0 };
    }

    pub(super) fn reload_emcy(&mut self) {
        self.emcy_cob = match read_u32(&mut self.od, 0x1014, 0) {
            Some(c) if c & crate::pdo::COB_INVALID != 0 => None,
            Some(c) => Some((c & 0x7FF) as u16),
            None => Some(0x080 + u16::from(self.node_id)),
        };
        self.emcy_inhibit = read_u32(&mut self.od, 0x1015, 0).unwrap_or(0) as u16;
    }

    pub(super) fn reload_guarding(&mut self) {
        self.guard_cob = read_u32(&mut self.od, 0x100E, 0).map_or(0x700 + u16::from(self.node_id), |c| (c & 0x7FF) as u16);
        let guard_ms = read_u32(&mut self.od, 0x100C, 0).unwrap_or(0) as u16;
        let factor = read_u32(&mut self.od, 0x100D, 0).unwrap_or(0) as u8;
        self.guarding.configure(guard_ms, factor);
    }

    pub(super) fn reload_heartbeat(&mut self, now_us: u64) {
        let period = read_u32(&mut self.od, 0x1017, 0).unwrap_or(0) as u16;
        if period != self.heartbeat.period_ms() {
            self.heartbeat.configure(period, now_us);
        }
    }

    pub(super) fn reload_consumer(&mut self) {
        if !D::COMM.heartbeat_consumer {
            return;
        }
        let count = read_u32(&mut self.od, 0x1016, 0).unwrap_or(0).min(127) as u8;
        let od = &mut self.od;
        let entries = (1..=count).map(|sub| read_u32(od, 0x1016, sub).unwrap_or(0));
        let mut list: Vec<u32, { crate::heartbeat::MAX_CONSUMED }> = Vec::new();
        for e in entries.filter(|&e| Consumer::decode(e).is_some()) {
            let _ = list.push(e);
        }
        self.consumer.configure(list.into_iter());
    }
}
