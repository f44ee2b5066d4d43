//! Two mirrored EEPROM banks, as CO401Memory1 keeps its 8 KiB of user data: every write goes
//! to both banks, every read checks both, and a power cut at any byte of any write leaves each
//! block holding either its old or its new contents in at least one bank.
//!
//! Each bank holds `BLOCKS` blocks of `BLOCK` data bytes, each followed by a 4-byte commit
//! record (see [`record`]). The layout of one bank:
//!
//! ```text
//! block 0: data[0..BLOCK] | begin | crc lo | crc hi | end
//! block 1: data[0..BLOCK] | begin | crc lo | crc hi | end
//! ...
//! ```
//!
//! - [`record`]: the commit record, and the write order that makes torn writes detectable;
//! - [`resolve`]: which copy of a block wins when the banks disagree (a pure function, so the
//!   proofs can check it on its own);
//! - [`status`]: the per-bank status bits CO401Memory1 reports in 6000h;
//! - [`banks`]: the mirrored banks over any two `embedded-storage` devices;
//! - [`ram`]: an in-memory EEPROM for emulated boards and tests.
#![no_std]
#![forbid(unsafe_code)]
#![deny(clippy::indexing_slicing, clippy::panic, clippy::unwrap_used, clippy::expect_used)]
#![cfg_attr(test, allow(clippy::indexing_slicing, clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod banks;
pub mod ram;
pub mod record;
pub mod resolve;
pub mod status;

pub use banks::{Error, MirroredBanks};
pub use status::BankStatus;

/// Bytes each bank's EEPROM must provide for `blocks` blocks of `block` bytes.
pub const fn bank_size(blocks: usize, block: usize) -> usize {
    blocks * (block + record::RECORD)
}

#[cfg(test)]
extern crate std;
