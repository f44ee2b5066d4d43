//! The object dictionary interface: what generated dictionaries implement and every engine of
//! the node reads and writes through.
//!
//! Generated code keeps the data in one struct of byte-aligned little-endian fields, which is
//! also the value image every entry's `offset` points into ([`image`]); everything
//! that decides *whether* an access is allowed lives here, once, so every device and both
//! sides (bus and host) refuse the same things with the same CiA 301 abort code.
//!
//! - [`abort`]: the CiA 301 SDO abort codes;
//! - [`side`]: who accesses ([`Side`]), where a write came from ([`WriteSource`]) and the
//!   state a write is judged in ([`AccessContext`]);
//! - [`entry`]: [`EntryInfo`], an entry's (or a run's) metadata, and its access checks;
//! - [`lookup`]: finding a run in a generated table, copying values out;
//! - [`image`]: reading, writing, resetting, saving and loading values in the value image;
//! - [`dictionary`]: the two traits a generated dictionary implements, [`EntryAccess`]
//!   (lookup, reads and writes of entries) and [`NodeDictionary`] (what the node needs besides:
//!   defaults, persistence, emergencies, the mode), and [`AppObjects`], the owner of the
//!   objects a device keeps outside the dictionary.

pub mod abort;
pub mod dictionary;
pub mod entry;
pub mod image;
pub mod lookup;
pub mod properties;
pub mod side;

pub use abort::SdoAbort;
pub use coforge_types::{Access, DataType, HostAccess, NmtState, Storage};
pub use dictionary::{AppObjects, Area, CommObjects, EntryAccess, NoAppObjects, NodeDictionary, mode_named};
pub use entry::{EntryFlags, EntryInfo, EntryKind, Limits, ReadLen, decode_int};
pub use lookup::{Table, find, find_run, read_slice};
pub use side::{AccessContext, NmtStates, Side, WriteSource};

#[cfg(test)]
pub(crate) use entry::test_entry;
