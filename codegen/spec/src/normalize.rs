//! Raw spec -> [`Device`]: expands templates, parses keywords and expressions, generates the
//! PDO parameter objects and resolves the serial host's access per entry.
//!
//! Problems found here are reported as diagnostics and the offending item is skipped, so one
//! run reports as many independent mistakes as possible.

use crate::diag::{Diagnostic, Diagnostics, Span};
use crate::expr::{Expr, Vars};
use crate::model::*;
use crate::raw::{self, Num, S, Scalar};
use crate::template::interpolate;
use crate::types::{Access, DataType, EmcyEvent, HostAccess, NmtState, ObjectKind, Storage, Sub0, WriteWhen, snake_case};
use std::collections::{BTreeMap, BTreeSet};

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

    Device { identity, hardware, modes, objects, pdo, emergencies, serial, redundant_pairs, errata }
}

fn identity(cx: &mut Cx<'_>, d: &S<raw::Device>) -> Identity {
    let none = Vars::new();
    let v = &d.value;
    let u32_of = |cx: &mut Cx<'_>, n: &Num, what: &str| cx.int_in::<u32>(n, &none, what, 0, 0xFFFF_FFFF).unwrap_or(0);
    Identity {
        name: v.name.value.clone(),
        ident: v.ident.as_ref().map_or_else(|| device_ident(&v.name.value), |i| i.value.clone()),
        vendor: v.vendor.value.clone(),
        vendor_id: u32_of(cx, &v.vendor_id, "vendor_id"),
        product_code: u32_of(cx, &v.product_code, "product_code"),
        revision: u32_of(cx, &v.revision, "revision"),
        profile: cx.int_in::<u16>(&v.profile, &none, "profile", 0, 0xFFFF).unwrap_or(0),
        description: v.description.clone().unwrap_or_default(),
        sdo_block_transfer: v.sdo_block_transfer.unwrap_or(true),
        datasheet_title: v.datasheet.value.title.clone(),
        datasheet_version: v.datasheet.value.version.clone(),
        datasheet_file: v.datasheet.value.file.clone(),
        span: span(d),
    }
}

/// `CO401Memory1` -> `co401memory1`, `CR3101 CANmem` -> `cr3101_canmem`: file and crate names.
fn device_ident(name: &str) -> String {
    let mut out = String::new();
    for c in name.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.is_empty() && !out.ends_with('_') {
            out.push('_');
        }
    }
    out.trim_end_matches('_').to_string()
}

fn level(cx: &mut Cx<'_>, s: &S<String>) -> Option<Level> {
    cx.keyword(
        s,
        "pin level",
        |l| match l {
            "high" => Some(Level::High),
            "low" => Some(Level::Low),
            "any" => Some(Level::Any),
            _ => None,
        },
        "high, low, any",
    )
}

fn hardware(cx: &mut Cx<'_>, h: &raw::Hardware) -> Hardware {
    let mut sel = |s: &Option<S<raw::Selector>>| s.as_ref().and_then(|s| selector(cx, s));
    let node_id = sel(&h.node_id);
    let can_bitrate = sel(&h.can_bitrate);
    let serial_bitrate = sel(&h.serial_bitrate);
    let config_pins = h.config_pins.as_ref().map(|c| {
        let settings = c
            .value
            .settings
            .iter()
            .filter_map(|s| {
                Some(PinSetting { pin: s.value.pin.value.clone(), level: level(cx, &s.value.level)?, meaning: s.value.meaning.clone(), span: span(s) })
            })
            .collect();
        ConfigPins {
            pins: c.value.pins.iter().map(|p| p.value.clone()).collect(),
            inverted: c.value.inverted,
            settings,
            description: c.value.description.clone().unwrap_or_default(),
        }
    });
    Hardware { node_id, can_bitrate, serial_bitrate, config_pins }
}

fn selector(cx: &mut Cx<'_>, s: &S<raw::Selector>) -> Option<Selector> {
    let none = Vars::new();
    let v = &s.value;
    let source = match (&v.pins[..], &v.object) {
        ([], None) => SelectorSource::Configuration,
        (pins, None) => SelectorSource::Pins { pins: pins.iter().map(|p| p.value.clone()).collect(), inverted: v.inverted },
        ([], Some(o)) => {
            let index = cx.int_in(&o.value.index, &none, "index", 1, 0xFFFF)?;
            let sub = match &o.value.sub {
                Some(n) => cx.int_in(n, &none, "sub", 0, 254)?,
                None => 0,
            };
            SelectorSource::Object { index, sub }
        }
        _ => {
            cx.err("spec-structure", span(s), "a selector reads either `pins` or an `object`, not both");
            return None;
        }
    };
    let range = match &v.range {
        Some(r) => Some((cx.int(&r.value.0, &none, "range start")?, cx.int(&r.value.1, &none, "range end")?)),
        None => None,
    };
    let mut codes = Vec::new();
    for c in &v.codes {
        let row = &c.value;
        let opt = |cx: &mut Cx<'_>, n: &Option<Num>, what: &str| n.as_ref().and_then(|n| cx.int(n, &none, what));
        let value = opt(cx, &row.value, "value");
        if (row.reserved && value.is_some()) || (!row.reserved && value.is_none() && row.meaning.is_none()) {
            cx.err("spec-structure", span(c), "a code row has a `value`, or is `reserved: true`, or states its `meaning` (a special code such as LSS)");
            continue;
        }
        codes.push(CodeRow {
            code: cx.int(&row.code, &none, "code")?,
            value,
            exact: opt(cx, &row.exact, "exact"),
            reserved: row.reserved,
            meaning: row.meaning.clone().unwrap_or_default(),
            note: row.note.clone().unwrap_or_default(),
            span: span(c),
        });
    }
    Some(Selector {
        source,
        unit: v.unit.as_ref().map(|u| u.value.clone()),
        range,
        codes,
        description: v.description.clone().unwrap_or_default(),
        span: span(s),
    })
}

