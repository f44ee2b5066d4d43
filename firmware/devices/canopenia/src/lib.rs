//! The CANopenIA coprocessor (`spec/canopenia.yaml`): a CANopen node and a minimal manager
//! that a host drives over a serial line with ESAcademy's remote-access protocol.
//!
//! - [`host`]: the host's commands as requests, and the start byte each answer copies;
//! - [`errors`]: the error-code bits of every local refusal and remote result;
//! - [`objects`]: the coprocessor's own dictionary hooks: program data, writes to act on;
//! - [`status`]: NODESTATUS, the codes of 5F04h;
//! - [`cache`]: remote reads answered from the manager's scans;
//! - [`rpdo_transmit`]: host writes to scanned nodes' RPDO entries sent as those PDOs;
//! - [`config`]: configuration loading: 1F50h/1F51h, the two slots, checking and applying a binary EDS;
//! - [`device`]: the whole coprocessor, driven by CAN frames, serial bytes and time.
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]
#![cfg_attr(test, allow(clippy::indexing_slicing, clippy::unwrap_used))]

coforge_macros::device!("../../../spec/canopenia.yaml");

pub mod cache;
pub mod config;
pub mod device;
pub mod errors;
pub mod host;
pub mod objects;
pub mod rpdo_transmit;
pub mod status;

pub use device::Canopenia;
