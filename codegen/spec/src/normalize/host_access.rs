//! `serial.host_access`: the serial host's access rule, and each entry's host access derived from it.

use super::{Cx, span};
use crate::expr::Vars;
use crate::model::{AccessRange, HostRead, HostRule, HostWrite, Object};
use crate::raw::{self, S};
use crate::types::{Access, HostAccess, Sub0, WriteWhen};

/// Derives each entry's serial-host access from the device rule, unless the entry sets its own.
pub(super) fn apply_host_access(objects: &mut [Object], rule: Option<&HostRule>) {
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

pub(super) fn host_rule(cx: &mut Cx<'_>, h: &S<raw::HostAccess>) -> Option<HostRule> {
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