fn mode(cx: &mut Cx<'_>, m: &S<raw::Mode>) -> Mode {
    let v = &m.value;
    let mut pins = BTreeMap::new();
    let mut command = None;
    let mut object = None;
    if let Some(sel) = &v.select {
        for (pin, lvl) in &sel.value.pins {
            if let Some(l) = level(cx, lvl) {
                pins.insert(pin.clone(), l);
            }
        }
        command = sel.value.command.as_ref().map(|c| c.value.clone());
        if let Some(o) = &sel.value.object {
            let none = Vars::new();
            let index = cx.int_in(&o.value.index, &none, "index", 1, 0xFFFF);
            let sub = o.value.sub.as_ref().map_or(Some(0), |n| cx.int_in(n, &none, "sub", 0, 254));
            let value = cx.int(&o.value.value, &none, "value");
            if let (Some(index), Some(sub), Some(value)) = (index, sub, value) {
                object = Some((index, sub, value));
            }
        }
    }
    Mode { name: v.name.value.clone(), description: v.description.clone().unwrap_or_default(), pins, command, object, span: span(m) }
}

fn expand_objects(cx: &mut Cx<'_>, items: &[S<raw::Object>], vars: &Vars, out: &mut Vec<Object>) {
    for item in items {
        let o = &item.value;
        match (&o.repeat, &o.objects) {
            (Some(rep), group) => {
                let Some((var, values)) = cx.repeat(rep, vars) else { continue };
                if group.is_some() && (o.index.is_some() || o.subs.is_some() || o.name.is_some()) {
                    cx.err("spec-structure", span(item), "a repeated group (`repeat` + `objects`) carries no object keys of its own");
                    continue;
                }
                for v in values {
                    let mut inner = vars.clone();
                    inner.insert(var.clone(), v);
                    match group {
                        Some(g) => expand_objects(cx, g, &inner, out),
                        None => out.extend(object(cx, item, &inner)),
                    }
                }
            }
            (None, Some(_)) => cx.err("spec-structure", span(item), "`objects` is only allowed in a group with `repeat`"),
            (None, None) => out.extend(object(cx, item, vars)),
        }
    }
}

fn object(cx: &mut Cx<'_>, item: &S<raw::Object>, vars: &Vars) -> Option<Object> {
    let o = &item.value;
    let at = span(item);
    let Some(index_n) = &o.index else {
        cx.err("spec-structure", at, "object has no `index`");
        return None;
    };
    let index: u16 = cx.int_in(index_n, vars, "index", 0x0001, 0xFFFF)?;
    let kind = match &o.kind {
        Some(k) => cx.keyword(k, "object kind", ObjectKind::parse, "var, array, record, domain")?,
        None if o.subs.is_some() => {
            cx.err("spec-structure", at, "an object with `subs` needs `kind: array` or `kind: record`");
            return None;
        }
        None => ObjectKind::Var,
    };
    let f = o.fields();
    let Some(name_s) = f.name else {
        cx.err("spec-structure", at, format!("object {index:#06X} has no `name`"));
        return None;
    };
    let name = cx.text(name_s, vars)?;
    let ident = match f.ident {
        Some(i) => cx.text(i, vars)?,
        None => snake_case(&name),
    };
    let modes = cx.modes(f.modes, &None);
    let storage = match f.storage {
        Some(s) => cx.keyword(s, "storage class", Storage::parse, "ram, persistent, app")?,
        None => Storage::Ram,
    };
    let sub0 = match &o.sub0 {
        Some(s) => cx.keyword(
            s,
            "sub0 meaning",
            |v| match v {
                "highest" => Some(Sub0::Highest),
                "count" => Some(Sub0::Count),
                _ => None,
            },
            "highest, count",
        )?,
        None => Sub0::Highest,
    };
    let description = cx.opt_text(f.description, vars);
    let entries = if kind.has_subs() {
        let Some(subs) = &o.subs else {
            cx.err("spec-structure", at, format!("{} object {index:#06X} needs `subs`", kind.name()));
            return None;
        };
        let stray = [
            f.data_type.map(span),
            f.access.map(span),
            f.default.map(span),
            f.host_access.map(span),
            f.pdo_mapping.map(span),
            f.length.map(span),
            f.low.map(span),
            f.high.map(span),
            f.unit.map(span),
        ];
        if let Some(s) = stray.into_iter().flatten().next() {
            cx.err("spec-structure", s, "entry keys of an ARRAY/RECORD belong on its `subs`");
        }
        let mut entries = Vec::new();
        expand_entries(cx, subs, vars, storage, &modes, &mut entries);
        entries
    } else {
        if let Some(subs) = &o.subs {
            cx.err("spec-structure", subs.first().map_or(at, span), format!("a {} object has no `subs`", kind.name()));
            return None;
        }
        vec![entry(cx, f, 0, at, vars, storage, &modes)?]
    };
    Some(Object { index, name, ident, kind, sub0, entries, description, modes, generated: false, span: at })
}

fn expand_entries(cx: &mut Cx<'_>, items: &[S<raw::Entry>], vars: &Vars, storage: Storage, modes: &ModeSet, out: &mut Vec<Entry>) {
    for item in items {
        let values = match &item.value.repeat {
            Some(rep) => match cx.repeat(rep, vars) {
                Some((var, values)) => values
                    .into_iter()
                    .map(|v| {
                        let mut inner = vars.clone();
                        inner.insert(var.clone(), v);
                        inner
                    })
                    .collect(),
                None => continue,
            },
            None => vec![vars.clone()],
        };
        for inner in values {
            let Some(sub_n) = &item.value.sub else {
                cx.err("spec-structure", span(item), "sub-entry has no `sub`");
                break;
            };
            let Some(sub) = cx.int_in(sub_n, &inner, "sub-index", 0, 254) else { break };
            if let Some(e) = entry(cx, item.value.fields(), sub, span(item), &inner, storage, modes) {
                out.push(e);
            }
        }
    }
}

