//! Diagnostics that point at a file, a line and a column, rendered with a source snippet.

use std::fmt::{self, Write as _};

/// A position in a spec file: 1-based line and column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default, Hash)]
pub struct Span {
    pub line: u32,
    pub col: u32,
}

impl Span {
    /// The position of a value read by serde-saphyr.
    pub fn of(loc: &serde_saphyr::Location) -> Self {
        Span { line: u32::try_from(loc.line()).unwrap_or(u32::MAX), col: u32::try_from(loc.column()).unwrap_or(u32::MAX) }
    }
    /// A span for generated items that have no place in the file.
    pub const NONE: Span = Span { line: 0, col: 0 };
    pub fn is_none(self) -> bool {
        self.line == 0
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Severity {
    Error,
    Warning,
}

/// One finding about a spec.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Diagnostic {
    pub severity: Severity,
    /// The rule that fired, e.g. `od-duplicate-index`; `yaml` for load errors.
    pub rule: &'static str,
    pub message: String,
    pub span: Span,
    /// Further places and explanations, each optionally with a position.
    pub notes: Vec<(Option<Span>, String)>,
}

impl Diagnostic {
    pub fn error(rule: &'static str, span: Span, message: impl Into<String>) -> Self {
        Diagnostic { severity: Severity::Error, rule, message: message.into(), span, notes: Vec::new() }
    }
    pub fn warning(rule: &'static str, span: Span, message: impl Into<String>) -> Self {
        Diagnostic { severity: Severity::Warning, rule, message: message.into(), span, notes: Vec::new() }
    }
    #[must_use]
    pub fn note(mut self, text: impl Into<String>) -> Self {
        self.notes.push((None, text.into()));
        self
    }
    #[must_use]
    pub fn note_at(mut self, span: Span, text: impl Into<String>) -> Self {
        self.notes.push((Some(span), text.into()));
        self
    }
}

/// Collects diagnostics while passes run.
#[derive(Debug, Default)]
pub struct Diagnostics {
    pub items: Vec<Diagnostic>,
}

impl Diagnostics {
    pub fn push(&mut self, d: Diagnostic) {
        self.items.push(d);
    }
    pub fn has_errors(&self) -> bool {
        self.items.iter().any(|d| d.severity == Severity::Error)
    }
    pub fn error_count(&self) -> usize {
        self.items.iter().filter(|d| d.severity == Severity::Error).count()
    }
    /// Sorted by position, so output is stable and reads top to bottom.
    pub fn sort(&mut self) {
        self.items.sort_by(|a, b| (a.span, a.rule, &a.message).cmp(&(b.span, b.rule, &b.message)));
        self.items.dedup();
    }
}

/// The text of a spec file, for rendering snippets.
#[derive(Debug, Clone)]
pub struct Source {
    pub name: String,
    pub text: String,
}

impl Source {
    fn line(&self, n: u32) -> Option<&str> {
        let idx = usize::try_from(n).ok()?.checked_sub(1)?;
        self.text.lines().nth(idx)
    }

    /// Renders one diagnostic like rustc does:
    ///
    /// ```text
    /// error[od-duplicate-index]: object 0x1000 is defined twice
    ///   --> spec/x.yaml:12:5
    ///    |
    /// 12 |   - index: 0x1000
    ///    |     ^^^^^
    /// ```
    pub fn render(&self, d: &Diagnostic) -> String {
        let mut out = String::new();
        let sev = match d.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        let _ = writeln!(out, "{sev}[{}]: {}", d.rule, d.message);
        self.render_place(&mut out, d.span, None);
        for (span, text) in &d.notes {
            match span {
                Some(s) if !s.is_none() => {
                    let _ = writeln!(out, "   = note: {text}");
                    self.render_place(&mut out, *s, None);
                }
                _ => {
                    let _ = writeln!(out, "   = note: {text}");
                }
            }
        }
        out
    }

    fn render_place(&self, out: &mut String, span: Span, label: Option<&str>) {
        if span.is_none() {
            let _ = writeln!(out, "  --> {}", self.name);
            return;
        }
        let _ = writeln!(out, "  --> {}:{}:{}", self.name, span.line, span.col);
        if let Some(line) = self.line(span.line) {
            let num = span.line.to_string();
            let pad = " ".repeat(num.len());
            let col = usize::try_from(span.col).unwrap_or(1).saturating_sub(1);
            let rest: String = line.chars().skip(col).collect();
            // Underline the token at the position: up to the end of a scalar or key.
            let width = rest
                .char_indices()
                .find(|&(_, c)| c == '#' || c == ',' || c == '}' || c == ']')
                .map_or(rest.trim_end().chars().count(), |(i, _)| rest[..i].trim_end().chars().count())
                .max(1);
            let _ = writeln!(out, "{pad} |");
            let _ = writeln!(out, "{num} | {line}");
            let _ = writeln!(out, "{pad} | {}{}{}", " ".repeat(col), "^".repeat(width), label.map(|l| format!(" {l}")).unwrap_or_default());
        }
    }

    pub fn render_all(&self, diags: &Diagnostics) -> String {
        diags.items.iter().map(|d| self.render(d)).collect::<Vec<_>>().join("\n")
    }
}

impl fmt::Display for Severity {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Severity::Error => "error",
            Severity::Warning => "warning",
        })
    }
}
