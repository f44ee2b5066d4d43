//! Runs coforge CANopen devices on a PC: a virtual CAN bus that in-process nodes and SLCAN
//! tools (python-can's `slcan` interface over `socket://`, `nc`) share.
//!
//! - [`slcan`]: the Lawicel ASCII protocol, an encoder and a streaming decoder that never panics;
//! - [`hub`]: the bus, a TCP SLCAN listener plus in-process [`hub::Port`]s;
//! - [`devices`]: the coforge devices by name, built and driven through the device contract;
//! - [`memory1`]: CO401Memory1's console commands (supply, corrupt, outputs);
//! - [`gw1`]: CO401GW1's console commands (input and emergency pins, enable, pins);
//! - [`cr3101`]: CR3101's board (a card image in its slot) and console (card, battery, LEDs);
//! - [`card`]: card images as a PC formats them;
//! - [`runner`]: real-time nodes on a hub, one thread for all of them;
//! - [`serial`]: a device's serial host interface on a TCP port;
//! - [`vbus`]: a deterministic in-process bus on a virtual clock, for tests;
//! - [`storage`], [`app`]: EEPROMs (memory or file) and app-backed objects.
#![forbid(unsafe_code)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]
#![cfg_attr(test, allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod app;
pub mod canopenia;
pub mod card;
pub mod cr3101;
pub mod devices;
pub mod gw1;
pub mod hub;
pub mod memory1;
pub mod runner;
pub mod serial;
pub mod slcan;
pub mod storage;
pub mod vbus;
