//! The co401gw1 device, generated from `spec/co401gw1.yaml`: its dictionary, default PDOs, node
//! settings, serial codecs and app hooks. It runs as a plain CANopen node until its behaviour
//! is written.
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]

coforge_macros::device!("../../../spec/co401gw1.yaml");
