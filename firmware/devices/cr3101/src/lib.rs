//! The cr3101 device, generated from `spec/cr3101.yaml`: its dictionary, default PDOs, node
//! settings, serial codecs and app hooks. It runs as a plain CANopen node until its behaviour
//! is written.
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]

coforge_macros::device!("../../../spec/cr3101.yaml");