fn entry(cx: &mut Cx<'_>, f: raw::EntryFields<'_>, sub: u8, at: Span, vars: &Vars, storage: Storage, modes: &ModeSet) -> Option<Entry> {
    let (Some(name_s), Some(type_s), Some(access_s)) = (f.name, f.data_type, f.access) else {
        let missing: Vec<_> = [("name", f.name.is_none()), ("type", f.data_type.is_none()), ("access", f.access.is_none())]
            .into_iter()
            .filter(|m| m.1)
            .map(|m| format!("`{}`", m.0))
            .collect();
        cx.err("spec-structure", at, format!("entry is missing {}", missing.join(", ")));
        return None;
    };
    let name = cx.text(name_s, vars)?;
    let data_type = cx.keyword(type_s, "data type", DataType::from_name, "a CiA 301 type such as UNSIGNED8, INTEGER16, VISIBLE_STRING (see spec/README.md)")?;
    let access = cx.keyword(access_s, "access type", Access::parse, "ro, wo, rw, rwr, rww, const")?;
    let host_access = match f.host_access {
        Some(h) => Some(cx.keyword(h, "host access", HostAccess::parse, "none, ro, wo, rw")?),
        None => None,
    };
    let storage = match f.storage {
        Some(s) => cx.keyword(s, "storage class", Storage::parse, "ram, persistent, app")?,
        None => storage,
    };
    let length = match f.length {
        Some(n) => {
            if !(data_type.is_string() || data_type == DataType::Domain) {
                cx.err("spec-structure", span(n), format!("`length` applies to strings and domains, not {data_type}"));
            }
            Some(cx.int_in::<u32>(n, vars, "length", 1, 0xFFFF_FFFF)?)
        }
        None => None,
    };
    let value = |cx: &mut Cx<'_>, n: Option<&Num>, what: &str, node_id: bool| -> Option<Option<Value>> {
        let Some(n) = n else { return Some(None) };
        let v = match (&n.value, data_type) {
            (Scalar::Str(s), t) if t.is_string() => Value::Str(cx.text(&S { value: s.clone(), referenced: n.referenced, defined: n.defined }, vars)?),
            (Scalar::Float(x), t) if t.is_real() => Value::Real(*x),
            (Scalar::Int(i), t) if t.is_real() => Value::Real(*i as f64),
            (Scalar::Bool(b), DataType::Boolean) => Value::Int(Expr::Num(i64::from(*b))),
            (Scalar::Int(_) | Scalar::Str(_), t) if t.int_range().is_some() => {
                let e = cx.expr(n, vars, what)?;
                if !node_id && e.uses_node_id() {
                    cx.err("spec-expr", span(n), format!("{what}: `$NODEID` is only allowed in defaults"));
                    return None;
                }
                Value::Int(e)
            }
            (other, t) => {
                cx.err("spec-value", span(n), format!("{what} for {t} cannot be {}", scalar_kind(other)));
                return None;
            }
        };
        Some(Some(v))
    };
    let default = value(cx, f.default, "default", true)?;
    let values = match f.values {
        Some(list) => {
            let mut v = Vec::new();
            for n in &list.value {
                v.push(cx.int(n, vars, "allowed value")?);
            }
            if v.is_empty() || data_type.int_range().is_none() {
                cx.err("spec-structure", span(list), "`values` lists the allowed values of an integer entry and must not be empty");
                return None;
            }
            Some(v)
        }
        None => None,
    };
    let writable_in = cx.nmt_states(f.writable_in)?;
    if let (Some(_), Some(list)) = (&writable_in, f.writable_in)
        && !access.writable()
    {
        cx.err("spec-structure", span(list), format!("`writable_in` restricts writes, but access `{access}` allows none"));
    }
    let low = value(cx, f.low, "low limit", false)?;
    let high = value(cx, f.high, "high limit", false)?;
    let span_of = |s: Option<Span>| s.unwrap_or(at);
    Some(Entry {
        sub,
        ident: match f.ident {
            Some(i) => cx.text(i, vars)?,
            None => snake_case(&name),
        },
        name,
        data_type,
        length,
        access,
        host_access: host_access.unwrap_or(HostAccess::None),
        host_override: host_access.is_some(),
        host_write_when: WriteWhen::Always,
        pdo_mapping: f.pdo_mapping.is_some_and(|p| p.value),
        default,
        low,
        high,
        unit: f.unit.map(|u| u.value.clone()).unwrap_or_default(),
        storage,
        description: f.description.and_then(|d| cx.text(d, vars)).unwrap_or_default(),
        modes: cx.modes(f.modes, modes),
        values,
        writable_in,
        spans: EntrySpans {
            at,
            data_type: span(type_s),
            access: span(access_s),
            default: span_of(f.default.map(span)),
            low: span_of(f.low.map(span)),
            high: span_of(f.high.map(span)),
            values: span_of(f.values.map(span)),
        },
    })
}

fn pdo_config(cx: &mut Cx<'_>, p: &raw::Pdo) -> PdoConfig {
    let mut config = PdoConfig::default();
    for (dir, set) in [(PdoDir::Rx, &p.rpdo), (PdoDir::Tx, &p.tpdo)] {
        let Some(set) = set else { continue };
        let Some((params, pdos)) = pdo_set(cx, dir, set) else { continue };
        config.pdos.extend(pdos);
        match dir {
            PdoDir::Rx => config.rpdo = Some(params),
            PdoDir::Tx => config.tpdo = Some(params),
        }
    }
    config.pdos.sort_by_key(|p| (p.dir, p.number, p.modes.clone()));
    config
}

