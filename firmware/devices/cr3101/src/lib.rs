//! The cr3101 device: its object dictionary tables and default PDOs, generated from
//! `spec/cr3101.yaml`. The device's behaviour comes with its own issue.
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]

coforge_macros::device!("../../../spec/cr3101.yaml");

/// The CANopen node's settings beyond CiA 301: start-up mode 20F4h, and every parameter
/// saved as soon as it is written ("saved automatically").
pub const fn node_config(node_id: u8) -> coforge_stack::node::NodeConfig {
    coforge_stack::node::NodeConfig { startup_object: Some(0x20F4), auto_save: true, ..coforge_stack::node::NodeConfig::new(node_id) }
}
