//! Reads a CiA 306 EDS file into a [`Dictionary`]: how the vendor's own EDS files become
//! test input for the binary EDS layout, and how `coforge beds --from-eds` works.

use super::dictionary::{Dictionary, Item, Settings, encode_int, fixed_size};
use crate::types::{Access, DataType, ObjectKind};
use ini::{Ini, ParseOption, Properties};
use std::collections::HashMap;

/// Why an EDS could not be read, naming the section.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImportError(pub String);

impl std::fmt::Display for ImportError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ImportError {}

fn number(text: &str) -> Option<i64> {
    let t = text.trim();
    let (neg, t) = t.strip_prefix('-').map_or((false, t), |rest| (true, rest));
    let n = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(hex) => i64::from_str_radix(hex, 16).ok()?,
        None => t.parse().ok()?,
    };
    Some(if neg { -n } else { n })
}

/// An integer value: a number, or `$NODEID` plus or minus a number in either order.
fn int_value(text: &str, node_id: u8) -> Option<i64> {
    let t: String = text.chars().filter(|c| !c.is_whitespace()).collect();
    let upper = t.to_ascii_uppercase();
    let Some(at) = upper.find("$NODEID") else { return number(&t) };
    let rest = format!("{}{}", &t[..at], &t[at + "$NODEID".len()..]);
    let rest = rest.trim_matches('+');
    let offset = if rest.is_empty() { 0 } else { number(rest)? };
    Some(i64::from(node_id) + offset)
}

fn key<'a>(p: &'a Properties, name: &str) -> Option<&'a str> {
    p.iter().find(|(k, _)| k.eq_ignore_ascii_case(name)).map(|(_, v)| v.trim())
}

fn data_type(code: u16) -> Option<DataType> {
    DataType::ALL.into_iter().find(|t| t.code() == code)
}

fn item(section: &str, p: &Properties, index: u16, sub: u8, kind: ObjectKind, node_id: u8) -> Result<Item, ImportError> {
    let err = |what: &str| ImportError(format!("[{section}]: {what}"));
    let code = key(p, "DataType").and_then(number).ok_or_else(|| err("no DataType"))?;
    let data_type = u16::try_from(code).ok().and_then(data_type).ok_or_else(|| err(&format!("unknown DataType 0x{code:04X}")))?;
    let access_text = key(p, "AccessType").unwrap_or("").to_ascii_lowercase();
    let access = Access::parse(&access_text).filter(|a| *a != Access::None).ok_or_else(|| err(&format!("unknown AccessType `{access_text}`")))?;
    let text = |name: &str| key(p, name).filter(|v| !v.is_empty());
    let (size, default, low, high) = match fixed_size(data_type) {
        Some(size) => {
            let int = |name: &str| -> Result<Option<Vec<u8>>, ImportError> {
                text(name)
                    .map(|v| int_value(v, node_id).map(|n| encode_int(data_type, n, size)).ok_or_else(|| err(&format!("{name} `{v}` is not a number"))))
                    .transpose()
            };
            (size, int("DefaultValue")?, int("LowLimit")?, int("HighLimit")?)
        }
        None => {
            let bytes = text("DefaultValue").map(|v| v.as_bytes().to_vec());
            (bytes.as_ref().map_or(0, Vec::len), bytes, None, None)
        }
    };
    let pdo_mapping = key(p, "PDOMapping").and_then(number).unwrap_or(0) != 0;
    let node_relative = text("DefaultValue").is_some_and(|v| v.to_ascii_uppercase().contains("$NODEID"));
    Ok(Item { index, sub, kind, data_type, access, pdo_mapping, size, default, node_relative, low, high })
}

/// The dummy entries a `[DummyUsage]` section declares in use.
fn dummies(ini: &Ini) -> Vec<Item> {
    let Some(usage) = ini.iter().find(|(s, _)| s.is_some_and(|s| s.eq_ignore_ascii_case("DummyUsage"))).map(|(_, p)| p) else { return Vec::new() };
    (1..=7_u16).filter(|i| key(usage, &format!("Dummy{i:04X}")).and_then(number) == Some(1)).filter_map(Item::dummy).collect()
}

/// Reads every object section (`[1018]`, `[1018sub3]`) of an EDS; values for `settings.node_id`.
pub fn import(text: &str, settings: Settings) -> Result<Dictionary, ImportError> {
    let option = ParseOption { enabled_quote: false, enabled_escape: false, ..ParseOption::default() };
    let ini = Ini::load_from_str_opt(text, option).map_err(|e| ImportError(format!("not an EDS: {e}")))?;
    let sections: HashMap<String, &Properties> = ini.iter().filter_map(|(s, p)| Some((s?.to_ascii_lowercase(), p))).collect();
    let mut items = dummies(&ini);
    for (name, p) in &sections {
        let Some(index) = (name.len() == 4).then(|| u16::from_str_radix(name, 16).ok()).flatten() else { continue };
        let object_type = key(p, "ObjectType").and_then(number).unwrap_or(7);
        let kind = match object_type {
            7 => ObjectKind::Var,
            8 => ObjectKind::Array,
            9 => ObjectKind::Record,
            2 => ObjectKind::Domain,
            other => return Err(ImportError(format!("[{name}]: ObjectType 0x{other:X} is not supported"))),
        };
        if !kind.has_subs() {
            items.push(item(name, p, index, 0, kind, settings.node_id)?);
            continue;
        }
        for (sub_name, sp) in &sections {
            let Some(sub) = sub_name.strip_prefix(name.as_str()).and_then(|s| s.strip_prefix("sub")).and_then(|s| u8::from_str_radix(s, 16).ok()) else {
                continue;
            };
            items.push(item(sub_name, sp, index, sub, kind, settings.node_id)?);
        }
    }
    items.sort_by_key(|i| (i.index, i.sub));
    Ok(Dictionary { settings, items })
}

/// The identification string the vendor's tool writes: `'<file name>' <date> <time> by
/// <ModifiedBy>`, the file name from `[FileInfo] FileName` without its path and `.eds`. The
/// date and time are when the tool ran; without `stamp` the EDS's modification date is used.
pub fn vendor_ident(text: &str, stamp: Option<&str>) -> String {
    let option = ParseOption { enabled_quote: false, enabled_escape: false, ..ParseOption::default() };
    let ini = Ini::load_from_str_opt(text, option).unwrap_or_default();
    let info = ini.iter().find(|(s, _)| s.is_some_and(|s| s.eq_ignore_ascii_case("FileInfo"))).map(|(_, p)| p);
    let field = |name: &str| info.and_then(|p| key(p, name)).unwrap_or("");
    let path = field("FileName");
    let file = path.rsplit(['\\', '/']).next().unwrap_or(path);
    let base = file.strip_suffix(".eds").or_else(|| file.strip_suffix(".EDS")).unwrap_or(file);
    let stamp = stamp.map_or_else(|| format!("{} {}", field("ModificationDate"), field("ModificationTime")), str::to_string);
    format!("'{base}' {stamp} by {}", field("ModifiedBy"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_with_the_node_id() {
        assert_eq!(int_value("$NODEID+0x180", 3), Some(0x183));
        assert_eq!(int_value("0x200 + $NODEID", 3), Some(0x203));
        assert_eq!(int_value("$NODEID", 5), Some(5));
        assert_eq!(int_value("-12", 5), Some(-12));
        assert_eq!(int_value("0xFFFFFFFF", 5), Some(0xFFFF_FFFF));
        assert_eq!(int_value("fast", 5), None);
    }
}
