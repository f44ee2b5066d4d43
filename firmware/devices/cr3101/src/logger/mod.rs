//! CR3101's logging model, the part of the device its dictionary hooks will hand their reads
//! and writes to (issue 16; not wired to the node yet):
//!
//! - [`pair`]: a redundant pair (2002h/2003h), a change taking effect when both halves agree;
//! - [`file_config`]: one file's configuration (3x00h..3x1ch) and its rules.

pub mod file_config;
pub mod pair;
