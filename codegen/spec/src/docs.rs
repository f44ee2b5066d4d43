//! Markdown docs.
use crate::model::Device;
pub fn markdown(d: &Device) -> String { d.identity.name.clone() }
