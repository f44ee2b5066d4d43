//! EDS export (CiA 306 electronic data sheet), one file per operating mode.
//!
//! The output is deterministic: no creation timestamps, objects in index order, so that the
//! files in `target/dist/` only change when the spec does.

use crate::model::{Device, Entry, Object, PdoDir, Value, in_mode};
use crate::types::{Access, ObjectKind};
use std::fmt::{self, Write as _};

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExportError(pub String);

impl fmt::Display for ExportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ExportError {}

/// Checks `mode` against the device: required exactly when the device has modes.
pub fn resolve_mode<'a>(d: &Device, mode: Option<&'a str>) -> Result<Option<&'a str>, ExportError> {
    let names: Vec<&str> = d.modes.iter().map(|m| m.name.as_str()).collect();
    match mode {
        None if names.is_empty() => Ok(None),
        None => Err(ExportError(format!("{} has operating modes; choose one with --mode ({})", d.identity.name, names.join(", ")))),
        Some(m) if names.contains(&m) => Ok(Some(m)),
        Some(m) if names.is_empty() => Err(ExportError(format!("{} has no operating modes, so --mode {m} does not apply", d.identity.name))),
        Some(m) => Err(ExportError(format!("unknown mode `{m}`; {} has: {}", d.identity.name, names.join(", ")))),
    }
}

/// The file name `coforge xtask dist` uses for a device (and mode).
pub fn file_name(d: &Device, mode: Option<&str>) -> String {
    match mode {
        Some(m) => format!("{}-{m}.eds", d.identity.ident),
        None => format!("{}.eds", d.identity.ident),
    }
}

/// Objects and entries a CAN master sees in `mode` (entries with access `none` are hidden).
pub(crate) fn objects_in<'a>(d: &'a Device, mode: Option<&'a str>) -> impl Iterator<Item = (&'a Object, Vec<&'a Entry>)> + 'a {
    d.objects
        .iter()
        .filter(move |o| in_mode(&o.modes, mode))
        .map(move |o| (o, o.entries.iter().filter(|e| in_mode(&e.modes, mode) && e.access != Access::None).collect::<Vec<_>>()))
        .filter(|(_, entries)| !entries.is_empty())
}

/// Dummy entries 0x0001..0x0007 are declared through `[DummyUsage]`, not as sections.
fn is_dummy(o: &Object) -> bool {
    o.index <= 0x0007
}

/// Whether the dummy data type `index` (0001h..0007h) is in use in `mode`: the spec declares
/// it, or a default PDO of this mode maps it.
pub(crate) fn dummy_in_use(d: &Device, mode: Option<&str>, index: u16) -> bool {
    let mapped = d.pdo.pdos.iter().filter(|p| in_mode(&p.modes, mode)).any(|p| p.map.iter().any(|m| m.index == index));
    mapped || objects_in(d, mode).any(|(o, _)| o.index == index)
}

/// CiA 306 access type: mappable rw entries become `rww` (mapped into an RPDO) or `rwr`
/// (mapped into a TPDO) according to the default mappings.
pub fn eds_access(d: &Device, o: &Object, e: &Entry, mode: Option<&str>) -> &'static str {
    if e.access != Access::Rw || !e.pdo_mapping {
        return e.access.name();
    }
    let mapped_in =
        |dir: PdoDir| d.pdo.pdos.iter().filter(|p| p.dir == dir && in_mode(&p.modes, mode)).any(|p| p.map.iter().any(|m| m.index == o.index && m.sub == e.sub));
    if mapped_in(PdoDir::Rx) {
        "rww"
    } else if mapped_in(PdoDir::Tx) {
        "rwr"
    } else {
        "rw"
    }
}

/// The `DefaultValue=` text: `$NODEID+0x180` for node-relative values.
pub fn eds_value(v: &Value) -> String {
    match v {
        Value::Int(e) => match e.node_id_offset() {
            Ok(Some(k)) => format!("$NODEID+0x{k:X}"),
            _ => match e.eval(&Default::default(), None) {
                Ok(n) if !(0..10).contains(&n) => format!("0x{:X}", n),
                Ok(n) => n.to_string(),
                Err(_) => String::new(),
            },
        },
        Value::Real(x) => format!("{x}"),
        Value::Str(s) => s.clone(),
    }
}

