//! The CANopen runtime that every generated coforge device implements and runs on.
//!
//! This version holds the object dictionary interface ([`od`]): the trait the `device!`
//! macro implements, entry metadata, the access checks of both sides (CANopen bus and
//! serial host) and the CiA 301 SDO abort codes. The protocol engines (NMT, SDO, PDO, EMCY,
//! heartbeat) build on it.
#![no_std]
#![forbid(unsafe_code)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]
#![cfg_attr(test, allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod od;
pub mod pdo;
pub mod value;
