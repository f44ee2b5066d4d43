//! The CANopen runtime that every generated coforge device implements and runs on.
//!
//! - [`od`]: the object dictionary interface the `device!` macro implements, entry metadata,
//!   the access checks of both sides (bus and serial host) and the CiA 301 SDO abort codes;
//! - [`device`]: the contract between a device and whatever runs it (boards, the simulator,
//!   the size probe, tests);
//! - [`config`]: how a device's node differs from plain CiA 301 (generated from the spec);
//! - [`frame`]: the CAN frame exchanged with the board (an `embedded-can` frame);
//! - [`sdo`]: the SDO server (expedited, segmented and block transfer);
//! - the other protocol engines (NMT, PDO, EMCY, SYNC, heartbeat, guarding, store/restore)
//!   and the [`node::Node`] that owns them.
//!
//! Everything is `no_std`, heap-free and poll-driven: the board feeds received frames and
//! the current time in microseconds, and takes the frames to send.
#![no_std]
#![forbid(unsafe_code)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]
#![cfg_attr(test, allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod config;
pub mod device;
pub mod emcy;
pub mod frame;
pub mod guarding;
pub mod heartbeat;
pub mod leds;
pub mod manager;
pub mod nmt;
pub mod node;
pub mod od;
pub mod pdo;
pub(crate) mod ring;
pub mod sdo;
pub mod store;
pub mod time;
pub mod value;

// The byte-order types and derives of the generated dictionaries' value structs, re-exported
// so that a device crate needs no dependency of its own.
pub use zerocopy;