fn pdo_set(cx: &mut Cx<'_>, dir: PdoDir, set: &S<raw::PdoSet>) -> Option<(PdoSet, Vec<Pdo>)> {
    let none = Vars::new();
    let v = &set.value;
    let max_sub = if dir == PdoDir::Tx { 6 } else { 5 };
    let mut comm_subs = Vec::new();
    for n in &v.comm_subs.value {
        comm_subs.push(cx.int_in::<u8>(n, &none, &format!("{} communication sub-index", dir.name()), 1, max_sub)?);
    }
    if !comm_subs.contains(&1) || !comm_subs.contains(&2) {
        cx.err("spec-structure", span(&v.comm_subs), "`comm_subs` must contain 1 (COB-ID) and 2 (transmission type)");
    }
    comm_subs.sort_unstable();
    comm_subs.dedup();
    let access = |cx: &mut Cx<'_>, a: &Option<S<String>>| match a {
        Some(a) => cx.keyword(a, "access type", Access::parse, "ro, rw, const"),
        None => Some(Access::Rw),
    };
    let params = PdoSet {
        comm_subs,
        max_mapped: cx.int_in(&v.max_mapped, &none, "max_mapped", 0, 64)?,
        comm_access: access(cx, &v.comm_access)?,
        mapping_access: access(cx, &v.mapping_access)?,
        mapping_writable_in: cx.nmt_states(v.writable_in.as_ref())?,
        span: span(set),
    };
    let mut pdos = Vec::new();
    for p in &v.pdos {
        let d = &p.value;
        let Some(number) = cx.int_in::<u16>(&d.number, &none, "PDO number", 1, 512) else { continue };
        let Some(cob_id) = cx.expr(&d.cob_id, &none, "cob_id") else { continue };
        let Some(transmission_type) = cx.int_in::<u8>(&d.transmission_type, &none, "transmission_type", 0, 255) else { continue };
        let mut opt = |n: &Option<Num>, what: &str, hi: i64| n.as_ref().map_or(Some(0), |n| cx.int_in::<i64>(n, &none, what, 0, hi));
        let (Some(inhibit), Some(event), Some(sync_start)) =
            (opt(&d.inhibit_time, "inhibit_time", 0xFFFF), opt(&d.event_timer, "event_timer", 0xFFFF), opt(&d.sync_start, "sync_start", 240))
        else {
            continue;
        };
        let mut map = Vec::new();
        for m in &d.map {
            let (Some(index), Some(sub), Some(bits)) = (
                cx.int_in(&m.value.index, &none, "mapped index", 1, 0xFFFF),
                cx.int_in(&m.value.sub, &none, "mapped sub-index", 0, 255),
                cx.int_in(&m.value.bits, &none, "mapped bit length", 1, 64),
            ) else {
                continue;
            };
            map.push(Mapping { index, sub, bits, span: span(m) });
        }
        pdos.push(Pdo {
            dir,
            number,
            cob_id,
            transmission_type,
            inhibit_time: u16::try_from(inhibit).unwrap_or(0),
            event_timer: u16::try_from(event).unwrap_or(0),
            sync_start: u8::try_from(sync_start).unwrap_or(0),
            map,
            modes: cx.modes(d.modes.as_ref(), &None),
            description: d.description.clone().unwrap_or_default(),
            span: span(p),
            cob_id_span: span(&d.cob_id),
            transmission_type_span: span(&d.transmission_type),
        });
    }
    Some((params, pdos))
}

/// Builds the generated entries of one PDO's parameter objects.
struct PdoEntries<'a> {
    pdo: &'a Pdo,
    storage: Storage,
}

impl PdoEntries<'_> {
    fn entry(&self, sub: u8, name: String, data_type: DataType, access: Access, default: i64) -> Entry {
        let at = self.pdo.span;
        Entry {
            sub,
            ident: snake_case(&name),
            name,
            data_type,
            length: None,
            access,
            host_access: HostAccess::None,
            host_override: false,
            host_write_when: WriteWhen::Always,
            pdo_mapping: false,
            default: Some(Value::Int(Expr::Num(default))),
            low: None,
            high: None,
            unit: String::new(),
            storage: self.storage,
            description: String::new(),
            modes: self.pdo.modes.clone(),
            values: None,
            writable_in: None,
            spans: EntrySpans { at, data_type: at, access: at, default: at, low: at, high: at, values: at },
        }
    }
}

/// Generates the CiA 301 communication and mapping objects of every default PDO.
fn pdo_objects(config: &PdoConfig, persistent: bool) -> Vec<Object> {
    let storage = if persistent { Storage::Persistent } else { Storage::Ram };
    let mut out = Vec::new();
    for pdo in &config.pdos {
        let Some(set) = (match pdo.dir {
            PdoDir::Rx => config.rpdo.as_ref(),
            PdoDir::Tx => config.tpdo.as_ref(),
        }) else {
            continue;
        };
        let n = pdo.number;
        let kind = pdo.dir.name();
        let highest = set.comm_subs.iter().copied().max().unwrap_or(0);
        let make = PdoEntries { pdo, storage };
        let mut comm = vec![make.entry(0, "Highest sub-index supported".into(), DataType::Unsigned8, Access::Ro, i64::from(highest))];
        for &sub in &set.comm_subs {
            let (name, ty, default, unit) = match sub {
                1 => (format!("COB-ID used by {kind}"), DataType::Unsigned32, 0, ""),
                2 => ("Transmission type".to_string(), DataType::Unsigned8, i64::from(pdo.transmission_type), ""),
                3 => ("Inhibit time".to_string(), DataType::Unsigned16, i64::from(pdo.inhibit_time), "100 us"),
                4 => ("Compatibility entry".to_string(), DataType::Unsigned8, 0, ""),
                5 => ("Event timer".to_string(), DataType::Unsigned16, i64::from(pdo.event_timer), "ms"),
                _ => ("SYNC start value".to_string(), DataType::Unsigned8, i64::from(pdo.sync_start), ""),
            };
            let mut e = make.entry(sub, name, ty, set.comm_access, default);
            e.unit = unit.to_string();
            if sub == 1 {
                e.default = Some(Value::Int(pdo.cob_id.clone()));
                e.spans.default = pdo.cob_id_span;
            }
            if sub == 2 {
                e.spans.default = pdo.transmission_type_span;
            }
            comm.push(e);
        }
        out.push(Object {
            index: pdo.dir.comm_base() + (n - 1),
            name: format!("{kind}{n} communication parameter"),
            ident: format!("{}{n}_comm", kind.to_ascii_lowercase()),
            kind: ObjectKind::Record,
            sub0: Sub0::Highest,
            entries: comm,
            description: pdo.description.clone(),
            modes: pdo.modes.clone(),
            generated: true,
            span: pdo.span,
        });
        let count = i64::try_from(pdo.map.len()).unwrap_or(i64::MAX);
        let mut mapping = vec![make.entry(0, "Number of mapped objects".into(), DataType::Unsigned8, set.mapping_access, count)];
        mapping[0].writable_in.clone_from(&set.mapping_writable_in);
        for sub in 1..=set.max_mapped {
            let value = pdo.map.get(usize::from(sub - 1)).map_or(0, |m| i64::from(m.encoded()));
            let mut e = make.entry(sub, format!("Mapped object {sub}"), DataType::Unsigned32, set.mapping_access, value);
            e.writable_in.clone_from(&set.mapping_writable_in);
            if let Some(m) = pdo.map.get(usize::from(sub - 1)) {
                e.spans.default = m.span;
            }
            mapping.push(e);
        }
        out.push(Object {
            index: pdo.dir.mapping_base() + (n - 1),
            name: format!("{kind}{n} mapping parameter"),
            ident: format!("{}{n}_mapping", kind.to_ascii_lowercase()),
            kind: ObjectKind::Record,
            sub0: Sub0::Count,
            entries: mapping,
            description: String::new(),
            modes: pdo.modes.clone(),
            generated: true,
            span: pdo.span,
        });
    }
    out
}

