//! NMT slave (CiA 301 7.2.8.3): the module control commands and the state codes that boot-up,
//! heartbeat and node guarding report.

pub use coforge_types::NmtState;

/// COB-ID of NMT module control.
pub const NMT_COB_ID: u16 = 0x000;

/// A module control command addressed to this node (or to all nodes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NmtCommand {
    Start,
    Stop,
    EnterPreOperational,
    ResetNode,
    ResetCommunication,
}

impl NmtCommand {
    /// Parses an NMT frame payload `[command, node-ID]`; `None` if it is not for `node_id`
    /// (node-ID 0 addresses every node) or is not a valid command.
    pub fn parse(payload: &[u8], node_id: u8) -> Option<NmtCommand> {
        addressed(payload, node_id).and_then(NmtCommand::from_code)
    }

    /// The command of a command specifier; `None` for a specifier CiA 301 does not define.
    pub const fn from_code(cs: u8) -> Option<NmtCommand> {
        Some(match cs {
            0x01 => NmtCommand::Start,
            0x02 => NmtCommand::Stop,
            0x80 => NmtCommand::EnterPreOperational,
            0x81 => NmtCommand::ResetNode,
            0x82 => NmtCommand::ResetCommunication,
            _ => return None,
        })
    }

    pub const fn code(self) -> u8 {
        match self {
            NmtCommand::Start => 0x01,
            NmtCommand::Stop => 0x02,
            NmtCommand::EnterPreOperational => 0x80,
            NmtCommand::ResetNode => 0x81,
            NmtCommand::ResetCommunication => 0x82,
        }
    }
}

/// The command specifier of an NMT frame payload `[command, node-ID]` addressed to `node_id`
/// or to every node (node-ID 0), whether CiA 301 defines the command or not; `None` if the
/// payload is not 2 bytes or addresses another node.
pub fn addressed(payload: &[u8], node_id: u8) -> Option<u8> {
    let [cs, target] = *payload else { return None };
    (target == 0 || target == node_id).then_some(cs)
}

/// The state byte of heartbeat and guarding answers (boot-up is 0).
pub const fn state_code(state: NmtState) -> u8 {
    match state {
        NmtState::Stopped => 0x04,
        NmtState::Operational => 0x05,
        NmtState::PreOperational => 0x7F,
    }
}

/// The state a heartbeat or guarding byte reports; `None` for boot-up and unknown values.
pub const fn state_of_code(code: u8) -> Option<NmtState> {
    match code & 0x7F {
        0x04 => Some(NmtState::Stopped),
        0x05 => Some(NmtState::Operational),
        0x7F => Some(NmtState::PreOperational),
        _ => None,
    }
}

/// Which services a state allows (CiA 301 table 88).
pub const fn allows_sdo(state: NmtState) -> bool {
    !matches!(state, NmtState::Stopped)
}

pub const fn allows_pdo(state: NmtState) -> bool {
    matches!(state, NmtState::Operational)
}

pub const fn allows_emcy_and_sync(state: NmtState) -> bool {
    !matches!(state, NmtState::Stopped)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_address_this_node_or_all() {
        assert_eq!(NmtCommand::parse(&[0x01, 5], 5), Some(NmtCommand::Start));
        assert_eq!(NmtCommand::parse(&[0x81, 0], 5), Some(NmtCommand::ResetNode));
        assert_eq!(NmtCommand::parse(&[0x01, 6], 5), None);
        assert_eq!(NmtCommand::parse(&[0x03, 5], 5), None);
        assert_eq!(NmtCommand::parse(&[0x01], 5), None);
        assert_eq!(NmtCommand::parse(&[0x01, 5, 0], 5), None, "NMT frames are exactly 2 bytes");
        assert_eq!(addressed(&[0x03, 5], 5), Some(0x03), "an undefined command is still addressed to the node");
        assert_eq!(addressed(&[0x81, 0], 5), Some(0x81));
        assert_eq!(addressed(&[0x01, 6], 5), None);
        assert_eq!(addressed(&[0x01], 5), None);
        for c in [NmtCommand::Start, NmtCommand::Stop, NmtCommand::EnterPreOperational, NmtCommand::ResetNode, NmtCommand::ResetCommunication] {
            assert_eq!(NmtCommand::parse(&[c.code(), 0], 1), Some(c));
        }
    }

    #[test]
    fn state_codes_round_trip() {
        for s in [NmtState::Stopped, NmtState::Operational, NmtState::PreOperational] {
            assert_eq!(state_of_code(state_code(s)), Some(s));
            assert_eq!(state_of_code(state_code(s) | 0x80), Some(s), "guarding toggle bit ignored");
        }
        assert_eq!(state_of_code(0), None);
        assert!(!allows_pdo(NmtState::PreOperational) && allows_pdo(NmtState::Operational));
        assert!(!allows_sdo(NmtState::Stopped));
    }
}
