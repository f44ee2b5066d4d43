//! Binary EDS v2.00 export (`coforge beds`): a spec, or a CiA 306 EDS file, as the compact
//! dictionary configuration CANopenIA loads through 1F50h.2.
//!
//! The passes, each in its own file:
//! - [`dictionary`]: the spec (or [`eds_import`]: an EDS) lowered to a flat list of entries
//!   with values resolved for one node-ID;
//! - [`layout`]: which table each entry goes to, and where it lives in the process image;
//! - [`write`]: the bytes, the padding and the CRC.
//!
//! The format itself (offsets, record layouts, a validating reader) is `coforge-beds`, which
//! the firmware shares.

pub mod dictionary;
pub mod eds_import;
pub mod layout;
pub mod write;

pub use dictionary::{Dictionary, Settings};
pub use layout::Conventions;

use crate::eds::ExportError;
use crate::model::Device;

/// The binary EDS of `d` in `mode`, for the node-ID, bit rate and FUNC bits of `settings`.
pub fn export(d: &Device, mode: Option<&str>, settings: Settings) -> Result<Vec<u8>, ExportError> {
    let dict = Dictionary::from_device(d, mode, settings)?;
    let tables = layout::lower(&dict, &Conventions::default())?;
    Ok(write::file(&dict.settings, &tables))
}

/// The binary EDS of a CiA 306 EDS file.
pub fn export_eds(text: &str, settings: Settings, conventions: &Conventions) -> Result<Vec<u8>, ExportError> {
    let dict = eds_import::import(text, settings).map_err(|e| ExportError(e.0))?;
    let tables = layout::lower(&dict, conventions)?;
    Ok(write::file(&dict.settings, &tables))
}
