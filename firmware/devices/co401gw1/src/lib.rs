//! The co401gw1 device: its object dictionary tables and default PDOs, generated from
//! `spec/co401gw1.yaml`. The device's behaviour comes with its own issue.
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]

coforge_macros::device!("../../../spec/co401gw1.yaml");

/// The CANopen node's settings beyond CiA 301: the frenzel+berg bus-off restart time (2180h),
/// boot-up message switch (2110h), and no RPDO deadline monitoring (erratum GW1-13: a DS301
/// 4.0 device, the RPDO event timer has no function).
pub const fn node_config(node_id: u8) -> coforge_stack::node::NodeConfig {
    coforge_stack::node::NodeConfig {
        restart_time_object: Some(0x2180),
        bootup_object: Some(0x2110),
        rpdo_deadlines: false,
        ..coforge_stack::node::NodeConfig::new(node_id)
    }
}
