//! Node monitoring for a manager: boot-ups, heartbeats and emergencies of up to 127 nodes
//! (CiA 301 7.2.8.3.2, 7.2.7), each change as one [`MonitorEvent`], and a table holding each
//! node's last known state.
//!
//! A small engine like the slave's heartbeat consumer: [`Monitor::on_frame`] takes every
//! received frame and [`Monitor::check`] finds lost heartbeats. Times are kept in wrapping
//! 32-bit milliseconds (8 bytes a node, 1,016 for all 127), so heartbeat gaps up to 24 days
//! are judged right.
//!
//! Choices where CiA 301 leaves room:
//! - Monitoring of a node starts with its first heartbeat (boot-up is not a heartbeat), and
//!   only if its consumer time is not 0. A boot-up ends monitoring until the next heartbeat
//!   and forgets the node's active emergency.
//! - Heartbeat bytes other than 04h, 05h and 7Fh (bit 7, the guarding toggle, ignored) are
//!   not heartbeats and change nothing.
//! - An emergency frame must have CiA 301's 8 bytes; each is one event. Error code 0000h
//!   ("error reset or no error") is [`MonitorEvent::EmergencyCleared`]; a node's emergency is
//!   active from an error until an error reset with an error register of 0.

use crate::frame::CanFrame;
use crate::nmt::{self, NmtState};

/// How many nodes a network has.
pub const NODES: usize = 127;

/// A remote node's NMT state as its boot-up and heartbeats say.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NodeState {
    /// Nothing heard from the node yet.
    #[default]
    Unknown,
    /// It sent its boot-up message (it is pre-operational now, its heartbeat will say).
    BootUp,
    Stopped,
    Operational,
    PreOperational,
}

impl NodeState {
    /// The state of a boot-up or heartbeat byte; `None` if it is neither.
    pub const fn of_code(code: u8) -> Option<NodeState> {
        if code & 0x7F == 0 {
            return Some(NodeState::BootUp);
        }
        Some(match nmt::state_of_code(code) {
            Some(NmtState::Stopped) => NodeState::Stopped,
            Some(NmtState::Operational) => NodeState::Operational,
            Some(NmtState::PreOperational) => NodeState::PreOperational,
            None => return None,
        })
    }
}

/// Whether a node's heartbeat is watched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Heartbeat {
    /// No consumer time, or no heartbeat since the node booted.
    Unmonitored,
    Active,
    /// Lost, until the next heartbeat.
    Lost,
}

/// What the manager knows of one node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NodeStatus {
    pub state: NodeState,
    pub heartbeat: Heartbeat,
    /// The node reported an error and no error reset with error register 0 since.
    pub emergency_active: bool,
    /// Heartbeat consumer time (0: not monitored).
    pub consumer_ms: u16,
}

/// A change on the network.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MonitorEvent {
    BootUp(u8),
    /// The node's first heartbeat since it booted or was lost: monitoring runs.
    HeartbeatStarted {
        node: u8,
        state: NodeState,
    },
    /// A heartbeat reports another state than the previous one.
    StateChanged {
        node: u8,
        from: NodeState,
        to: NodeState,
    },
    HeartbeatLost(u8),
    /// An emergency frame with an error code other than 0000h.
    Emergency {
        node: u8,
        code: u16,
        register: u8,
        data: [u8; 5],
    },
    /// An error reset (code 0000h): one error has gone; `register` (1001h) says whether
    /// others remain.
    EmergencyCleared {
        node: u8,
        register: u8,
    },
}

const HB_ACTIVE: u8 = 0x01;
const HB_LOST: u8 = 0x02;
const EMCY_ACTIVE: u8 = 0x04;

#[derive(Debug, Clone, Copy)]
struct Slot {
    state: NodeState,
    flags: u8,
    consumer_ms: u16,
    /// When the last heartbeat came (wrapping ms).
    last_ms: u32,
}

