//! `objects:`: templates and groups expanded into objects and their entries.

use super::{Cx, scalar_kind, span};
use crate::diag::Span;
use crate::expr::{Expr, Vars};
use crate::model::{Entry, EntrySpans, ModeSet, Object, Value};
use crate::raw::{self, Num, S, Scalar};
use crate::types::{Access, DataType, HostAccess, ObjectKind, Storage, Sub0, WriteWhen, snake_case};

pub(super) fn expand_objects(cx: &mut Cx<'_>, items: &[S<raw::Object>], vars: &Vars, out: &mut Vec<Object>) {
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
