//! EDS export (CiA 306).
use crate::model::Device;
pub fn export(_d: &Device, _mode: Option<&str>) -> Result<String, String> { Err("EDS export is being written".into()) }
pub fn model_json(_d: &Device, _mode: Option<&str>, _node: u8) -> Result<String, String> { Err("model export is being written".into()) }
