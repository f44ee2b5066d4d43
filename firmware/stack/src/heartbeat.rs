//! Heartbeat producer (1017h) and consumer (1016h), CiA 301 7.2.8.3.2.2.

use crate::nmt::{NmtState, state_of_code};
use heapless::Vec;

/// Sends the node's state every producer period.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Producer {
    period_ms: u16,
    next_us: Option<u64>,
}

impl Producer {
    /// A new period (a 1017h write, or a reset); the first heartbeat follows one period later.
    pub fn configure(&mut self, period_ms: u16, now_us: u64) {
        self.period_ms = period_ms;
        self.next_us = (period_ms != 0).then(|| crate::time::later_us(now_us, period_ms.into(), 1000));
    }

    pub const fn period_ms(&self) -> u16 {
        self.period_ms
    }

    /// Whether a heartbeat is due now; schedules the next one if so.
    pub fn due(&mut self, now_us: u64) -> bool {
        match self.next_us {
            Some(t) if now_us >= t => {
                // Keep the period stable even if polled late, but never burst to catch up.
                let next = crate::time::later_us(t, self.period_ms.into(), 1000);
                self.next_us = Some(if next > now_us { next } else { crate::time::later_us(now_us, self.period_ms.into(), 1000) });
                true
            }
            _ => false,
        }
    }
}

/// How many producers one node can monitor at once.
pub const MAX_CONSUMED: usize = 8;

/// One monitored producer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Monitored {
    pub node_id: u8,
    pub time_ms: u16,
    /// Monitoring starts with the first heartbeat received (CiA 301).
    pub last_us: Option<u64>,
    pub state: Option<NmtState>,
    pub lost: bool,
}

/// What a heartbeat or a timeout changed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConsumerEvent {
    /// The producer's heartbeat did not come in time.
    Lost(u8),
    /// A lost producer is back.
    Recovered(u8),
}

/// The heartbeat consumer.
#[derive(Debug, Clone, Default)]
pub struct Consumer {
    monitored: Vec<Monitored, MAX_CONSUMED>,
}

impl Consumer {
    /// Decodes a 1016h entry: `(node-ID, time in ms)`; `None` if unused.
    pub const fn decode(entry: u32) -> Option<(u8, u16)> {
        let node = (entry >> 16) as u8;
        let time = entry as u16;
        if node == 0 || node > 127 || time == 0 { None } else { Some((node, time)) }
    }

    /// Replaces the monitored set; `false` if it has more entries than [`MAX_CONSUMED`].
    pub fn configure(&mut self, entries: impl Iterator<Item = u32>) -> bool {
        self.monitored.clear();
        for (node_id, time_ms) in entries.filter_map(Consumer::decode) {
            if self.monitored.push(Monitored { node_id, time_ms, last_us: None, state: None, lost: false }).is_err() {
                return false;
            }
        }
        true
    }

    pub fn monitored(&self) -> &[Monitored] {
        &self.monitored
    }

    /// A heartbeat (or boot-up) from `node_id`.
    pub fn on_heartbeat(&mut self, node_id: u8, code: u8, now_us: u64) -> Option<ConsumerEvent> {
        let m = self.monitored.iter_mut().find(|m| m.node_id == node_id)?;
        m.last_us = Some(now_us);
        m.state = state_of_code(code);
        if core::mem::take(&mut m.lost) { Some(ConsumerEvent::Recovered(node_id)) } else { None }
    }

    /// The first producer whose heartbeat is overdue (each loss is reported once).
    pub fn check(&mut self, now_us: u64) -> Option<ConsumerEvent> {
        let m = self.monitored.iter_mut().find(|m| !m.lost && m.last_us.is_some_and(|t| now_us.saturating_sub(t) > u64::from(m.time_ms) * 1000))?;
        m.lost = true;
        Some(ConsumerEvent::Lost(m.node_id))
    }

    /// Whether any monitored producer is lost (for the error LED).
    pub fn any_lost(&self) -> bool {
        self.monitored.iter().any(|m| m.lost)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn producer_sends_every_period() {
        let mut p = Producer::default();
        p.configure(100, 0);
        assert!(!p.due(99_999));
        assert!(p.due(100_000));
        assert!(!p.due(150_000));
        assert!(p.due(230_000), "late poll still sends");
        assert!(!p.due(299_999));
        assert!(p.due(300_000), "period stays on its grid");
        p.configure(0, 300_000);
        assert!(!p.due(10_000_000));
    }

    #[test]
    fn consumer_reports_loss_once_and_recovery() {
        let mut c = Consumer::default();
        assert!(c.configure([0x0005_0064, 0, 0x0080_0010].into_iter()), "node 128 is not a node");
        assert_eq!(c.monitored().len(), 1);
        assert_eq!(c.check(1_000_000_000), None, "monitoring starts with the first heartbeat");
        assert_eq!(c.on_heartbeat(5, 0x05, 0), None);
        assert_eq!(c.check(100_000), None);
        assert_eq!(c.check(100_001), Some(ConsumerEvent::Lost(5)));
        assert_eq!(c.check(200_000), None, "reported once");
        assert!(c.any_lost());
        assert_eq!(c.on_heartbeat(5, 0x7F, 200_000), Some(ConsumerEvent::Recovered(5)));
        assert_eq!(c.monitored()[0].state, Some(NmtState::PreOperational));
        assert!(!c.configure((0..9).map(|n| (n + 1) << 16 | 100)));
    }
}