/// Derives each entry's serial-host access from the device rule, unless the entry sets its own.
fn apply_host_access(objects: &mut [Object], rule: Option<&HostRule>) {
    for o in objects.iter_mut() {
        for e in &mut o.entries {
            if e.host_override {
                continue;
            }
            let Some(rule) = rule else {
                e.host_access = HostAccess::None;
                continue;
            };
            let read = match rule.read {
                HostRead::All => true,
                HostRead::None => false,
                HostRead::Listed => rule.readable.iter().any(|r| r.contains(o.index, e.sub)),
            };
            // Sub 0 of an ARRAY/RECORD describes its structure; no device rule makes it writable.
            let structural = o.kind.has_subs() && e.sub == 0 && o.sub0 == Sub0::Highest;
            let (write, when) = match rule.write {
                HostWrite::All => (e.access != Access::Const, WriteWhen::Always),
                HostWrite::None => (false, WriteWhen::Always),
                HostWrite::SameAsCan => (e.access.writable(), WriteWhen::Always),
                HostWrite::Listed => match rule.writable.iter().find(|r| r.contains(o.index, e.sub)) {
                    Some(r) => (e.access != Access::Const, r.when),
                    None => (false, WriteWhen::Always),
                },
            };
            e.host_access = HostAccess::from_flags(read, write && !structural);
            e.host_write_when = when;
        }
    }
}

fn emergency(cx: &mut Cx<'_>, e: &S<raw::Emergency>) -> Option<Emergency> {
    let none = Vars::new();
    let v = &e.value;
    let code = cx.int_in(&v.code, &none, "emergency code", 0, 0xFFFF)?;
    let error_register = cx.int_in(&v.error_register, &none, "error register", 0, 0xFF)?;
    let manufacturer = match &v.manufacturer.value {
        Scalar::Str(s) => match hex_bytes(s, true) {
            Ok(b) if b.len() == 5 => [b[0], b[1], b[2], b[3], b[4]],
            Ok(b) => {
                cx.err("spec-value", span(&v.manufacturer), format!("`manufacturer` has {} bytes; an EMCY frame carries exactly 5 (bytes 3..7)", b.len()));
                return None;
            }
            Err(m) => {
                cx.err("spec-value", span(&v.manufacturer), m);
                return None;
            }
        },
        other => {
            cx.err("spec-value", span(&v.manufacturer), format!("`manufacturer` must be 5 hex bytes such as `00 00 00 00 80`, found {}", scalar_kind(other)));
            return None;
        }
    };
    let example = match &v.example {
        Some(x) => match &x.value {
            Scalar::Str(s) => match hex_bytes(s, false) {
                Ok(b) => Some(b.into_iter().flatten().collect()),
                Err(m) => {
                    cx.err("spec-value", span(x), m);
                    return None;
                }
            },
            other => {
                cx.err("spec-value", span(x), format!("`example` must be hex bytes, found {}", scalar_kind(other)));
                return None;
            }
        },
        None => None,
    };
    let nmt = match &v.nmt {
        Some(n) => cx.keyword(
            n,
            "NMT effect",
            |s| match s {
                "none" => Some(NmtEffect::None),
                "error_behavior" => Some(NmtEffect::ErrorBehavior),
                "preoperational" => Some(NmtEffect::PreOperational),
                "stopped" => Some(NmtEffect::Stopped),
                _ => None,
            },
            "none, error_behavior, preoperational, stopped",
        )?,
        None => NmtEffect::None,
    };
    let outputs = match &v.outputs {
        Some(n) => cx.keyword(
            n,
            "output effect",
            |s| match s {
                "unchanged" => Some(OutputEffect::Unchanged),
                "error_state" => Some(OutputEffect::ErrorState),
                _ => None,
            },
            "unchanged, error_state",
        )?,
        None => OutputEffect::Unchanged,
    };
    let event = match &v.event {
        Some(n) => Some(cx.keyword(n, "stack event", EmcyEvent::parse, &EmcyEvent::ALL.map(EmcyEvent::name).join(", "))?),
        None => None,
    };
    Some(Emergency {
        name: v.name.value.clone(),
        event,
        code,
        error_register,
        manufacturer,
        description: v.description.clone().unwrap_or_default(),
        trigger: v.trigger.clone().unwrap_or_default(),
        nmt,
        outputs,
        reset: v.reset.clone().unwrap_or_default(),
        enabled_by: match &v.enabled_by {
            Some(n) => Some(cx.int_in(n, &none, "enabled_by", 1, 0xFFFF)?),
            None => None,
        },
        example_span: v.example.as_ref().map_or(span(e), span),
        example,
        modes: cx.modes(v.modes.as_ref(), &None),
        span: span(e),
    })
}

fn serial(cx: &mut Cx<'_>, s: &S<raw::Serial>) -> Option<Serial> {
    let v = &s.value;
    let framing = framing(cx, &v.framing)?;
    let none = Vars::new();
    let host_access = match &v.host_access {
        Some(h) => host_rule(cx, h)?,
        None => HostRule { read: HostRead::None, write: HostWrite::None, readable: Vec::new(), writable: Vec::new(), description: String::new() },
    };
    let error_bits = v
        .error_bits
        .iter()
        .filter_map(|b| {
            Some(ErrorBit {
                bit: cx.int_in(&b.value.bit, &none, "error bit", 0, 63)?,
                name: b.value.name.value.clone(),
                description: b.value.description.clone().unwrap_or_default(),
                span: span(b),
            })
        })
        .collect();
    let commands = v.commands.iter().filter_map(|c| command(cx, c, &framing)).collect();
    let settings =
        v.settings.as_ref().map(|st| SerialSettings { data_bits: st.value.data_bits, parity: st.value.parity.value.clone(), stop_bits: st.value.stop_bits });
    Some(Serial {
        settings,
        framing,
        host_access,
        error_bits,
        commands,
        description: v.description.clone().unwrap_or_default(),
        framing_span: span(&v.framing),
    })
}

