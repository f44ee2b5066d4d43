//! Errata rules: every resolved contradiction is fully recorded.

use crate::diag::{Diagnostic, Diagnostics};
use crate::model::Device;
use std::collections::BTreeMap;

pub fn complete(d: &Device, diags: &mut Diagnostics) {
    let mut ids = BTreeMap::new();
    for e in &d.errata {
        for (key, value) in [("id", &e.id), ("where", &e.location), ("datasheet", &e.datasheet), ("choice", &e.choice), ("reason", &e.reason)] {
            if value.trim().is_empty() {
                diags.push(Diagnostic::error("errata-complete", e.span, format!("erratum `{}` has an empty `{key}`", e.id)));
            }
        }
        if let Some(first) = ids.insert(e.id.as_str(), e.span) {
            diags.push(Diagnostic::error("errata-complete", e.span, format!("erratum id `{}` is used twice", e.id)).note_at(first, "first used here"));
        }
    }
}
