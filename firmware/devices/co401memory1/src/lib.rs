//! The CO401Memory1 bus memory module (`spec/co401memory1.yaml`): 8 KiB of user data in two
//! mirrored EEPROM banks, reached over CANopen (5000h..503Fh) and over the serial host
//! protocol, with per-bank status and commands, bank checksums, a supply-voltage guard and a
//! CAN monitoring channel.
//!
//! - [`board`]: what a board provides: configuration pins, supply reading, status outputs;
//! - [`memory`]: the app-backed objects (memory bytes, checksums, bank status and commands)
//!   over [`coforge_storage::MirroredBanks`];
//! - [`supply`]: the 15 V / 11 V write guard;
//! - [`monitor`]: the CAN monitoring channel (RPDO2's identifier);
//! - [`host`]: the serial host protocol, on the generated codecs;
//! - [`device`]: the whole module, driven by CAN frames, serial bytes and time.
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]

coforge_macros::device!("../../../spec/co401memory1.yaml");

pub mod board;
pub mod device;
pub mod host;
pub mod memory;
pub mod monitor;
pub mod supply;

pub use board::{Board, Config, ConfigError, FixedBoard, StatusOutputs};
pub use device::Memory1;
pub use memory::{BANK_SIZE, BLOCK, BLOCKS, Banks, MemoryApp};