fn framing(cx: &mut Cx<'_>, f: &S<raw::Framing>) -> Option<Framing> {
    let none = Vars::new();
    let v = &f.value;
    let at = span(f);
    // Which keys each kind takes, so that a key meant for another kind is reported.
    let given: [(&str, Option<Span>); 9] = [
        ("resync_pause_ms", v.resync_pause_ms.as_ref().map(span)),
        ("inter_byte_timeout_ms", v.inter_byte_timeout_ms.as_ref().map(span)),
        ("extension_threshold", v.extension_threshold.as_ref().map(span)),
        ("start_byte", v.start_byte.as_ref().map(span)),
        ("start_byte_bits", v.start_byte_bits.as_ref().map(span)),
        ("length_bytes", v.length_bytes.as_ref().map(span)),
        ("length_counts", v.length_counts.as_ref().map(span)),
        ("max_payload", v.max_payload.as_ref().map(span)),
        ("crc", v.crc.as_ref().map(span)),
    ];
    let allowed: &[&str] = match v.kind.value.as_str() {
        "nibble_length" => &["resync_pause_ms"],
        "length_byte" => &["resync_pause_ms", "inter_byte_timeout_ms", "extension_threshold"],
        "start_length_crc" => {
            &["start_byte", "start_byte_bits", "length_bytes", "length_counts", "max_payload", "crc", "resync_pause_ms", "inter_byte_timeout_ms"]
        }
        other => {
            cx.err("spec-value", span(&v.kind), format!("unknown framing kind `{other}`; expected one of: nibble_length, length_byte, start_length_crc"));
            return None;
        }
    };
    for (key, sp) in given {
        if let Some(sp) = sp
            && !allowed.contains(&key)
        {
            cx.err("spec-structure", sp, format!("`{key}` does not apply to `{}` framing", v.kind.value));
        }
    }
    let mut need = |n: &Option<Num>, key: &str, lo: i64, hi: i64| -> Option<i64> {
        match n {
            Some(n) => cx.int_in(n, &none, key, lo, hi),
            None => {
                cx.err("spec-structure", at, format!("`{}` framing needs `{key}`", v.kind.value));
                None
            }
        }
    };
    Some(match v.kind.value.as_str() {
        "nibble_length" => Framing::NibbleLength { resync_pause_ms: u32::try_from(need(&v.resync_pause_ms, "resync_pause_ms", 1, 60_000)?).ok()? },
        "length_byte" => Framing::LengthByte {
            inter_byte_timeout_ms: u32::try_from(need(&v.inter_byte_timeout_ms, "inter_byte_timeout_ms", 1, 60_000)?).ok()?,
            resync_pause_ms: u32::try_from(need(&v.resync_pause_ms, "resync_pause_ms", 1, 60_000)?).ok()?,
            extension_threshold: u8::try_from(need(&v.extension_threshold, "extension_threshold", 1, 0xFF)?).ok()?,
        },
        _ => {
            let start_byte = u8::try_from(need(&v.start_byte, "start_byte", 0, 0xFF)?).ok()?;
            let length_bytes = u8::try_from(need(&v.length_bytes, "length_bytes", 1, 2)?).ok()?;
            let max_payload = u16::try_from(need(&v.max_payload, "max_payload", 1, 0xFFFF)?).ok()?;
            let length_counts = match &v.length_counts {
                Some(l) => cx.keyword(
                    l,
                    "length_counts",
                    |s| match s {
                        "payload" => Some(LengthCounts::Payload),
                        "payload_and_crc" => Some(LengthCounts::PayloadAndCrc),
                        "frame" => Some(LengthCounts::Frame),
                        _ => None,
                    },
                    "payload, payload_and_crc, frame",
                )?,
                None => LengthCounts::Payload,
            };
            let Some(crc) = &v.crc else {
                cx.err("spec-structure", at, "`start_length_crc` framing needs `crc`");
                return None;
            };
            let start_bits = match &v.start_byte_bits {
                Some(b) => {
                    let mut mask = |n: &Num, what: &str| cx.int_in::<u8>(n, &none, what, 1, 0xFF);
                    let bits = StartBits {
                        network: mask(&b.value.network, "network mask")?,
                        crc: mask(&b.value.crc, "crc flag")?,
                        long_length: mask(&b.value.long_length, "long_length flag")?,
                    };
                    if bits.network & bits.crc != 0 || bits.network & bits.long_length != 0 || bits.crc & bits.long_length != 0 {
                        cx.err("spec-structure", span(b), "the start byte's `network`, `crc` and `long_length` bits must not overlap");
                        return None;
                    }
                    if let Err(e) = bits.options(start_byte, length_bytes) {
                        cx.err("spec-value", span(b), format!("the default {e}"));
                        return None;
                    }
                    Some(bits)
                }
                None => None,
            };
            Framing::StartLengthCrc { start_byte, start_bits, length_bytes, length_counts, max_payload, crc: crc_params(cx, crc)? }
        }
    })
}

