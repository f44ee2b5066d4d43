//! The cr3101 device, generated from `spec/cr3101.yaml`: its dictionary, default PDOs, node
//! settings, serial codecs and app hooks. It runs as a plain CANopen node until its behaviour
//! is written; [`card`] is the memory card that behaviour logs to, [`logger`] the model of its
//! configuration.
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]
#![cfg_attr(test, allow(clippy::indexing_slicing, clippy::unwrap_used))]

coforge_macros::device!("../../../spec/cr3101.yaml");

pub mod card;
pub mod clock;
pub mod logger;
