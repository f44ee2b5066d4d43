//! `pdo:`: the PDO sets and default PDOs, and the CiA 301 PDO parameter objects generated from them.

use super::{Cx, span};
use crate::expr::{Expr, Vars};
use crate::model::{Entry, EntrySpans, Mapping, Object, Pdo, PdoConfig, PdoDir, PdoSet, Value};
use crate::raw::{self, Num, S};
use crate::types::{Access, DataType, HostAccess, ObjectKind, Storage, Sub0, WriteWhen, snake_case};

pub(super) fn pdo_config(cx: &mut Cx<'_>, p: &raw::Pdo) -> PdoConfig {
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
pub(super) fn pdo_objects(config: &PdoConfig, persistent: bool) -> Vec<Object> {
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