fn crc_params(cx: &mut Cx<'_>, c: &S<raw::Crc>) -> Option<CrcParams> {
    let none = Vars::new();
    let v = &c.value;
    let width: u8 = cx.int_in(&v.width, &none, "crc width", 8, 64)?;
    let max = if width == 64 { i64::MAX } else { (1_i64 << width) - 1 };
    let mut p = |n: &Num, what: &str| cx.int_in::<u64>(n, &none, what, 0, max);
    let (poly, init, xor_out, check) = (p(&v.poly, "poly")?, p(&v.init, "init")?, p(&v.xor_out, "xor_out")?, p(&v.check, "check")?);
    let little_endian = cx.keyword(
        &v.byte_order,
        "byte order",
        |s| match s {
            "little" => Some(true),
            "big" => Some(false),
            _ => None,
        },
        "little, big",
    )?;
    let mut covers = (false, false, false);
    for part in &v.covers.value {
        match part.value.as_str() {
            "start" => covers.0 = true,
            "length" => covers.1 = true,
            "payload" => covers.2 = true,
            other => cx.err("spec-value", span(part), format!("unknown CRC coverage `{other}`; expected start, length, payload")),
        }
    }
    Some(CrcParams {
        width,
        poly,
        init,
        reflect_in: v.reflect_in,
        reflect_out: v.reflect_out,
        xor_out,
        check,
        little_endian,
        covers_start: covers.0,
        covers_length: covers.1,
        covers_payload: covers.2,
        check_span: span(&v.check),
    })
}

fn host_rule(cx: &mut Cx<'_>, h: &S<raw::HostAccess>) -> Option<HostRule> {
    let v = &h.value;
    let read = cx.keyword(
        &v.read,
        "host read rule",
        |s| match s {
            "all" => Some(HostRead::All),
            "none" => Some(HostRead::None),
            "listed" => Some(HostRead::Listed),
            _ => None,
        },
        "all, none, listed",
    )?;
    let write = cx.keyword(
        &v.write,
        "host write rule",
        |s| match s {
            "all" => Some(HostWrite::All),
            "none" => Some(HostWrite::None),
            "listed" => Some(HostWrite::Listed),
            "same_as_can" => Some(HostWrite::SameAsCan),
            _ => None,
        },
        "all, none, listed, same_as_can",
    )?;
    let ranges = |cx: &mut Cx<'_>, list: &[S<raw::AccessRange>]| -> Vec<AccessRange> { list.iter().filter_map(|r| access_range(cx, r)).collect() };
    let readable = ranges(cx, &v.readable);
    let writable = ranges(cx, &v.writable);
    if read != HostRead::Listed && !readable.is_empty() {
        cx.err("spec-structure", span(&v.read), "`readable` is only used with `read: listed`");
    }
    if write != HostWrite::Listed && !writable.is_empty() {
        cx.err("spec-structure", span(&v.write), "`writable` is only used with `write: listed`");
    }
    Some(HostRule { read, write, readable, writable, description: v.description.clone().unwrap_or_default() })
}

fn access_range(cx: &mut Cx<'_>, r: &S<raw::AccessRange>) -> Option<AccessRange> {
    let none = Vars::new();
    let v = &r.value;
    let (from, to) = match (&v.index, &v.from, &v.to) {
        (Some(i), None, None) => {
            let i = cx.int_in(i, &none, "index", 1, 0xFFFF)?;
            (i, i)
        }
        (None, Some(f), Some(t)) => (cx.int_in(f, &none, "from", 1, 0xFFFF)?, cx.int_in(t, &none, "to", 1, 0xFFFF)?),
        _ => {
            cx.err("spec-structure", span(r), "an access range has either `index` or both `from` and `to`");
            return None;
        }
    };
    let when = match &v.when {
        Some(w) => cx.keyword(
            w,
            "condition",
            |s| match s {
                "always" => Some(WriteWhen::Always),
                "before_can_enabled" => Some(WriteWhen::BeforeCanEnabled),
                _ => None,
            },
            "always, before_can_enabled",
        )?,
        None => WriteWhen::Always,
    };
    let sub = match &v.sub {
        Some(s) => Some(cx.int_in(s, &none, "sub", 0, 254)?),
        None => None,
    };
    Some(AccessRange { from, to, sub, when, note: v.note.clone().unwrap_or_default(), span: span(r) })
}

