//! The spec file as written: a serde model of `spec/README.md`, with positions.
//!
//! Nothing here is interpreted; `normalize` turns it into the model that generators use.
//! Every struct denies unknown keys, so a typo is an error that points at its line.

use serde::Deserialize;
use serde_saphyr::Spanned;
use std::collections::BTreeMap;

/// A scalar as YAML gave it: numbers may be integers or expression strings.
#[derive(Debug, Clone, PartialEq)]
pub enum Scalar {
    Int(i128),
    Float(f64),
    Bool(bool),
    Str(String),
}

impl<'de> Deserialize<'de> for Scalar {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Scalar;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number, an expression or a string")
            }
            fn visit_i64<E>(self, v: i64) -> Result<Scalar, E> {
                Ok(Scalar::Int(v.into()))
            }
            fn visit_u64<E>(self, v: u64) -> Result<Scalar, E> {
                Ok(Scalar::Int(v.into()))
            }
            fn visit_i128<E>(self, v: i128) -> Result<Scalar, E> {
                Ok(Scalar::Int(v))
            }
            fn visit_f64<E>(self, v: f64) -> Result<Scalar, E> {
                Ok(Scalar::Float(v))
            }
            fn visit_bool<E>(self, v: bool) -> Result<Scalar, E> {
                Ok(Scalar::Bool(v))
            }
            fn visit_str<E>(self, v: &str) -> Result<Scalar, E> {
                Ok(Scalar::Str(v.to_string()))
            }
        }
        d.deserialize_any(V)
    }
}

