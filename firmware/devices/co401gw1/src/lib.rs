//! The CO401GW1 CANopen gateway chip (`spec/co401gw1.yaml`): a DS401 I/O slave whose
//! process data a host microcontroller exchanges over a UART, 16 bytes each way, with 8
//! digital input and 8 digital output pins of its own.
//!
//! - [`board`]: what a board provides: the ID and CFG pins, IN0..IN7, EMY0#/EMY1#, OUT0..OUT7,
//!   the LEDs and the watchdog;
//! - [`image`]: the process image behind 6000h/6100h/6120h and 6200h/6300h/6320h;
//! - [`ds401`]: when an input change is an event, what the outputs show on an error;
//! - [`host`]: the host's commands as requests, and its configuration before enable;
//! - [`device`]: the whole chip, driven by CAN frames, serial bytes and time;
//! - [`console`]: the pin console of the simulator and the QEMU image.
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]
#![cfg_attr(test, allow(clippy::indexing_slicing, clippy::unwrap_used))]

#[cfg(test)]
extern crate std;

coforge_macros::device!("../../../spec/co401gw1.yaml");

pub mod board;
pub mod console;
pub mod device;
pub mod ds401;
pub mod host;
pub mod image;

pub use board::{Board, FixedBoard, PinConfig};
pub use console::{Answer, Command, ConsoleError};
pub use device::Gw1;
pub use image::IoImage;