fn command(cx: &mut Cx<'_>, c: &S<raw::Command>, framing: &Framing) -> Option<Command> {
    let none = Vars::new();
    let v = &c.value;
    let code_max: i64 = match framing {
        Framing::NibbleLength { .. } => 0xF,
        _ => 0xFF,
    };
    let code = match &v.code.value {
        Scalar::Str(s) if s.chars().count() == 1 && !s.starts_with(|ch: char| ch.is_ascii_digit()) => u32::from(s.chars().next().unwrap_or('\0')),
        _ => cx.int_in(&v.code, &none, "command code", 0, code_max)?,
    };
    if i64::from(code) > code_max {
        cx.err("spec-value", span(&v.code), format!("command code {code:#X} does not fit the {} framing (at most {code_max:#X})", framing.kind()));
        return None;
    }
    let code_param = match &v.code_param {
        Some(p) => Some(CodeParam {
            name: p.value.name.value.clone(),
            mask: cx.int_in(&p.value.mask, &none, "code_param mask", 1, code_max)?,
            range: match &p.value.range {
                Some(r) => Some((cx.int_in(&r.value.0, &none, "range start", 0, code_max)?, cx.int_in(&r.value.1, &none, "range end", 0, code_max)?)),
                None => None,
            },
            values: match &p.value.values {
                Some(list) => {
                    if p.value.range.is_some() {
                        cx.err("spec-structure", span(list), "`code_param` takes either `range` or `values`");
                    }
                    let mut v = Vec::new();
                    for n in &list.value {
                        v.push(cx.int_in(n, &none, "code parameter value", 0, code_max)?);
                    }
                    Some(v)
                }
                None => None,
            },
        }),
        None => None,
    };
    let direction = cx.keyword(
        &v.direction,
        "direction",
        |s| match s {
            "host_to_device" => Some(Direction::HostToDevice),
            "device_to_host" => Some(Direction::DeviceToHost),
            _ => None,
        },
        "host_to_device, device_to_host",
    )?;
    let kind = cx.keyword(
        &v.kind,
        "command kind",
        |s| match s {
            "request" => Some(CommandKind::Request),
            "response" => Some(CommandKind::Response),
            "command" => Some(CommandKind::Command),
            "ack" => Some(CommandKind::Ack),
            "indication" => Some(CommandKind::Indication),
            _ => None,
        },
        "request, response, command, ack, indication",
    )?;
    let fields = fields(cx, &v.fields, framing)?;
    let fixed: u32 = fields.iter().map(|f| f.ty.fixed_size()).sum();
    let tail_max = fields.iter().find_map(|f| match f.ty {
        FieldType::Tail { max } => Some(max),
        _ => None,
    });
    let len_int = |cx: &mut Cx<'_>, s: &Scalar, sp: &S<raw::Length>| -> Option<u32> {
        cx.int_in(&S { value: s.clone(), referenced: sp.referenced, defined: sp.defined }, &none, "length", 0, 0xFFFF)
    };
    let length = match &v.length {
        Some(l) => match &l.value {
            raw::Length::Fixed(n) => {
                let n = len_int(cx, n, l)?;
                (n, n)
            }
            raw::Length::Range { min, max } => (len_int(cx, min, l)?, len_int(cx, max, l)?),
        },
        None => (fixed, fixed + tail_max.unwrap_or(0)),
    };
    let ack = match &v.ack {
        Some(a) => Some(Ack {
            field: a.value.field.value.clone(),
            positive: cx.int(&a.value.positive, &none, "positive")?,
            negative: cx.int(&a.value.negative, &none, "negative")?,
            span: span(a),
        }),
        None => None,
    };
    let mut examples = Vec::new();
    for ex in &v.examples {
        let bytes = match &ex.value.bytes.value {
            Scalar::Str(s) => match hex_bytes(s, false) {
                Ok(b) => b.into_iter().flatten().collect(),
                Err(m) => {
                    cx.err("spec-value", span(&ex.value.bytes), m);
                    continue;
                }
            },
            Scalar::Int(i) if (0..=255).contains(i) => vec![u8::try_from(*i).unwrap_or(0)],
            other => {
                cx.err("spec-value", span(&ex.value.bytes), format!("example `bytes` must be hex bytes such as `33 12 50 04`, found {}", scalar_kind(other)));
                continue;
            }
        };
        let mut values = BTreeMap::new();
        for (name, val) in &ex.value.fields {
            // Strings for byte fields are hex bytes (`"81"` is one byte 0x81); for integer
            // fields they are expressions.
            let byte_field = fields.iter().any(|f| &f.name == name && matches!(f.ty, FieldType::Bytes(_) | FieldType::Tail { .. }));
            let parsed = match &val.value {
                Scalar::Int(i) => i64::try_from(*i).ok().map(ExampleValue::Int),
                Scalar::Str(s) if byte_field => hex_bytes(s, false).ok().map(|b| ExampleValue::Bytes(b.into_iter().flatten().collect())),
                Scalar::Str(s) => Expr::parse(s).and_then(|e| e.eval(&none, None)).ok().map(ExampleValue::Int),
                _ => None,
            };
            match parsed {
                Some(p) => {
                    values.insert(name.clone(), (p, span(val)));
                }
                None => cx.err("spec-value", span(val), format!("example value for `{name}` must be an integer or hex bytes")),
            }
        }
        examples.push(Example { bytes, fields: values, note: ex.value.note.clone().unwrap_or_default(), span: span(ex) });
    }
    Some(Command {
        name: v.name.value.clone(),
        code,
        code_param,
        direction,
        kind,
        reply: v.reply.as_ref().map(|r| r.value.clone()),
        length,
        length_code: match &v.length_code {
            Some(n) => Some(cx.int_in(n, &none, "length_code", 0, 0xFF)?),
            None => None,
        },
        ack,
        description: v.description.clone().unwrap_or_default(),
        fields,
        examples,
        modes: cx.modes(v.modes.as_ref(), &None),
        span: span(c),
        code_span: span(&v.code),
        length_span: v.length.as_ref().map_or(span(c), span),
        reply_span: v.reply.as_ref().map_or(span(c), span),
    })
}

fn fields(cx: &mut Cx<'_>, list: &[S<raw::Field>], framing: &Framing) -> Option<Vec<Field>> {
    let none = Vars::new();
    let mut out = Vec::new();
    let mut next = 0_u32;
    let mut ok = true;
    for f in list {
        let v = &f.value;
        let ty = match v.field_type.value.as_str() {
            "u8" => FieldType::Unsigned(1),
            "u16" => FieldType::Unsigned(2),
            "u24" => FieldType::Unsigned(3),
            "u32" => FieldType::Unsigned(4),
            "i8" => FieldType::Signed(1),
            "i16" => FieldType::Signed(2),
            "i32" => FieldType::Signed(4),
            "bytes" => match &v.size {
                Some(n) => FieldType::Bytes(cx.int_in(n, &none, "size", 1, 0xFFFF)?),
                None => {
                    cx.err("spec-structure", span(f), "a `bytes` field needs `size`");
                    ok = false;
                    continue;
                }
            },
            "tail" => FieldType::Tail {
                max: match &v.max {
                    Some(n) => cx.int_in(n, &none, "max", 0, 0xFFFF)?,
                    None => framing.max_data().saturating_sub(next),
                },
            },
            other => {
                cx.err(
                    "spec-value",
                    span(&v.field_type),
                    format!("unknown field type `{other}`; expected one of: u8, u16, u24, u32, i8, i16, i32, bytes, tail"),
                );
                ok = false;
                continue;
            }
        };
        if v.size.is_some() && !matches!(ty, FieldType::Bytes(_)) {
            cx.err("spec-structure", span(f), "`size` only applies to `bytes` fields");
        }
        if v.max.is_some() && !matches!(ty, FieldType::Tail { .. }) {
            cx.err("spec-structure", span(f), "`max` only applies to `tail` fields");
        }
        let big_endian = match &v.order {
            Some(o) => cx.keyword(
                o,
                "byte order",
                |s| match s {
                    "le" => Some(false),
                    "be" => Some(true),
                    _ => None,
                },
                "le, be",
            )?,
            None => false,
        };
        let at = match &v.at {
            Some(n) => cx.int_in(n, &none, "at", 0, 0xFFFF)?,
            None => next,
        };
        next = at + ty.fixed_size();
        out.push(Field {
            name: v.name.value.clone(),
            ty,
            big_endian,
            at,
            explicit_at: v.at.is_some(),
            description: v.description.clone().unwrap_or_default(),
            span: span(f),
        });
    }
    ok.then_some(out)
}