fn single_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn write_entry(out: &mut String, d: &Device, o: &Object, e: &Entry, mode: Option<&str>) {
    let _ = writeln!(out, "ParameterName={}", single_line(&e.name));
    let _ = writeln!(out, "ObjectType=0x{:X}", if o.kind == ObjectKind::Domain { ObjectKind::Domain.code() } else { ObjectKind::Var.code() });
    let _ = writeln!(out, "DataType=0x{:04X}", e.data_type.code());
    let _ = writeln!(out, "AccessType={}", eds_access(d, o, e, mode));
    if let Some(v) = &e.default {
        let _ = writeln!(out, "DefaultValue={}", eds_value(v));
    }
    if let Some(v) = &e.low {
        let _ = writeln!(out, "LowLimit={}", eds_value(v));
    }
    if let Some(v) = &e.high {
        let _ = writeln!(out, "HighLimit={}", eds_value(v));
    }
    let _ = writeln!(out, "PDOMapping={}", u8::from(e.pdo_mapping));
}

/// An EDS object list section and which indices belong to it.
type ObjectList = (&'static str, fn(u16) -> bool);

/// Renders the EDS of a device in one mode (`None` for devices without modes).
pub fn export(d: &Device, mode: Option<&str>) -> Result<String, ExportError> {
    let mode = resolve_mode(d, mode)?;
    let id = &d.identity;
    let mut out = String::new();
    let mode_text = mode.map(|m| format!(" ({m} mode)")).unwrap_or_default();
    let _ = writeln!(out, "[FileInfo]");
    let _ = writeln!(out, "FileName={}", file_name(d, mode));
    let _ = writeln!(out, "FileVersion=1\nFileRevision=0\nEDSVersion=4.0");
    let _ = writeln!(
        out,
        "Description={}{mode_text}, generated by coforge from {} {}",
        single_line(&id.name),
        single_line(&id.datasheet_title),
        single_line(&id.datasheet_version)
    );
    let _ = writeln!(out, "CreatedBy=coforge {}", env!("CARGO_PKG_VERSION"));
    let _ = writeln!(out);

    let pdos_in = |dir: PdoDir| d.pdo.pdos.iter().filter(|p| p.dir == dir && in_mode(&p.modes, mode)).count();
    let rates: Vec<i64> = d.hardware.can_bitrate.as_ref().map(|s| s.codes.iter().filter_map(|c| c.value).collect()).unwrap_or_default();
    let _ = writeln!(out, "[DeviceInfo]");
    let _ = writeln!(out, "VendorName={}", single_line(&id.vendor));
    let _ = writeln!(out, "VendorNumber=0x{:X}", id.vendor_id);
    let _ = writeln!(out, "ProductName={}", single_line(&id.name));
    let _ = writeln!(out, "ProductNumber=0x{:X}", id.product_code);
    let _ = writeln!(out, "RevisionNumber=0x{:X}", id.revision);
    let _ = writeln!(out, "OrderCode={}", single_line(&id.name));
    for rate in [10, 20, 50, 125, 250, 500, 800, 1000] {
        // Without a bit-rate table (configured elsewhere), every standard rate is possible.
        let _ = writeln!(out, "BaudRate_{rate}={}", u8::from(rates.is_empty() || rates.contains(&rate)));
    }
    let _ = writeln!(out, "SimpleBootUpMaster=0\nSimpleBootUpSlave=1\nGranularity=8\nDynamicChannelsSupported=0\nGroupMessaging=0");
    let _ = writeln!(out, "NrOfRXPDO={}\nNrOfTXPDO={}", pdos_in(PdoDir::Rx), pdos_in(PdoDir::Tx));
    let lss = d.hardware.node_id.as_ref().is_some_and(|s| s.codes.iter().any(|c| c.code == 0 && c.meaning.contains("LSS")));
    let _ = writeln!(out, "LSS_Supported={}", u8::from(lss));
    let _ = writeln!(out);

    let objects: Vec<_> = objects_in(d, mode).collect();
    let _ = writeln!(out, "[DummyUsage]");
    for i in 1..=7_u16 {
        let _ = writeln!(out, "Dummy{i:04X}={}", u8::from(dummy_in_use(d, mode, i)));
    }
    let _ = writeln!(out);

    let lists: [ObjectList; 3] = [
        ("MandatoryObjects", |i| matches!(i, 0x1000 | 0x1001 | 0x1018)),
        ("OptionalObjects", |i| (0x1000..=0x1FFF).contains(&i) && !matches!(i, 0x1000 | 0x1001 | 0x1018) || i >= 0x6000),
        ("ManufacturerObjects", |i| (0x2000..=0x5FFF).contains(&i)),
    ];
    for (title, belongs) in lists {
        let members: Vec<u16> = objects.iter().map(|(o, _)| o.index).filter(|&i| belongs(i)).collect();
        let _ = writeln!(out, "[{title}]");
        let _ = writeln!(out, "SupportedObjects={}", members.len());
        for (n, index) in members.iter().enumerate() {
            let _ = writeln!(out, "{}=0x{index:04X}", n + 1);
        }
        let _ = writeln!(out);
    }

    for (o, entries) in objects.iter().filter(|(o, _)| !is_dummy(o)) {
        let _ = writeln!(out, "[{:04X}]", o.index);
        if o.kind.has_subs() {
            let _ = writeln!(out, "ParameterName={}", single_line(&o.name));
            let _ = writeln!(out, "ObjectType=0x{:X}", o.kind.code());
            let _ = writeln!(out, "SubNumber={}", entries.len());
            let _ = writeln!(out);
            for e in entries {
                let _ = writeln!(out, "[{:04X}sub{:X}]", o.index, e.sub);
                write_entry(&mut out, d, o, e, mode);
                let _ = writeln!(out);
            }
        } else if let Some(e) = entries.first() {
            write_entry(&mut out, d, o, e, mode);
            let _ = writeln!(out);
        }
    }
    Ok(out)
}

/// The object dictionary of one mode as JSON, with defaults resolved for `node_id`: what
/// a master importing our EDS must see. Used by the interoperability tests.
pub fn model_json(d: &Device, mode: Option<&str>, node_id: u8) -> Result<String, ExportError> {
    let mode = resolve_mode(d, mode)?;
    let mut entries = Vec::new();
    for (o, es) in objects_in(d, mode) {
        for e in es {
            let default = match &e.default {
                None => serde_json::Value::Null,
                Some(Value::Str(s)) => serde_json::Value::from(s.as_str()),
                Some(Value::Real(x)) => serde_json::Value::from(*x),
                Some(v @ Value::Int(_)) => v.int_for(node_id).map_or(serde_json::Value::Null, serde_json::Value::from),
            };
            entries.push(serde_json::json!({
                "index": o.index,
                "sub": e.sub,
                "object_kind": o.kind.name(),
                "name": e.name,
                "data_type": e.data_type.code(),
                "access": eds_access(d, o, e, mode),
                "pdo_mapping": e.pdo_mapping,
                "host_access": e.host_access.name(),
                "host_write_before_can_enabled": e.host_write_when == crate::types::WriteWhen::BeforeCanEnabled,
                "storage": e.storage.name(),
                "default": default,
                "dummy": is_dummy(o),
            }));
        }
    }
    let doc = serde_json::json!({ "device": d.identity.name, "mode": mode, "node_id": node_id, "entries": entries });
    serde_json::to_string_pretty(&doc).map_err(|e| ExportError(e.to_string()))
}

/// A summary for tools: names, modes and the EDS file of each mode.
pub fn info_json(d: &Device) -> String {
    let modes: Vec<Option<&str>> = d.mode_names();
    let eds: Vec<serde_json::Value> = modes.iter().map(|m| serde_json::json!({ "mode": m, "file": file_name(d, *m) })).collect();
    let doc = serde_json::json!({
        "name": d.identity.name,
        "ident": d.identity.ident,
        "modes": d.modes.iter().map(|m| m.name.as_str()).collect::<Vec<_>>(),
        "eds": eds,
        "objects": d.objects.len(),
        "entries": d.objects.iter().map(|o| o.entries.len()).sum::<usize>(),
        "pdos": d.pdo.pdos.len(),
        "emergencies": d.emergencies.len(),
        "serial_commands": d.serial.as_ref().map_or(0, |s| s.commands.len()),
        "errata": d.errata.len(),
    });
    serde_json::to_string_pretty(&doc).unwrap_or_default()
}
