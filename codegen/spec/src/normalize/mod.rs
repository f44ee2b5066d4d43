//! Raw spec -> [`Device`]: expands templates, parses keywords and expressions, generates the
//! PDO parameter objects and resolves the serial host's access per entry.
//!
//! Problems found here are reported as diagnostics and the offending item is skipped, so one
//! run reports as many independent mistakes as possible.
//!
//! - `mod.rs`: the entry point [`normalize`], the context `Cx` (diagnostics, numbers,
//!   expressions, keywords, modes, repeats) and shared helpers ([`span`], [`hex_bytes`]);
//! - `identity.rs`: the `device:` identity and the `node:` settings;
//! - `hardware.rs`: pin and object selectors, code tables and configuration pins;
//! - `modes.rs`: operating modes and how each is selected;
//! - `objects.rs`: `objects:` with templates and groups expanded into objects and entries;
//! - `pdo.rs`: the PDO sets and default PDOs, and the PDO parameter objects generated from them;
//! - `host_access.rs`: the serial host's access rule and each entry's host access derived from it;
//! - `emcy.rs`: emergencies;
//! - `serial.rs`: the serial protocol: settings, framing, CRC, commands and their fields.

mod emcy;
mod hardware;
mod host_access;
mod identity;
mod modes;
mod objects;
mod pdo;
mod serial;

use emcy::emergency;
use hardware::hardware;
use host_access::apply_host_access;
use identity::{identity, node_settings};
use modes::mode;
use objects::expand_objects;
use pdo::{pdo_config, pdo_objects};
use serial::serial;

use crate::diag::{Diagnostic, Diagnostics, Span};
use crate::expr::{Expr, Vars};
use crate::model::{Device, Erratum, ModeSet, RedundantPair};
use crate::raw::{self, Num, S, Scalar};
use crate::template::interpolate;
use crate::types::NmtState;
use std::collections::BTreeSet;

pub const FORMAT_VERSION: u32 = 1;

/// Largest number of items one `repeat` may produce; guards against typos like `count: 0x10000`.
const MAX_REPEAT: i64 = 4096;

pub fn span<T>(s: &S<T>) -> Span {
    Span::of(&s.referenced)
}

struct Cx<'d> {
    diags: &'d mut Diagnostics,
    modes: BTreeSet<String>,
}

