//! The canopenia device: its object dictionary tables and default PDOs, generated from
//! `spec/canopenia.yaml`. The device's behaviour comes with its own issue.
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]

coforge_macros::device!("../../../spec/canopenia.yaml");

/// The CANopen node's settings: plain CiA 301.
pub const fn node_config(node_id: u8) -> coforge_stack::node::NodeConfig {
    coforge_stack::node::NodeConfig::new(node_id)
}
