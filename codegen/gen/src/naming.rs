//! Rust identifiers from spec names: one place for keywords, leading digits and CamelCase.

use proc_macro2::{Ident, Span};
use quote::format_ident;

const KEYWORDS: &[&str] = &[
    "abstract", "as", "async", "await", "become", "box", "break", "const", "continue", "crate", "do", "dyn", "else", "enum", "extern", "false", "final", "fn",
    "for", "gen", "if", "impl", "in", "let", "loop", "macro", "match", "mod", "move", "mut", "override", "priv", "pub", "ref", "return", "static", "struct",
    "super", "trait", "true", "try", "type", "typeof", "unsafe", "unsized", "use", "virtual", "where", "while", "yield",
];

/// A snake_case spec name as an identifier (`r#type`, `_1st`).
pub fn ident(name: &str) -> Ident {
    let safe = if name.is_empty() || name.starts_with(|c: char| c.is_ascii_digit()) { format!("_{name}") } else { name.to_string() };
    if KEYWORDS.contains(&safe.as_str()) { format_ident!("r#{}", safe) } else { Ident::new(&safe, Span::call_site()) }
}

/// `digital_alt` -> `DigitalAlt`.
pub fn camel(name: &str) -> Ident {
    let s: String = name.split('_').filter(|p| !p.is_empty()).map(|p| p[..1].to_ascii_uppercase() + &p[1..]).collect();
    ident(&s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_become_valid_identifiers() {
        assert_eq!(camel("digital_alt").to_string(), "DigitalAlt");
        assert_eq!(camel("pdo_read").to_string(), "PdoRead");
        assert_eq!(ident("type").to_string(), "r#type");
        assert_eq!(ident("1st_value").to_string(), "_1st_value");
    }
}