pub type S<T> = Spanned<T>;
pub type Num = Spanned<Scalar>;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    pub format: S<u32>,
    pub device: S<Device>,
    #[serde(default)]
    pub node: Option<S<Node>>,
    #[serde(default)]
    pub hardware: Option<S<Hardware>>,
    #[serde(default)]
    pub modes: Vec<S<Mode>>,
    pub objects: Vec<S<Object>>,
    #[serde(default)]
    pub pdo: Option<S<Pdo>>,
    #[serde(default)]
    pub emergencies: Vec<S<Emergency>>,
    #[serde(default)]
    pub serial: Option<S<Serial>>,
    #[serde(default)]
    pub redundant_pairs: Vec<S<RedundantPair>>,
    #[serde(default)]
    pub errata: Vec<S<Erratum>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Device {
    pub name: S<String>,
    #[serde(default)]
    pub ident: Option<S<String>>,
    pub vendor: S<String>,
    pub vendor_id: Num,
    pub product_code: Num,
    pub revision: Num,
    pub profile: Num,
    #[serde(default)]
    pub description: Option<String>,
    /// Whether the SDO server does block transfer; `true` when absent.
    #[serde(default)]
    pub sdo_block_transfer: Option<bool>,
    pub datasheet: S<Datasheet>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Datasheet {
    pub title: String,
    pub version: String,
    pub file: String,
}

/// `node:`: how the CANopen node differs from a plain CiA 301 slave. Absent keys keep the
/// CiA 301 behaviour.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Node {
    #[serde(default)]
    pub restart_time_object: Option<Num>,
    #[serde(default)]
    pub bootup_object: Option<Num>,
    #[serde(default)]
    pub startup_object: Option<Num>,
    #[serde(default)]
    pub rpdo_deadline_monitoring: Option<bool>,
    #[serde(default)]
    pub combine_emcy_codes: Option<bool>,
    #[serde(default)]
    pub auto_save: Option<bool>,
    #[serde(default)]
    pub listed_emergencies_only: Option<bool>,
    #[serde(default)]
    pub tpdo_on_write: Option<bool>,
    #[serde(default)]
    pub remapping_object: Option<Num>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hardware {
    #[serde(default)]
    pub node_id: Option<S<Selector>>,
    #[serde(default)]
    pub can_bitrate: Option<S<Selector>>,
    #[serde(default)]
    pub serial_bitrate: Option<S<Selector>>,
    #[serde(default)]
    pub config_pins: Option<S<ConfigPins>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Selector {
    #[serde(default)]
    pub pins: Vec<S<String>>,
    #[serde(default)]
    pub object: Option<S<EntryRef>>,
    #[serde(default)]
    pub inverted: bool,
    #[serde(default)]
    pub unit: Option<S<String>>,
    #[serde(default)]
    pub range: Option<S<(Num, Num)>>,
    #[serde(default)]
    pub codes: Vec<S<Code>>,
    #[serde(default)]
    pub description: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EntryRef {
    pub index: Num,
    #[serde(default)]
    pub sub: Option<Num>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Code {
    pub code: Num,
    #[serde(default)]
    pub value: Option<Num>,
    #[serde(default)]
    pub exact: Option<Num>,
    #[serde(default)]
    pub reserved: bool,
    #[serde(default)]
    pub meaning: Option<String>,
    #[serde(default)]
    pub note: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConfigPins {
    pub pins: Vec<S<String>>,
    #[serde(default)]
    pub inverted: bool,
    #[serde(default)]
    pub settings: Vec<S<PinSetting>>,
    #[serde(default)]
    pub description: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PinSetting {
    pub pin: S<String>,
    pub level: S<String>,
    pub meaning: String,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mode {
    pub name: S<String>,
    #[serde(default)]
    pub description: Option<String>,
    #[serde(default)]
    pub select: Option<S<ModeSelect>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModeSelect {
    #[serde(default)]
    pub pins: BTreeMap<String, S<String>>,
    #[serde(default)]
    pub command: Option<S<String>>,
    #[serde(default)]
    pub object: Option<S<ModeObject>>,
}

/// A mode chosen by the value of an OD entry (CR3101's PDO operating mode 20F5).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModeObject {
    pub index: Num,
    #[serde(default)]
    pub sub: Option<Num>,
    pub value: Num,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Repeat {
    pub var: S<String>,
    #[serde(default)]
    pub count: Option<Num>,
    #[serde(default)]
    pub from: Option<Num>,
    #[serde(default)]
    pub to: Option<Num>,
}

/// Declares a struct that also carries the keys shared by VAR objects and sub-entries.
///
/// serde's `flatten` would lose both `deny_unknown_fields` and the value positions, so the
/// shared keys are spliced in by this macro and read back through [`EntryFields`].
macro_rules! with_entry_fields {
    ($(#[$m:meta])* pub struct $name:ident { $($(#[$fm:meta])* pub $f:ident: $t:ty,)* }) => {
        $(#[$m])*
        #[derive(Debug, Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct $name {
            $($(#[$fm])* pub $f: $t,)*
            #[serde(default)]
            pub name: Option<S<String>>,
            #[serde(default)]
            pub ident: Option<S<String>>,
            #[serde(default, rename = "type")]
            pub data_type: Option<S<String>>,
            #[serde(default)]
            pub length: Option<Num>,
            #[serde(default)]
            pub access: Option<S<String>>,
            #[serde(default)]
            pub host_access: Option<S<String>>,
            #[serde(default)]
            pub pdo_mapping: Option<S<bool>>,
            #[serde(default)]
            pub default: Option<Num>,
            #[serde(default)]
            pub low: Option<Num>,
            #[serde(default)]
            pub high: Option<Num>,
            #[serde(default)]
            pub unit: Option<S<String>>,
            #[serde(default)]
            pub storage: Option<S<String>>,
            #[serde(default)]
            pub description: Option<S<String>>,
            #[serde(default)]
            pub modes: Option<S<Vec<S<String>>>>,
            #[serde(default)]
            pub values: Option<S<Vec<Num>>>,
            #[serde(default)]
            pub writable_in: Option<S<Vec<S<String>>>>,
        }

        impl $name {
            pub fn fields(&self) -> EntryFields<'_> {
                EntryFields {
                    name: self.name.as_ref(),
                    ident: self.ident.as_ref(),
                    data_type: self.data_type.as_ref(),
                    length: self.length.as_ref(),
                    access: self.access.as_ref(),
                    host_access: self.host_access.as_ref(),
                    pdo_mapping: self.pdo_mapping.as_ref(),
                    default: self.default.as_ref(),
                    low: self.low.as_ref(),
                    high: self.high.as_ref(),
                    unit: self.unit.as_ref(),
                    storage: self.storage.as_ref(),
                    description: self.description.as_ref(),
                    modes: self.modes.as_ref(),
                    values: self.values.as_ref(),
                    writable_in: self.writable_in.as_ref(),
                }
            }
        }
    };
}

/// The keys shared by VAR objects and sub-entries, borrowed from either.
#[derive(Debug, Clone, Copy)]
pub struct EntryFields<'a> {
    pub name: Option<&'a S<String>>,
    pub ident: Option<&'a S<String>>,
    pub data_type: Option<&'a S<String>>,
    pub length: Option<&'a Num>,
    pub access: Option<&'a S<String>>,
    pub host_access: Option<&'a S<String>>,
    pub pdo_mapping: Option<&'a S<bool>>,
    pub default: Option<&'a Num>,
    pub low: Option<&'a Num>,
    pub high: Option<&'a Num>,
    pub unit: Option<&'a S<String>>,
    pub storage: Option<&'a S<String>>,
    pub description: Option<&'a S<String>>,
    pub modes: Option<&'a S<Vec<S<String>>>>,
    pub values: Option<&'a S<Vec<Num>>>,
    pub writable_in: Option<&'a S<Vec<S<String>>>>,
}

with_entry_fields! {
    /// An object, a template of objects (`repeat` + object keys) or a group (`repeat` + `objects`).
    pub struct Object {
        #[serde(default)]
        pub repeat: Option<S<Repeat>>,
        #[serde(default)]
        pub objects: Option<Vec<S<Object>>>,
        #[serde(default)]
        pub index: Option<Num>,
        #[serde(default)]
        pub kind: Option<S<String>>,
        #[serde(default)]
        pub sub0: Option<S<String>>,
        #[serde(default)]
        pub subs: Option<Vec<S<Entry>>>,
    }
}

with_entry_fields! {
    /// A sub-entry of an ARRAY or RECORD (or a template of them with `repeat`).
    pub struct Entry {
        #[serde(default)]
        pub repeat: Option<S<Repeat>>,
        #[serde(default)]
        pub sub: Option<Num>,
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pdo {
    #[serde(default)]
    pub rpdo: Option<S<PdoSet>>,
    #[serde(default)]
    pub tpdo: Option<S<PdoSet>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PdoSet {
    pub comm_subs: S<Vec<Num>>,
    pub max_mapped: Num,
    #[serde(default)]
    pub comm_access: Option<S<String>>,
    #[serde(default)]
    pub mapping_access: Option<S<String>>,
    #[serde(default)]
    pub writable_in: Option<S<Vec<S<String>>>>,
    #[serde(default)]
    pub pdos: Vec<S<PdoDefault>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PdoDefault {
    pub number: Num,
    pub cob_id: Num,
    pub transmission_type: Num,
    #[serde(default)]
    pub inhibit_time: Option<Num>,
    #[serde(default)]
    pub event_timer: Option<Num>,
    #[serde(default)]
    pub sync_start: Option<Num>,
    #[serde(default)]
    pub map: Vec<S<MapEntry>>,
    #[serde(default)]
    pub modes: Option<S<Vec<S<String>>>>,
    #[serde(default)]
    pub description: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapEntry {
    pub index: Num,
    pub sub: Num,
    pub bits: Num,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Emergency {
    pub name: S<String>,
    pub code: Num,
    pub error_register: Num,
    pub manufacturer: S<Scalar>,
    #[serde(default)]
    pub description: Option<String>,
    #[serde(default)]
    pub trigger: Option<String>,
    #[serde(default)]
    pub nmt: Option<S<String>>,
    #[serde(default)]
    pub outputs: Option<S<String>>,
    #[serde(default)]
    pub reset: Option<String>,
    #[serde(default)]
    pub enabled_by: Option<Num>,
    #[serde(default)]
    pub event: Option<S<String>>,
    #[serde(default)]
    pub example: Option<S<Scalar>>,
    #[serde(default)]
    pub modes: Option<S<Vec<S<String>>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Serial {
    #[serde(default)]
    pub settings: Option<S<SerialSettings>>,
    pub framing: S<Framing>,
    #[serde(default)]
    pub host_access: Option<S<HostAccess>>,
    #[serde(default)]
    pub error_bits: Vec<S<ErrorBit>>,
    #[serde(default)]
    pub commands: Vec<S<Command>>,
    #[serde(default)]
    pub description: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SerialSettings {
    pub data_bits: u8,
    pub parity: S<String>,
    pub stop_bits: u8,
}

/// All framing parameters; which ones apply depends on `kind` (checked when normalising).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Framing {
    pub kind: S<String>,
    #[serde(default)]
    pub resync_pause_ms: Option<Num>,
    #[serde(default)]
    pub inter_byte_timeout_ms: Option<Num>,
    #[serde(default)]
    pub extension_threshold: Option<Num>,
    #[serde(default)]
    pub start_byte: Option<Num>,
    #[serde(default)]
    pub start_byte_bits: Option<S<StartByteBits>>,
    #[serde(default)]
    pub length_bytes: Option<Num>,
    #[serde(default)]
    pub length_counts: Option<S<String>>,
    #[serde(default)]
    pub max_payload: Option<Num>,
    #[serde(default)]
    pub crc: Option<S<Crc>>,
    #[serde(default)]
    pub description: Option<String>,
}

/// Bit fields of a start byte that also carries frame options (CANopenIA 6.1).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StartByteBits {
    pub network: Num,
    pub crc: Num,
    pub long_length: Num,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Crc {
    pub width: Num,
    pub poly: Num,
    pub init: Num,
    pub reflect_in: bool,
    pub reflect_out: bool,
    pub xor_out: Num,
    pub check: Num,
    pub byte_order: S<String>,
    pub covers: S<Vec<S<String>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HostAccess {
    pub read: S<String>,
    pub write: S<String>,
    #[serde(default)]
    pub readable: Vec<S<AccessRange>>,
    #[serde(default)]
    pub writable: Vec<S<AccessRange>>,
    #[serde(default)]
    pub description: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AccessRange {
    #[serde(default)]
    pub index: Option<Num>,
    #[serde(default)]
    pub sub: Option<Num>,
    #[serde(default)]
    pub from: Option<Num>,
    #[serde(default)]
    pub to: Option<Num>,
    #[serde(default)]
    pub when: Option<S<String>>,
    #[serde(default)]
    pub note: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ErrorBit {
    pub bit: Num,
    pub name: S<String>,
    #[serde(default)]
    pub description: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Command {
    pub name: S<String>,
    pub code: Num,
    #[serde(default)]
    pub code_param: Option<S<CodeParam>>,
    pub direction: S<String>,
    pub kind: S<String>,
    #[serde(default)]
    pub reply: Option<S<String>>,
    #[serde(default)]
    pub length: Option<S<Length>>,
    #[serde(default)]
    pub length_code: Option<Num>,
    #[serde(default)]
    pub ack: Option<S<Ack>>,
    #[serde(default)]
    pub description: Option<String>,
    #[serde(default)]
    pub fields: Vec<S<Field>>,
    #[serde(default)]
    pub examples: Vec<S<Example>>,
    #[serde(default)]
    pub modes: Option<S<Vec<S<String>>>>,
}

/// `length: 3` or `length: { min: 1, max: 8 }`.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub enum Length {
    Fixed(Scalar),
    Range { min: Scalar, max: Scalar },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CodeParam {
    pub name: S<String>,
    pub mask: Num,
    #[serde(default)]
    pub range: Option<S<(Num, Num)>>,
    #[serde(default)]
    pub values: Option<S<Vec<Num>>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ack {
    pub field: S<String>,
    pub positive: Num,
    pub negative: Num,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Field {
    pub name: S<String>,
    #[serde(rename = "type")]
    pub field_type: S<String>,
    #[serde(default)]
    pub order: Option<S<String>>,
    #[serde(default)]
    pub size: Option<Num>,
    #[serde(default)]
    pub max: Option<Num>,
    #[serde(default)]
    pub at: Option<Num>,
    #[serde(default)]
    pub description: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Example {
    pub bytes: S<Scalar>,
    #[serde(default)]
    pub fields: BTreeMap<String, S<Scalar>>,
    #[serde(default)]
    pub note: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RedundantPair {
    pub primary: Num,
    pub shadow: Num,
    #[serde(default)]
    pub description: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Erratum {
    pub id: S<String>,
    #[serde(rename = "where")]
    pub location: S<String>,
    pub datasheet: S<String>,
    pub choice: S<String>,
    pub reason: S<String>,
}
