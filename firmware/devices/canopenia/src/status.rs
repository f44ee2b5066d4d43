//! NODESTATUS (manual section 9.3): the codes of 5F04h (every node the manager knows), and
//! what the manager's events mean in them. The NMT states have their heartbeat codes, so
//! 5F00h.02 (the coprocessor's own state) is `nmt::state_code`.

use coforge_stack::manager::ManagerEvent;
use coforge_stack::manager::monitor::{MonitorEvent, NodeState};
use coforge_stack::manager::scan::ScanEvent;

pub const BOOT: u8 = 0x00;
pub const STOPPED: u8 = 0x04;
pub const OPERATIONAL: u8 = 0x05;
pub const PREOP: u8 = 0x7F;
pub const EMCY_NEW: u8 = 0x80;
pub const EMCY_OVER: u8 = 0x81;
pub const HB_ACTIVE: u8 = 0x90;
pub const HB_LOST: u8 = 0x91;
pub const SCAN_STARTED: u8 = 0x9F;
pub const SCAN_COMPLETE: u8 = 0xA0;
pub const SCAN_ABORTED: u8 = 0xA8;
pub const RESET_APP: u8 = 0xB0;
pub const RESET_COM: u8 = 0xB1;

fn of_state(state: NodeState) -> Option<u8> {
    match state {
        NodeState::Unknown => None,
        NodeState::BootUp => Some(BOOT),
        NodeState::Stopped => Some(STOPPED),
        NodeState::Operational => Some(OPERATIONAL),
        NodeState::PreOperational => Some(PREOP),
    }
}

/// The node a manager event is about and the codes it records for it, in order: a first
/// heartbeat records the state it reports, then that monitoring runs (as the manual's example
/// output shows: "status changed to 0x05 - OPERATIONAL", then "0x90 - HB ACTIVE").
pub fn of_event(event: &ManagerEvent) -> Option<(u8, [Option<u8>; 2])> {
    let one = |node: u8, code: u8| Some((node, [Some(code), None]));
    match *event {
        ManagerEvent::Node(MonitorEvent::BootUp(node)) => one(node, BOOT),
        ManagerEvent::Node(MonitorEvent::HeartbeatStarted { node, state }) => Some((node, [of_state(state), Some(HB_ACTIVE)])),
        ManagerEvent::Node(MonitorEvent::StateChanged { node, to, .. }) => Some((node, [of_state(to), None])),
        ManagerEvent::Node(MonitorEvent::HeartbeatLost(node)) => one(node, HB_LOST),
        ManagerEvent::Node(MonitorEvent::Emergency { node, .. }) => one(node, EMCY_NEW),
        ManagerEvent::Node(MonitorEvent::EmergencyCleared { node, .. }) => one(node, EMCY_OVER),
        ManagerEvent::Scan(ScanEvent::Started(node)) => one(node, SCAN_STARTED),
        ManagerEvent::Scan(ScanEvent::Complete(node)) => one(node, SCAN_COMPLETE),
        ManagerEvent::Scan(ScanEvent::Aborted { node, .. }) => one(node, SCAN_ABORTED),
        ManagerEvent::Sdo(_) => None,
    }
}
