//! What a binary EDS is made from: one flat list of dictionary entries with their values
//! resolved for one node-ID, and the header settings. Both a spec ([`Dictionary::from_device`])
//! and a CiA 306 EDS file ([`super::eds_import`]) lower to this, so one layout pass serves both.

use crate::eds::{ExportError, dummy_in_use, eds_access, objects_in, resolve_mode};
use crate::model::{Device, Value};
use crate::types::{Access, DataType, ObjectKind};

/// Header settings a file carries but a dictionary does not.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Settings {
    pub node_id: u8,
    pub bitrate_kbit: u16,
    /// FUNC bits (`coforge_beds::layout::func`).
    pub func: u32,
    /// The identification string (at most 96 bytes are kept).
    pub ident: String,
}

/// One entry, its values encoded as the device stores them (little-endian, strings as bytes).
#[derive(Debug, Clone, PartialEq)]
pub struct Item {
    pub index: u16,
    pub sub: u8,
    pub kind: ObjectKind,
    pub data_type: DataType,
    /// CiA 306 access, with `rww`/`rwr` for mapped process data.
    pub access: Access,
    pub pdo_mapping: bool,
    /// Bytes the value takes (a string's: its default's length, or its declared maximum).
    pub size: usize,
    pub default: Option<Vec<u8>>,
    /// The default depends on the node-ID (`$NODEID+0x180`); `default` holds it resolved.
    pub node_relative: bool,
    pub low: Option<Vec<u8>>,
    pub high: Option<Vec<u8>>,
}

impl Item {
    /// The dummy data-type entry `index` (0001h..0007h) in use: constant 0 of its type's size.
    pub fn dummy(index: u16) -> Option<Item> {
        let data_type = DataType::ALL.into_iter().find(|t| t.code() == index)?;
        let size = fixed_size(data_type)?;
        Some(Item {
            index,
            sub: 0,
            kind: ObjectKind::Var,
            data_type,
            access: Access::Const,
            pdo_mapping: true,
            size,
            default: Some(vec![0; size]),
            node_relative: false,
            low: None,
            high: None,
        })
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Dictionary {
    pub settings: Settings,
    /// Sorted by index, then sub-index.
    pub items: Vec<Item>,
}

/// Bytes of a value of `data_type` (strings and domains: none fixed).
pub fn fixed_size(data_type: DataType) -> Option<usize> {
    data_type.bits().map(|bits| bits.div_ceil(8) as usize)
}

/// A number in `size` little-endian bytes (two's complement, truncated); for a REAL entry,
/// that number as a real.
pub fn encode_int(data_type: DataType, n: i64, size: usize) -> Vec<u8> {
    match data_type {
        DataType::Real32 => (n as f32).to_le_bytes().to_vec(),
        DataType::Real64 => (n as f64).to_le_bytes().to_vec(),
        _ => {
            let mut bytes = n.to_le_bytes().to_vec();
            bytes.resize(size.max(8), if n < 0 { 0xFF } else { 0 });
            bytes.truncate(size);
            bytes
        }
    }
}

/// A spec value for `node_id`, encoded; `None` when it cannot be resolved.
fn encode_value(v: &Value, data_type: DataType, size: usize, node_id: u8) -> Option<Vec<u8>> {
    match v {
        Value::Int(_) => v.int_for(node_id).map(|n| encode_int(data_type, n, size)),
        Value::Real(x) => Some(match data_type {
            DataType::Real64 => x.to_le_bytes().to_vec(),
            _ => (*x as f32).to_le_bytes().to_vec(),
        }),
        Value::Str(s) => Some(s.as_bytes().to_vec()),
    }
}

impl Dictionary {
    /// The dictionary a CAN master sees of `d` in `mode`, values for `settings.node_id`.
    pub fn from_device(d: &Device, mode: Option<&str>, settings: Settings) -> Result<Dictionary, ExportError> {
        let mode = resolve_mode(d, mode)?;
        let mut items = Vec::new();
        for (o, entries) in objects_in(d, mode) {
            for e in entries {
                let declared = e.length.map(|l| l as usize);
                let text = match &e.default {
                    Some(Value::Str(s)) => Some(s.len()),
                    _ => None,
                };
                let size = fixed_size(e.data_type).or(declared.max(text)).unwrap_or(0);
                let value = |v: &Option<Value>| v.as_ref().and_then(|v| encode_value(v, e.data_type, size, settings.node_id));
                items.push(Item {
                    index: o.index,
                    sub: e.sub,
                    kind: o.kind,
                    data_type: e.data_type,
                    access: Access::parse(eds_access(d, o, e, mode)).unwrap_or(e.access),
                    pdo_mapping: e.pdo_mapping,
                    size,
                    default: value(&e.default),
                    node_relative: matches!(&e.default, Some(Value::Int(x)) if matches!(x.node_id_offset(), Ok(Some(_)))),
                    low: value(&e.low),
                    high: value(&e.high),
                });
            }
        }
        // Dummies a default PDO maps without the spec declaring them, as the EDS lists them.
        let undeclared: Vec<Item> =
            (1..=7_u16).filter(|&i| dummy_in_use(d, mode, i) && !items.iter().any(|it| it.index == i)).filter_map(Item::dummy).collect();
        items.extend(undeclared);
        items.sort_by_key(|i| (i.index, i.sub));
        Ok(Dictionary { settings, items })
    }

    pub fn item(&self, index: u16, sub: u8) -> Option<&Item> {
        self.items.iter().find(|i| (i.index, i.sub) == (index, sub))
    }

    /// An entry's default as a number (little-endian, at most 8 bytes).
    pub fn default_u64(&self, index: u16, sub: u8) -> Option<u64> {
        let bytes = self.item(index, sub)?.default.as_ref()?;
        let mut le = [0_u8; 8];
        le.iter_mut().zip(bytes).for_each(|(d, s)| *d = *s);
        Some(u64::from_le_bytes(le))
    }
}
