//! `{expr}` placeholders in template strings: `Memory block {b}`, `Component {c + 1}`,
//! `Block {b:02X}`. `{{` and `}}` stand for literal braces.

use crate::expr::{Expr, ExprError, Vars};
use std::fmt::Write as _;

pub fn interpolate(text: &str, vars: &Vars) -> Result<String, ExprError> {
    if !text.contains(['{', '}']) {
        return Ok(text.to_string());
    }
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(pos) = rest.find(['{', '}']) {
        out.push_str(&rest[..pos]);
        let tail = &rest[pos..];
        if let Some(after) = tail.strip_prefix("{{") {
            out.push('{');
            rest = after;
        } else if let Some(after) = tail.strip_prefix("}}") {
            out.push('}');
            rest = after;
        } else if tail.starts_with('}') {
            return Err(ExprError("unmatched `}` in template (write `}}` for a brace)".into()));
        } else {
            let close = tail.find('}').ok_or_else(|| ExprError("unclosed `{` in template (write `{{` for a brace)".into()))?;
            let inner = &tail[1..close];
            let (src, spec) = inner.split_once(':').unwrap_or((inner, ""));
            let value = Expr::parse(src)?.eval(vars, None)?;
            format_value(&mut out, value, spec)?;
            rest = &tail[close + 1..];
        }
    }
    out.push_str(rest);
    Ok(out)
}

/// Supports `` (decimal), `X`/`x` (hex) and a zero-padded width such as `02X` or `03`.
fn format_value(out: &mut String, value: i64, spec: &str) -> Result<(), ExprError> {
    let bad = || ExprError(format!("unknown format `{spec}` (use X, x, 02X or 03)"));
    let (width, radix) = match spec.strip_suffix(['X', 'x']) {
        Some(w) => (w, spec.chars().last()),
        None => (spec, None),
    };
    let width: usize = if width.is_empty() {
        0
    } else {
        let digits = width.strip_prefix('0').ok_or_else(bad)?;
        digits.parse().map_err(|_| bad())?
    };
    let _ = match radix {
        Some('X') => write!(out, "{value:0width$X}"),
        Some(_) => write!(out, "{value:0width$x}"),
        None => write!(out, "{value:0width$}"),
    };
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders_are_evaluated_and_formatted() {
        let mut vars = Vars::new();
        vars.insert("f".into(), 2);
        vars.insert("b".into(), 10);
        assert_eq!(interpolate("File {f + 1}", &vars), Ok("File 3".into()));
        assert_eq!(interpolate("Block {b:02X} {{x}}", &vars), Ok("Block 0A {x}".into()));
        assert_eq!(interpolate("0x{0x5000 + b:X}", &vars), Ok("0x500A".into()));
        assert_eq!(interpolate("plain", &vars), Ok("plain".into()));
    }

    #[test]
    fn malformed_templates_are_errors() {
        let vars = Vars::new();
        for bad in ["{", "}", "{q}", "{1:Z}", "{1 +}"] {
            assert!(interpolate(bad, &vars).is_err(), "{bad}");
        }
    }
}