impl Cx<'_> {
    fn err(&mut self, rule: &'static str, at: Span, msg: impl Into<String>) {
        self.diags.push(Diagnostic::error(rule, at, msg));
    }

    /// An integer that may be written as an expression (no `$NODEID`).
    fn int(&mut self, n: &Num, vars: &Vars, what: &str) -> Option<i64> {
        let at = span(n);
        match &n.value {
            Scalar::Int(v) => match i64::try_from(*v) {
                Ok(v) => Some(v),
                Err(_) => {
                    self.err("spec-value", at, format!("{what} {v} does not fit in 64 bits"));
                    None
                }
            },
            Scalar::Str(s) => match Expr::parse(s).and_then(|e| e.eval(vars, None)) {
                Ok(v) => Some(v),
                Err(e) => {
                    self.err("spec-expr", at, format!("{what}: {e}"));
                    None
                }
            },
            other => {
                self.err("spec-value", at, format!("{what} must be an integer or an expression, found {}", scalar_kind(other)));
                None
            }
        }
    }

    /// An integer that must fit `T` and lie in `lo..=hi`.
    fn int_in<T: TryFrom<i64>>(&mut self, n: &Num, vars: &Vars, what: &str, lo: i64, hi: i64) -> Option<T> {
        let v = self.int(n, vars, what)?;
        if !(lo..=hi).contains(&v) {
            self.err("spec-value", span(n), format!("{what} {} is outside {}..={}", show(v), show(lo), show(hi)));
            return None;
        }
        T::try_from(v).ok()
    }

    /// An expression that may use `$NODEID`, with repeat variables bound.
    fn expr(&mut self, n: &Num, vars: &Vars, what: &str) -> Option<Expr> {
        let at = span(n);
        let parsed = match &n.value {
            Scalar::Int(v) => i64::try_from(*v).map(Expr::Num).map_err(|_| crate::expr::ExprError(format!("{v} does not fit in 64 bits"))),
            Scalar::Str(s) => Expr::parse(s),
            other => {
                self.err("spec-value", at, format!("{what} must be an integer or an expression, found {}", scalar_kind(other)));
                return None;
            }
        };
        match parsed.and_then(|e| e.bind(vars)).and_then(|e| e.node_id_offset().map(|_| e)) {
            Ok(e) => Some(e),
            Err(e) => {
                self.err("spec-expr", at, format!("{what}: {e}"));
                None
            }
        }
    }

    fn text(&mut self, s: &S<String>, vars: &Vars) -> Option<String> {
        match interpolate(&s.value, vars) {
            Ok(t) => Some(t),
            Err(e) => {
                self.err("spec-expr", span(s), format!("in template `{}`: {e}", s.value));
                None
            }
        }
    }

    fn opt_text(&mut self, s: Option<&S<String>>, vars: &Vars) -> String {
        s.and_then(|s| self.text(s, vars)).unwrap_or_default()
    }

    fn keyword<T>(&mut self, s: &S<String>, what: &str, parse: impl Fn(&str) -> Option<T>, expected: &str) -> Option<T> {
        let v = parse(&s.value);
        if v.is_none() {
            self.err("spec-value", span(s), format!("unknown {what} `{}`; expected one of: {expected}", s.value));
        }
        v
    }

    fn modes(&mut self, list: Option<&S<Vec<S<String>>>>, inherited: &ModeSet) -> ModeSet {
        let Some(list) = list else { return inherited.clone() };
        let mut set = BTreeSet::new();
        for m in &list.value {
            if !self.modes.contains(&m.value) {
                let known: Vec<_> = self.modes.iter().cloned().collect();
                let msg = if known.is_empty() {
                    format!("mode `{}` is used but the spec declares no `modes`", m.value)
                } else {
                    format!("unknown mode `{}`; declared modes: {}", m.value, known.join(", "))
                };
                self.err("spec-mode", span(m), msg);
            }
            set.insert(m.value.clone());
        }
        if list.value.is_empty() {
            self.err("spec-mode", span(list), "`modes` must not be empty (omit it for every mode)");
        }
        if let Some(parent) = inherited
            && !set.is_subset(parent)
        {
            self.err("spec-mode", span(list), "an entry's `modes` must be a subset of its object's `modes`");
        }
        Some(set)
    }

    /// `writable_in: [preoperational, ...]`.
    fn nmt_states(&mut self, list: Option<&S<Vec<S<String>>>>) -> Option<Option<Vec<NmtState>>> {
        let Some(list) = list else { return Some(None) };
        let mut states = Vec::new();
        for s in &list.value {
            states.push(self.keyword(s, "NMT state", NmtState::parse, "preoperational, operational, stopped")?);
        }
        if states.is_empty() {
            self.err("spec-structure", span(list), "`writable_in` must name at least one NMT state (omit it for every state)");
            return None;
        }
        states.sort_unstable();
        states.dedup();
        Some(Some(states))
    }

    /// `repeat: { var, count }` or `{ var, from, to }` -> the variable and its values.
    fn repeat(&mut self, r: &S<raw::Repeat>, vars: &Vars) -> Option<(String, Vec<i64>)> {
        let rep = &r.value;
        let at = span(r);
        let name = &rep.var.value;
        if !name.starts_with(|c: char| c.is_ascii_lowercase()) || !name.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_') {
            self.err("spec-repeat", span(&rep.var), format!("repeat variable `{name}` must be a lower-case identifier"));
            return None;
        }
        if vars.contains_key(name) {
            self.err("spec-repeat", span(&rep.var), format!("repeat variable `{name}` shadows an enclosing repeat"));
            return None;
        }
        let (from, to) = match (&rep.count, &rep.from, &rep.to) {
            (Some(c), None, None) => (0, self.int(c, vars, "repeat count")? - 1),
            (None, Some(f), Some(t)) => (self.int(f, vars, "repeat from")?, self.int(t, vars, "repeat to")?),
            _ => {
                self.err("spec-repeat", at, "`repeat` needs either `count` or both `from` and `to`");
                return None;
            }
        };
        if to < from || to - from >= MAX_REPEAT {
            self.err("spec-repeat", at, format!("repeat range {from}..={to} is empty or longer than {MAX_REPEAT}"));
            return None;
        }
        Some((name.clone(), (from..=to).collect()))
    }
}

