//! Proof obligations as plain functions that assert.
//!
//! Each `prop_*` function states one property for one input. Three engines check them:
//! - Kani harnesses ([`harnesses`], `cargo kani`, GitHub workflow `kani.yml`) for every input
//!   up to a bound;
//! - exhaustive tests where the domain is small (`tests/exhaustive.rs`,
//!   `tests/banks_exhaustive.rs`, and the state-space search `tests/banks_model.rs`);
//! - bounded random tests with proptest where it is not (`tests/random.rs`).
//!
//! See `verification/README.md` for the list of obligations and which engine checks each.
#![no_std]
#![forbid(unsafe_code)]

pub mod banks;
pub mod canopenia;
pub mod canopenia_files;
pub mod framing;
pub mod gw1;
pub mod inputs;
pub mod integrity;
pub mod manager;
pub mod node;
pub mod rng;
pub mod stack;

#[cfg(kani)]
mod harnesses;
