//! How a device's node differs from a plain CiA 301 slave: the spec's `node:` section,
//! which the generated `node_config` turns into this.

/// How a device's node differs from a plain CiA 301 slave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NodeConfig {
    /// 1..=127.
    pub node_id: u8,
    /// SDO server timeout.
    pub sdo_timeout_us: u64,
    /// An object whose value 1 makes the node enter Operational by itself after boot-up
    /// (CR3101 20F4h "CANopen StartUp mode").
    pub startup_object: Option<u16>,
    /// Save every persistent entry as soon as it is written (CR3101: "all parameters are
    /// saved automatically").
    pub auto_save: bool,
    /// An object holding the bus-off restart time in ms, 0 = no automatic restart
    /// (frenzel+berg 2180h "CAN Restart Time").
    pub restart_time_object: Option<u16>,
    /// An object whose value 0 suppresses the boot-up message (frenzel+berg 2110h).
    pub bootup_object: Option<u16>,
    /// Emergency bytes 3..7 carry the OR of every active error's manufacturer bytes.
    pub combine_emcy_codes: bool,
    /// An RPDO's event timer (14xxh.5) is a deadline monitor (CiA 301 4.2, EMCY 8250h). Off
    /// for DS301 4.0 devices, where the entry exists but has no function for RPDOs.
    pub rpdo_deadlines: bool,
    /// A stack event (CAN warning or passive, RPDO length, SYNC or RPDO timeout, guarding,
    /// heartbeat) sends only the emergency the spec lists for it: without one, no EMCY frame
    /// and no error-register bit, though a communication error still gets its 1029h reaction.
    pub listed_emergencies_only: bool,
    /// A write of an entry that a valid TPDO maps triggers that TPDO (CiA 301), whoever
    /// writes (SDO, RPDO, device, host). Off where the device decides when its TPDOs go out
    /// (DS401 input rules), through [`Node::trigger_mapped`](crate::node::Node::trigger_mapped).
    pub tpdo_on_write: bool,
    /// An object whose value 0 refuses every write of a PDO mapping (16xxh, 1Axxh), from any
    /// side, with SDO abort 0800 0021h (CO401GW1 2102h "Remapping Enabled Info").
    pub remapping_object: Option<u16>,
}

impl NodeConfig {
    pub const fn new(node_id: u8) -> Self {
        NodeConfig {
            node_id,
            sdo_timeout_us: 1_000_000,
            startup_object: None,
            auto_save: false,
            restart_time_object: None,
            bootup_object: None,
            combine_emcy_codes: false,
            rpdo_deadlines: true,
            listed_emergencies_only: false,
            tpdo_on_write: true,
            remapping_object: None,
        }
    }
}
