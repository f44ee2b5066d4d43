//! The CR3101 CANmem data logger (`spec/cr3101.yaml`): process data from RPDOs logged as
//! time-stamped records into up to eight files on a FAT memory card, read back over SDO or
//! the PDO read mode.
//!
//! - [`board`]: what a board provides: the card slot, the clock at power-on, the LEDs;
//! - [`card`]: what lands on the card and how (records, files, the configuration file);
//! - [`clock`]: the real-time clock (2010h);
//! - [`logger`]: the files' configurations and operating modes over the card;
//! - `objects`: the app-backed objects' hooks, handed to the logger;
//! - [`device`]: the whole device, driven by CAN frames and time.
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]
#![cfg_attr(test, allow(clippy::indexing_slicing, clippy::unwrap_used))]

coforge_macros::device!("../../../spec/cr3101.yaml");

pub mod board;
pub mod card;
pub mod clock;
pub mod device;
pub mod logger;
mod objects;

pub use board::{Board, CardSense, StatusLeds};
pub use device::Cr3101;