const EMPTY: Slot = Slot { state: NodeState::Unknown, flags: 0, consumer_ms: 0, last_ms: 0 };

/// The table of all 127 nodes.
#[derive(Debug, Clone)]
pub struct Monitor {
    slots: [Slot; NODES],
    /// The earliest heartbeat deadline, if any node is monitored: `check` scans only then.
    next_due_ms: Option<u32>,
}

impl Default for Monitor {
    fn default() -> Self {
        Self::new()
    }
}

/// Wrapping milliseconds of a microsecond time.
fn ms(now_us: u64) -> u32 {
    crate::time::ms_of_us(now_us) as u32
}

/// Whether wrapping time `t` has reached `deadline` (within 24 days either way).
fn reached(t: u32, deadline: u32) -> bool {
    t.wrapping_sub(deadline) < 1 << 31
}

impl Monitor {
    pub const fn new() -> Self {
        Monitor { slots: [EMPTY; NODES], next_due_ms: None }
    }

    /// Sets the heartbeat consumer time of `node`, or of every node (`None`); 0 stops
    /// monitoring. Takes effect with the node's next heartbeat.
    pub fn set_consumer_ms(&mut self, node: Option<u8>, time_ms: u16) {
        match node {
            Some(node) => {
                if let Some(slot) = self.slot(node) {
                    slot.consumer_ms = time_ms;
                }
            }
            None => self.slots.iter_mut().for_each(|s| s.consumer_ms = time_ms),
        }
    }

    /// What is known of `node` (1..=127).
    pub fn status(&self, node: u8) -> Option<NodeStatus> {
        let slot = self.slots.get(usize::from(node).checked_sub(1)?)?;
        let heartbeat = match slot.flags & (HB_ACTIVE | HB_LOST) {
            HB_ACTIVE => Heartbeat::Active,
            HB_LOST => Heartbeat::Lost,
            _ => Heartbeat::Unmonitored,
        };
        Some(NodeStatus { state: slot.state, heartbeat, emergency_active: slot.flags & EMCY_ACTIVE != 0, consumer_ms: slot.consumer_ms })
    }

    fn slot(&mut self, node: u8) -> Option<&mut Slot> {
        self.slots.get_mut(usize::from(node).checked_sub(1)?)
    }

    /// A received frame: boot-up and heartbeat (700h + node), emergency (80h + node).
    pub fn on_frame(&mut self, frame: &CanFrame, now_us: u64) -> Option<MonitorEvent> {
        if frame.rtr {
            return None;
        }
        match frame.id {
            0x701..=0x77F => self.on_heartbeat((frame.id - 0x700) as u8, frame.payload(), ms(now_us)),
            0x081..=0x0FF => self.on_emergency((frame.id - 0x080) as u8, frame.payload()),
            _ => None,
        }
    }

    fn on_heartbeat(&mut self, node: u8, payload: &[u8], now_ms: u32) -> Option<MonitorEvent> {
        let [code] = *payload else { return None };
        let state = NodeState::of_code(code)?;
        let next_due = &mut self.next_due_ms;
        let slot = self.slots.get_mut(usize::from(node).checked_sub(1)?)?;
        let from = core::mem::replace(&mut slot.state, state);
        if state == NodeState::BootUp {
            slot.flags = 0;
            return Some(MonitorEvent::BootUp(node));
        }
        slot.last_ms = now_ms;
        if slot.consumer_ms == 0 {
            slot.flags &= !(HB_ACTIVE | HB_LOST);
        } else {
            let deadline = now_ms.wrapping_add(u32::from(slot.consumer_ms));
            if next_due.is_none_or(|due| reached(due, deadline)) {
                *next_due = Some(deadline);
            }
            if slot.flags & HB_ACTIVE == 0 {
                slot.flags = slot.flags & !HB_LOST | HB_ACTIVE;
                return Some(MonitorEvent::HeartbeatStarted { node, state });
            }
        }
        (from != state).then_some(MonitorEvent::StateChanged { node, from, to: state })
    }

