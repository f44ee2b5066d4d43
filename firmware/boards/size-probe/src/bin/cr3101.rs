//! cr3101: what its generated code costs in flash (see `src/probe.rs`).
#![no_std]
#![no_main]

#[macro_use]
#[path = "../probe.rs"]
mod probe;

probe!(cr3101, 0x20);