fn scalar_kind(s: &Scalar) -> &'static str {
    match s {
        Scalar::Int(_) => "an integer",
        Scalar::Float(_) => "a real number",
        Scalar::Bool(_) => "a boolean",
        Scalar::Str(_) => "a string",
    }
}

fn show(v: i64) -> String {
    if v >= 16 { format!("{v:#X}") } else { v.to_string() }
}

/// Parses `"30 81 01 00"` (optionally `0x` prefixed; `xx` marks a varying byte if allowed).
pub fn hex_bytes(text: &str, allow_wild: bool) -> Result<Vec<Option<u8>>, String> {
    text.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .map(|t| {
            let h = t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")).unwrap_or(t);
            if allow_wild && h.eq_ignore_ascii_case("xx") {
                Ok(None)
            } else if h.len() <= 2 {
                u8::from_str_radix(h, 16).map(Some).map_err(|_| format!("`{t}` is not a hex byte"))
            } else {
                Err(format!("`{t}` is not a hex byte"))
            }
        })
        .collect()
}

/// Normalises a parsed spec. Always returns a model; check `diags` for errors.
pub fn normalize(spec: &raw::Spec, diags: &mut Diagnostics) -> Device {
    let modes: BTreeSet<String> = spec.modes.iter().map(|m| m.value.name.value.clone()).collect();
    let mut cx = Cx { diags, modes };
    if spec.format.value != FORMAT_VERSION {
        cx.err("spec-format", span(&spec.format), format!("unsupported spec format {}; this coforge reads format {FORMAT_VERSION}", spec.format.value));
    }
    let none = Vars::new();
    let identity = identity(&mut cx, &spec.device);
    let (node, node_spans) = spec.node.as_ref().map(|n| node_settings(&mut cx, n)).unwrap_or_default();
    let hardware = spec.hardware.as_ref().map(|h| hardware(&mut cx, &h.value)).unwrap_or_default();
    let modes = spec.modes.iter().map(|m| mode(&mut cx, m)).collect();

    let mut objects = Vec::new();
    expand_objects(&mut cx, &spec.objects, &none, &mut objects);
    let persistent_pdos = objects.iter().any(|o| o.index == 0x1010);
    let pdo = spec.pdo.as_ref().map(|p| pdo_config(&mut cx, &p.value)).unwrap_or_default();
    objects.extend(pdo_objects(&pdo, persistent_pdos));

    let serial = spec.serial.as_ref().and_then(|s| serial(&mut cx, s));
    apply_host_access(&mut objects, serial.as_ref().map(|s| &s.host_access));
    objects.sort_by(|a, b| (a.index, &a.modes).cmp(&(b.index, &b.modes)));

    let emergencies = spec.emergencies.iter().filter_map(|e| emergency(&mut cx, e)).collect();
    let redundant_pairs = spec
        .redundant_pairs
        .iter()
        .filter_map(|p| {
            let primary = cx.int_in(&p.value.primary, &none, "primary", 1, 0xFFFF)?;
            let shadow = cx.int_in(&p.value.shadow, &none, "shadow", 1, 0xFFFF)?;
            Some(RedundantPair { primary, shadow, description: p.value.description.clone().unwrap_or_default(), span: span(p) })
        })
        .collect();
    let errata = spec
        .errata
        .iter()
        .map(|e| {
            let e2 = &e.value;
            Erratum {
                id: e2.id.value.clone(),
                location: e2.location.value.clone(),
                datasheet: e2.datasheet.value.clone(),
                choice: e2.choice.value.clone(),
                reason: e2.reason.value.clone(),
                span: span(e),
            }
        })
        .collect();

    Device { identity, node, node_spans, hardware, modes, objects, pdo, emergencies, serial, redundant_pairs, errata }
}
