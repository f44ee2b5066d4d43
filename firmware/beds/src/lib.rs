//! The binary EDS, format version 2.00: a compact object dictionary configuration that a
//! CANopen stack loads at run time (CANopenIA takes one through 1F50h.2).
//!
//! - [`layout`]: where everything is in a file: header fields, the eight tables, record sizes,
//!   FUNC and DSAT bits, the CRC;
//! - [`records`]: one type per record kind, decoded from its bytes;
//! - [`reader`]: [`BinaryEds::parse`] checks a whole file (CRC, header, every table's bounds and
//!   sentinel, every entry inside the process image) before anything reads it, then hands out
//!   the tables as iterators. It allocates nothing and never panics, whatever the bytes: a
//!   device can validate a file as it arrives.
//!
//! The writer lives in `coforge-spec` (`coforge beds`), which exports a spec as such a file.
#![no_std]
#![forbid(unsafe_code)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]
#![cfg_attr(test, allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod layout;
pub mod reader;
pub mod records;

pub use layout::{Dsat, Table};
pub use reader::{BinaryEds, Error, Header};
pub use records::{GenericEntry, OdEntry, PdoRecord, SdoReply};
