//! The cr3101 device: its object dictionary tables and default PDOs, generated from
//! `spec/cr3101.yaml`. The device's behaviour comes with its own issue.
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]

coforge_macros::device!("../../../spec/cr3101.yaml");
