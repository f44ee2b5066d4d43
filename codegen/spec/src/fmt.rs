//! fmt
pub fn format(t: &str) -> Result<String, String> { Ok(t.to_string()) }
pub fn first_difference(_a: &str, _b: &str) -> String { String::new() }