    fn on_emergency(&mut self, node: u8, payload: &[u8]) -> Option<MonitorEvent> {
        let [c0, c1, register, d0, d1, d2, d3, d4] = *payload else { return None };
        let slot = self.slot(node)?;
        let code = u16::from_le_bytes([c0, c1]);
        // After an error reset the error register says whether errors remain.
        if code == 0 && register == 0 {
            slot.flags &= !EMCY_ACTIVE;
        } else {
            slot.flags |= EMCY_ACTIVE;
        }
        if code == 0 {
            return Some(MonitorEvent::EmergencyCleared { node, register });
        }
        Some(MonitorEvent::Emergency { node, code, register, data: [d0, d1, d2, d3, d4] })
    }

    /// The next heartbeat found lost at `now_us`; call until `None`.
    pub fn check(&mut self, now_us: u64) -> Option<MonitorEvent> {
        // Most polls: nothing monitored, or nothing due yet.
        let due = self.next_due_ms?;
        let now_ms = ms(now_us);
        if !reached(now_ms, due) {
            return None;
        }
        let mut next: Option<u32> = None;
        for (node, slot) in (1..).zip(self.slots.iter_mut()) {
            if slot.flags & HB_ACTIVE == 0 || slot.consumer_ms == 0 {
                continue;
            }
            let deadline = slot.last_ms.wrapping_add(u32::from(slot.consumer_ms));
            if reached(now_ms, deadline) {
                slot.flags = slot.flags & !HB_ACTIVE | HB_LOST;
                // Others may be due too: the next call scans again.
                return Some(MonitorEvent::HeartbeatLost(node));
            }
            if next.is_none_or(|n| reached(n, deadline)) {
                next = Some(deadline);
            }
        }
        self.next_due_ms = next;
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hb(node: u8, code: u8) -> CanFrame {
        CanFrame::data(0x700 + u16::from(node), &[code]).expect("a heartbeat")
    }

    fn emcy(node: u8, code: u16, register: u8) -> CanFrame {
        let [c0, c1] = code.to_le_bytes();
        CanFrame::data(0x080 + u16::from(node), &[c0, c1, register, 1, 2, 3, 4, 5]).expect("an emergency")
    }

    const MS: u64 = 1000;

    #[test]
    fn boot_up_heartbeats_and_loss() {
        let mut m = Monitor::new();
        m.set_consumer_ms(None, 300);
        assert_eq!(m.on_frame(&hb(3, 0x00), 0), Some(MonitorEvent::BootUp(3)));
        assert_eq!(m.status(3).map(|s| (s.state, s.heartbeat)), Some((NodeState::BootUp, Heartbeat::Unmonitored)));
        assert_eq!(m.check(10_000 * MS), None, "a boot-up starts no monitoring");
        assert_eq!(m.on_frame(&hb(3, 0x7F), 10_000 * MS), Some(MonitorEvent::HeartbeatStarted { node: 3, state: NodeState::PreOperational }));
        assert_eq!(m.on_frame(&hb(3, 0x7F), 10_200 * MS), None, "same state, no event");
        assert_eq!(
            m.on_frame(&hb(3, 0x05), 10_400 * MS),
            Some(MonitorEvent::StateChanged { node: 3, from: NodeState::PreOperational, to: NodeState::Operational })
        );
        assert_eq!(m.check(10_699 * MS), None);
        assert_eq!(m.check(10_700 * MS), Some(MonitorEvent::HeartbeatLost(3)), "lost when the consumer time has elapsed");
        assert_eq!(m.check(10_700 * MS), None, "once");
        assert_eq!(m.status(3).map(|s| s.heartbeat), Some(Heartbeat::Lost));
        assert_eq!(
            m.on_frame(&hb(3, 0x85), 11_000 * MS),
            Some(MonitorEvent::HeartbeatStarted { node: 3, state: NodeState::Operational }),
            "the guarding toggle bit is ignored"
        );
        assert_eq!(m.on_frame(&hb(3, 0x33), 11_100 * MS), None, "not a state");
        assert_eq!(m.on_frame(&hb(3, 0x05), 11_250 * MS), None);
        assert_eq!(m.check(11_500 * MS), None, "the invalid byte was no heartbeat, the last valid one was at 11,250 ms");
        assert_eq!(m.check(11_550 * MS), Some(MonitorEvent::HeartbeatLost(3)));
    }

    #[test]
    fn every_lost_node_is_reported_once() {
        let mut m = Monitor::new();
        m.set_consumer_ms(None, 100);
        m.set_consumer_ms(Some(9), 0);
        for node in 1..=127 {
            m.on_frame(&hb(node, 0x05), 0);
        }
        assert_eq!(m.status(9).map(|s| s.heartbeat), Some(Heartbeat::Unmonitored));
        m.on_frame(&hb(5, 0x05), 50 * MS);
        let mut lost: heapless::Vec<u8, 127> = heapless::Vec::new();
        while let Some(MonitorEvent::HeartbeatLost(n)) = m.check(100 * MS) {
            lost.push(n).expect("at most 127 nodes");
        }
        assert_eq!(lost.len(), 125, "all but node 5 (late) and node 9 (not monitored)");
        assert!(!lost.contains(&5) && !lost.contains(&9));
        assert_eq!(m.check(149 * MS), None);
        assert_eq!(m.check(150 * MS), Some(MonitorEvent::HeartbeatLost(5)));
    }

    #[test]
    fn heartbeats_survive_the_millisecond_clock_wrapping() {
        let mut m = Monitor::new();
        m.set_consumer_ms(Some(1), 500);
        let start = (u64::from(u32::MAX) - 200) * MS;
        m.on_frame(&hb(1, 0x05), start);
        assert_eq!(m.check(start + 499 * MS), None);
        assert_eq!(m.check(start + 500 * MS), Some(MonitorEvent::HeartbeatLost(1)));
    }

    #[test]
    fn emergencies_new_and_cleared() {
        let mut m = Monitor::new();
        assert_eq!(m.on_frame(&emcy(7, 0x8130, 0x11), 0), Some(MonitorEvent::Emergency { node: 7, code: 0x8130, register: 0x11, data: [1, 2, 3, 4, 5] }));
        assert!(m.status(7).is_some_and(|s| s.emergency_active));
        assert_eq!(m.on_frame(&emcy(7, 0x0000, 0x01), 0), Some(MonitorEvent::EmergencyCleared { node: 7, register: 0x01 }));
        assert!(m.status(7).is_some_and(|s| s.emergency_active), "an error remains");
        assert_eq!(m.on_frame(&emcy(7, 0x0000, 0), 0), Some(MonitorEvent::EmergencyCleared { node: 7, register: 0 }));
        assert!(m.status(7).is_some_and(|s| !s.emergency_active));
        let short = CanFrame::data(0x087, &[0x30, 0x81, 0x11]).expect("a frame");
        assert_eq!(m.on_frame(&short, 0), None, "an emergency has 8 bytes");
        assert_eq!(m.on_frame(&CanFrame::data(0x080, &[]).expect("SYNC"), 0), None, "SYNC is not node 0's emergency");
        assert_eq!(m.on_frame(&CanFrame::remote(0x707, 1).expect("a remote frame"), 0), None);
        // A boot-up forgets the active emergency.
        m.on_frame(&emcy(7, 0x5000, 1), 0);
        m.on_frame(&hb(7, 0), 0);
        assert!(m.status(7).is_some_and(|s| !s.emergency_active));
        assert_eq!(m.status(0), None);
        assert_eq!(m.status(128), None);
    }
}
