//! The CiA 301 vocabulary (from `coforge-types`, shared with the firmware) and identifier
//! conversion.

pub use coforge_types::*;

/// Converts a datasheet name into a snake_case identifier.
pub fn snake_case(name: &str) -> String {
    let mut out = String::new();
    let mut prev_lower = false;
    for c in name.chars() {
        if c.is_ascii_alphanumeric() {
            if c.is_ascii_uppercase() && prev_lower && !out.ends_with('_') {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
            prev_lower = c.is_ascii_lowercase() || c.is_ascii_digit();
        } else {
            if !out.is_empty() && !out.ends_with('_') {
                out.push('_');
            }
            prev_lower = false;
        }
    }
    let trimmed = out.trim_end_matches('_').to_string();
    if trimmed.starts_with(|c: char| c.is_ascii_digit()) { format!("_{trimmed}") } else { trimmed }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snake_case_examples() {
        assert_eq!(snake_case("COB-ID Sync"), "cob_id_sync");
        assert_eq!(snake_case("Memory block 12"), "memory_block_12");
        assert_eq!(snake_case("Nr of SubIndex"), "nr_of_sub_index");
        assert_eq!(snake_case("1st value"), "_1st_value");
        assert_eq!(snake_case("Error Register (1001h)"), "error_register_1001h");
    }
}
