//! The memory card (issue 16, item 1): what lands on it and how.
//!
//! - [`record`]: one data record's bytes, the layout a PC tool reads;
//! - [`files`]: the FAT volume and the pre-allocated data files.

pub mod files;
pub mod record;
#[cfg(feature = "card-sample")]
pub mod sample;
