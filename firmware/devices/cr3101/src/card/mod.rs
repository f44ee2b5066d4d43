//! The memory card (issue 16, item 1): what lands on it and how.
//!
//! - [`record`]: one data record's bytes, the layout a PC tool reads;
//! - [`files`]: the FAT volume and the pre-allocated data files;
//! - [`settings`]: the card's configuration file;
//! - [`fat_clock`]: the time the FAT directory entries take.

pub mod fat_clock;
pub mod files;
pub mod record;
#[cfg(feature = "card-sample")]
pub mod sample;
pub mod settings;
