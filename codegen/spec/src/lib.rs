//! coforge-spec: loads a device spec (YAML), validates it, normalises it into a [`Device`]
//! model and exports it (EDS per CiA 306, Markdown docs).
//!
//! ```no_run
//! let loaded = coforge_spec::load_file("spec/co401memory1.yaml".as_ref());
//! eprint!("{}", loaded.render_diagnostics());
//! if let Some(device) = loaded.device() {
//!     println!("{} objects", device.objects.len());
//! }
//! ```
#![forbid(unsafe_code)]

pub mod beds;
pub mod diag;
pub mod docs;
pub mod eds;
pub mod expr;
pub mod fmt;
pub mod frame;
pub mod model;
pub mod normalize;
pub mod raw;
pub mod template;
pub mod types;
pub mod validate;

pub use diag::{Diagnostic, Diagnostics, Severity, Source, Span};
pub use model::Device;

use std::path::Path;

/// A spec after loading: its text, its diagnostics and, if it parsed, the model.
#[derive(Debug)]
pub struct Loaded {
    pub source: Source,
    pub diagnostics: Diagnostics,
    model: Option<Device>,
}

impl Loaded {
    /// The model, if the spec loaded without errors.
    pub fn device(&self) -> Option<&Device> {
        if self.diagnostics.has_errors() { None } else { self.model.as_ref() }
    }
    pub fn into_device(self) -> Option<Device> {
        if self.diagnostics.has_errors() { None } else { self.model }
    }
    pub fn render_diagnostics(&self) -> String {
        self.source.render_all(&self.diagnostics)
    }
}

/// Loads, normalises and validates a spec from text; `name` is used in diagnostics.
pub fn load_str(name: &str, text: &str) -> Loaded {
    let source = Source { name: name.to_string(), text: text.to_string() };
    let mut diagnostics = Diagnostics::default();
    // YAML 1.2 booleans only: with YAML 1.1 rules a repeat variable `n` or `y` would read as a boolean.
    let options = serde_saphyr::options! { strict_booleans: true };
    let model = match serde_saphyr::from_str_with_options::<raw::Spec>(text, options) {
        Ok(spec) => {
            let device = normalize::normalize(&spec, &mut diagnostics);
            // Validation passes assume a well-formed model; run them once normalising succeeded.
            if !diagnostics.has_errors() {
                validate::run_all(&device, &mut diagnostics);
            }
            Some(device)
        }
        Err(e) => {
            diagnostics.push(yaml_error(&e));
            None
        }
    };
    diagnostics.sort();
    Loaded { source, diagnostics, model }
}

/// Reads and loads a spec file. An unreadable file becomes an `io` diagnostic.
pub fn load_file(path: &Path) -> Loaded {
    let name = path.display().to_string();
    match std::fs::read_to_string(path) {
        Ok(text) => load_str(&name, &text),
        Err(e) => {
            let mut diagnostics = Diagnostics::default();
            diagnostics.push(Diagnostic::error("io", Span::NONE, format!("cannot read {name}: {e}")));
            Loaded { source: Source { name, text: String::new() }, diagnostics, model: None }
        }
    }
}

/// Turns a serde-saphyr error into a diagnostic with its position and without its own
/// snippet (we render our own, the same way for every diagnostic).
fn yaml_error(e: &serde_saphyr::Error) -> Diagnostic {
    let span = e.location().map_or(Span::NONE, |l| Span::of(&l));
    let text = e.to_string();
    let first = text.lines().next().unwrap_or("invalid YAML");
    let first = first.strip_prefix("error: ").unwrap_or(first);
    // Drop the "line N column M: " prefix; the position is rendered separately.
    let message = match first.split_once(": ") {
        Some((pos, rest)) if pos.starts_with("line ") => rest,
        _ => first,
    };
    Diagnostic::error("yaml", span, message.to_string())
}
