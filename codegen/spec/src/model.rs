//! The normalised device model: templates expanded, expressions parsed and bound, PDO
//! parameter objects generated, everything sorted. Generators (code, EDS, docs) read only this.

use crate::diag::Span;
use crate::expr::Expr;
use crate::types::{Access, DataType, EmcyEvent, HostAccess, NmtState, ObjectKind, Storage, Sub0, WriteWhen};
use std::collections::{BTreeMap, BTreeSet};

#[derive(Debug, Clone)]
pub struct Device {
    pub identity: Identity,
    /// The spec's `node:` section (all defaults without one).
    pub node: NodeSettings,
    /// Where each object setting of `node:` stands in the spec, for diagnostics.
    pub node_spans: NodeSpans,
    pub hardware: Hardware,
    pub modes: Vec<Mode>,
    /// Sorted by index, then by mode set.
    pub objects: Vec<Object>,
    pub pdo: PdoConfig,
    pub emergencies: Vec<Emergency>,
    pub serial: Option<Serial>,
    pub redundant_pairs: Vec<RedundantPair>,
    pub errata: Vec<Erratum>,
}

#[derive(Debug, Clone)]
pub struct Identity {
    pub name: String,
    /// `name` in snake_case: crate, module and file names.
    pub ident: String,
    pub vendor: String,
    pub vendor_id: u32,
    pub product_code: u32,
    pub revision: u32,
    pub profile: u16,
    pub description: String,
    /// Whether the SDO server does block transfer (CiA 301 7.2.4.3.9..16). Without it a block
    /// request is refused with abort 0504 0001h and the code is left out of the image.
    pub sdo_block_transfer: bool,
    pub datasheet_title: String,
    pub datasheet_version: String,
    pub datasheet_file: String,
    pub span: Span,
}

/// How the device's CANopen node differs from a plain CiA 301 slave (the spec's `node:`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeSettings {
    pub restart_time_object: Option<u16>,
    pub bootup_object: Option<u16>,
    pub startup_object: Option<u16>,
    pub rpdo_deadline_monitoring: bool,
    pub combine_emcy_codes: bool,
    pub auto_save: bool,
    /// Stack events send only the emergencies the spec lists (no CiA 301 defaults).
    pub listed_emergencies_only: bool,
    /// A write of an entry a valid TPDO maps triggers the TPDO (else the device does).
    pub tpdo_on_write: bool,
    /// An UNSIGNED8 object whose value 0 refuses every write of a PDO mapping.
    pub remapping_object: Option<u16>,
}

/// Plain CiA 301: no device-specific objects, RPDO deadline monitoring on, emergency
/// manufacturer bytes not combined, persistent entries saved only through 1010, the CiA 301
/// emergency for a stack event the spec lists none for, TPDOs triggered by writes of what they
/// map, PDO mappings writable as CiA 301 alone says.
impl Default for NodeSettings {
    fn default() -> Self {
        NodeSettings {
            restart_time_object: None,
            bootup_object: None,
            startup_object: None,
            rpdo_deadline_monitoring: true,
            combine_emcy_codes: false,
            auto_save: false,
            listed_emergencies_only: false,
            tpdo_on_write: true,
            remapping_object: None,
        }
    }
}

impl NodeSettings {
    /// The settings that name an object, by spec key: the node reads sub 0 of each at run time.
    pub fn objects(&self) -> [(&'static str, Option<u16>); 4] {
        [
            ("restart_time_object", self.restart_time_object),
            ("bootup_object", self.bootup_object),
            ("startup_object", self.startup_object),
            ("remapping_object", self.remapping_object),
        ]
    }
}

/// Positions of the object settings in `node:` ([`Span::NONE`] where absent).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NodeSpans {
    pub restart_time_object: Span,
    pub bootup_object: Span,
    pub startup_object: Span,
    pub remapping_object: Span,
}

impl NodeSpans {
    /// The position of an object setting by its spec key (as in [`NodeSettings::objects`]).
    pub fn of(&self, key: &str) -> Span {
        match key {
            "restart_time_object" => self.restart_time_object,
            "bootup_object" => self.bootup_object,
            "startup_object" => self.startup_object,
            "remapping_object" => self.remapping_object,
            _ => Span::NONE,
        }
    }
}

/// The modes an item exists in; `None` means every mode.
pub type ModeSet = Option<BTreeSet<String>>;

/// Whether two mode sets can be active at the same time.
pub fn modes_overlap(a: &ModeSet, b: &ModeSet) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => !a.is_disjoint(b),
        _ => true,
    }
}

pub fn in_mode(set: &ModeSet, mode: Option<&str>) -> bool {
    match (set, mode) {
        (None, _) | (_, None) => true,
        (Some(s), Some(m)) => s.contains(m),
    }
}

#[derive(Debug, Clone, Default)]
pub struct Hardware {
    pub node_id: Option<Selector>,
    pub can_bitrate: Option<Selector>,
    pub serial_bitrate: Option<Selector>,
    pub config_pins: Option<ConfigPins>,
}

#[derive(Debug, Clone)]
pub enum SelectorSource {
    Pins {
        pins: Vec<String>,
        inverted: bool,
    },
    Object {
        index: u16,
        sub: u8,
    },
    /// Set by configuration that is not part of the spec (CANopenIA's binary EDS).
    Configuration,
}

#[derive(Debug, Clone)]
pub struct Selector {
    pub source: SelectorSource,
    pub unit: Option<String>,
    pub range: Option<(i64, i64)>,
    pub codes: Vec<CodeRow>,
    pub description: String,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub struct CodeRow {
    pub code: i64,
    pub value: Option<i64>,
    pub exact: Option<i64>,
    pub reserved: bool,
    pub meaning: String,
    pub note: String,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub struct ConfigPins {
    pub pins: Vec<String>,
    pub inverted: bool,
    pub settings: Vec<PinSetting>,
    pub description: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    High,
    Low,
    Any,
}

impl Level {
    /// The spec keyword.
    pub fn name(self) -> &'static str {
        match self {
            Level::High => "high",
            Level::Low => "low",
            Level::Any => "any",
        }
    }
}

#[derive(Debug, Clone)]
pub struct PinSetting {
    pub pin: String,
    pub level: Level,
    pub meaning: String,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub struct Mode {
    pub name: String,
    pub description: String,
    pub pins: BTreeMap<String, Level>,
    pub command: Option<String>,
    /// Selected by an OD entry holding this value: (index, sub, value).
    pub object: Option<(u16, u8, i64)>,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub struct Object {
    pub index: u16,
    pub name: String,
    pub ident: String,
    pub kind: ObjectKind,
    pub sub0: Sub0,
    /// A VAR has exactly one entry with sub-index 0.
    pub entries: Vec<Entry>,
    pub description: String,
    pub modes: ModeSet,
    /// Generated from the `pdo:` section rather than written in `objects:`.
    pub generated: bool,
    pub span: Span,
}

impl Object {
    pub fn entry(&self, sub: u8) -> Option<&Entry> {
        self.entries.iter().find(|e| e.sub == sub)
    }
    pub fn highest_sub(&self) -> u8 {
        self.entries.iter().map(|e| e.sub).max().unwrap_or(0)
    }
}

/// A default, limit or other entry value.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// Integer, possibly depending on `$NODEID`.
    Int(Expr),
    Real(f64),
    Str(String),
}

impl Value {
    /// The value for a node ID (`None` for strings and reals, or on arithmetic errors).
    pub fn int_for(&self, node_id: u8) -> Option<i64> {
        match self {
            Value::Int(e) => e.eval(&Default::default(), Some(i64::from(node_id))).ok(),
            _ => None,
        }
    }
}

#[derive(Debug, Clone)]
pub struct Entry {
    pub sub: u8,
    pub name: String,
    pub ident: String,
    pub data_type: DataType,
    /// Maximum byte length of strings and domains.
    pub length: Option<u32>,
    pub access: Access,
    pub host_access: HostAccess,
    /// `host_access` was written on the entry rather than derived from `serial.host_access`.
    pub host_override: bool,
    pub host_write_when: WriteWhen,
    pub pdo_mapping: bool,
    pub default: Option<Value>,
    pub low: Option<Value>,
    pub high: Option<Value>,
    pub unit: String,
    pub storage: Storage,
    pub description: String,
    pub modes: ModeSet,
    /// The only values a write may store (besides `low`/`high`), if restricted.
    pub values: Option<Vec<i64>>,
    /// NMT states in which a CAN-side write is accepted; `None` means every state.
    pub writable_in: Option<Vec<NmtState>>,
    pub spans: EntrySpans,
}

impl Entry {
    /// Size in bits as mapped into a PDO (strings: their maximum length).
    pub fn bits(&self) -> Option<u32> {
        self.data_type.bits().or_else(|| self.length.map(|l| l * 8))
    }
}

#[derive(Debug, Clone, Copy, Default)]
pub struct EntrySpans {
    pub at: Span,
    pub data_type: Span,
    pub access: Span,
    pub default: Span,
    pub low: Span,
    pub high: Span,
    pub values: Span,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum PdoDir {
    Rx,
    Tx,
}

impl PdoDir {
    pub fn comm_base(self) -> u16 {
        match self {
            PdoDir::Rx => 0x1400,
            PdoDir::Tx => 0x1800,
        }
    }
    pub fn mapping_base(self) -> u16 {
        match self {
            PdoDir::Rx => 0x1600,
            PdoDir::Tx => 0x1A00,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            PdoDir::Rx => "RPDO",
            PdoDir::Tx => "TPDO",
        }
    }
}

#[derive(Debug, Clone, Default)]
pub struct PdoConfig {
    pub rpdo: Option<PdoSet>,
    pub tpdo: Option<PdoSet>,
    /// All default PDOs, sorted by direction and number.
    pub pdos: Vec<Pdo>,
}

#[derive(Debug, Clone)]
pub struct PdoSet {
    pub comm_subs: Vec<u8>,
    pub max_mapped: u8,
    pub comm_access: Access,
    pub mapping_access: Access,
    /// NMT states in which the mapping may be written.
    pub mapping_writable_in: Option<Vec<NmtState>>,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub struct Pdo {
    pub dir: PdoDir,
    pub number: u16,
    pub cob_id: Expr,
    pub transmission_type: u8,
    pub inhibit_time: u16,
    pub event_timer: u16,
    pub sync_start: u8,
    pub map: Vec<Mapping>,
    pub modes: ModeSet,
    pub description: String,
    pub span: Span,
    pub cob_id_span: Span,
    pub transmission_type_span: Span,
}

#[derive(Debug, Clone, Copy)]
pub struct Mapping {
    pub index: u16,
    pub sub: u8,
    pub bits: u8,
    pub span: Span,
}

impl Mapping {
    /// The UNSIGNED32 value stored in a mapping object's sub-entry.
    pub fn encoded(self) -> u32 {
        (u32::from(self.index) << 16) | (u32::from(self.sub) << 8) | u32::from(self.bits)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NmtEffect {
    None,
    ErrorBehavior,
    PreOperational,
    Stopped,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputEffect {
    Unchanged,
    ErrorState,
}

impl NmtEffect {
    /// The spec keyword.
    pub fn name(self) -> &'static str {
        match self {
            NmtEffect::None => "none",
            NmtEffect::ErrorBehavior => "error_behavior",
            NmtEffect::PreOperational => "preoperational",
            NmtEffect::Stopped => "stopped",
        }
    }
}

impl OutputEffect {
    /// The spec keyword.
    pub fn name(self) -> &'static str {
        match self {
            OutputEffect::Unchanged => "unchanged",
            OutputEffect::ErrorState => "error_state",
        }
    }
}

#[derive(Debug, Clone)]
pub struct Emergency {
    pub name: String,
    pub code: u16,
    pub error_register: u8,
    /// Bytes 3..7 of the EMCY frame; `None` marks a byte that varies.
    pub manufacturer: [Option<u8>; 5],
    pub description: String,
    pub trigger: String,
    pub nmt: NmtEffect,
    pub outputs: OutputEffect,
    pub reset: String,
    pub enabled_by: Option<u16>,
    /// The stack condition that sends this emergency.
    pub event: Option<EmcyEvent>,
    pub example: Option<Vec<u8>>,
    pub modes: ModeSet,
    pub span: Span,
    pub example_span: Span,
}

impl Emergency {
    /// The 8 frame bytes with varying bytes shown as `None`.
    pub fn frame(&self) -> [Option<u8>; 8] {
        let [c0, c1] = self.code.to_le_bytes();
        let m = self.manufacturer;
        [Some(c0), Some(c1), Some(self.error_register), m[0], m[1], m[2], m[3], m[4]]
    }
}

#[derive(Debug, Clone)]
pub struct Serial {
    pub settings: Option<SerialSettings>,
    pub framing: Framing,
    pub host_access: HostRule,
    pub error_bits: Vec<ErrorBit>,
    pub commands: Vec<Command>,
    pub description: String,
    pub framing_span: Span,
}

#[derive(Debug, Clone)]
pub struct SerialSettings {
    pub data_bits: u8,
    pub parity: String,
    pub stop_bits: u8,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Framing {
    /// CO401Memory1: `CMD << 4 | LEN`, then LEN data bytes.
    NibbleLength { resync_pause_ms: u32 },
    /// CO401GW1: command byte, DataLen byte, data.
    LengthByte { inter_byte_timeout_ms: u32, resync_pause_ms: u32, extension_threshold: u8 },
    /// CANopenIA: start byte, length, payload, CRC.
    StartLengthCrc { start_byte: u8, start_bits: Option<StartBits>, length_bytes: u8, length_counts: LengthCounts, max_payload: u16, crc: CrcParams },
}

impl Framing {
    pub fn kind(&self) -> &'static str {
        match self {
            Framing::NibbleLength { .. } => "nibble_length",
            Framing::LengthByte { .. } => "length_byte",
            Framing::StartLengthCrc { .. } => "start_length_crc",
        }
    }
    /// The most data bytes one frame can carry.
    pub fn max_data(&self) -> u32 {
        match self {
            Framing::NibbleLength { .. } => 15,
            Framing::LengthByte { extension_threshold, .. } => u32::from(*extension_threshold).saturating_sub(1),
            // The command code is the first payload byte.
            Framing::StartLengthCrc { max_payload, .. } => u32::from(*max_payload).saturating_sub(1),
        }
    }
}

/// Masks of the start byte's option bits: the network number (never 0), CRC present, and a
/// 16-bit length field. Bits outside the three masks are reserved and must be 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StartBits {
    pub network: u8,
    pub crc: u8,
    pub long_length: u8,
}

impl StartBits {
    /// What a start byte selects: (CRC present, length field width), or why it is invalid.
    pub fn options(self, start: u8, length_bytes: u8) -> Result<(bool, u8), String> {
        if start & !(self.network | self.crc | self.long_length) != 0 {
            return Err(format!("start byte {start:#04X} sets reserved bits"));
        }
        if start & self.network == 0 {
            return Err(format!("start byte {start:#04X} names network 0, which is reserved"));
        }
        Ok((start & self.crc != 0, if start & self.long_length != 0 { 2 } else { length_bytes }))
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthCounts {
    Payload,
    PayloadAndCrc,
    Frame,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CrcParams {
    pub width: u8,
    pub poly: u64,
    pub init: u64,
    pub reflect_in: bool,
    pub reflect_out: bool,
    pub xor_out: u64,
    pub check: u64,
    pub little_endian: bool,
    pub covers_length: bool,
    pub covers_payload: bool,
    pub covers_start: bool,
    pub check_span: Span,
}

impl CrcParams {
    /// Bit-by-bit reference implementation of the Rocksoft model, for checking parameters.
    pub fn compute(&self, data: &[u8]) -> u64 {
        let width = u32::from(self.width);
        let top = 1_u64 << (width - 1);
        let mask = if width == 64 { u64::MAX } else { (1_u64 << width) - 1 };
        let mut crc = self.init & mask;
        for &byte in data {
            let b = if self.reflect_in { byte.reverse_bits() } else { byte };
            crc ^= u64::from(b) << (width - 8);
            for _ in 0..8 {
                crc = if crc & top != 0 { ((crc << 1) ^ self.poly) & mask } else { (crc << 1) & mask };
            }
        }
        if self.reflect_out {
            crc = crc.reverse_bits() >> (64 - width);
        }
        (crc ^ self.xor_out) & mask
    }
}

#[derive(Debug, Clone)]
pub struct HostRule {
    pub read: HostRead,
    pub write: HostWrite,
    pub readable: Vec<AccessRange>,
    pub writable: Vec<AccessRange>,
    pub description: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HostRead {
    All,
    None,
    Listed,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HostWrite {
    All,
    None,
    Listed,
    SameAsCan,
}

#[derive(Debug, Clone)]
pub struct AccessRange {
    pub from: u16,
    pub to: u16,
    pub sub: Option<u8>,
    pub when: WriteWhen,
    pub note: String,
    pub span: Span,
}

impl AccessRange {
    pub fn contains(&self, index: u16, sub: u8) -> bool {
        (self.from..=self.to).contains(&index) && self.sub.is_none_or(|s| s == sub)
    }
}

#[derive(Debug, Clone)]
pub struct ErrorBit {
    pub bit: u8,
    pub name: String,
    pub description: String,
    pub span: Span,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Direction {
    HostToDevice,
    DeviceToHost,
}

impl Direction {
    pub fn name(self) -> &'static str {
        match self {
            Direction::HostToDevice => "host_to_device",
            Direction::DeviceToHost => "device_to_host",
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommandKind {
    Request,
    Response,
    Command,
    Ack,
    Indication,
}

impl CommandKind {
    /// The spec keyword.
    pub fn name(self) -> &'static str {
        match self {
            CommandKind::Request => "request",
            CommandKind::Response => "response",
            CommandKind::Command => "command",
            CommandKind::Ack => "ack",
            CommandKind::Indication => "indication",
        }
    }
}

#[derive(Debug, Clone)]
pub struct Command {
    pub name: String,
    pub code: u32,
    pub code_param: Option<CodeParam>,
    pub direction: Direction,
    pub kind: CommandKind,
    pub reply: Option<String>,
    /// Declared data length (LEN nibble / DataLen / payload after the code byte).
    pub length: (u32, u32),
    pub length_code: Option<u32>,
    pub ack: Option<Ack>,
    pub description: String,
    pub fields: Vec<Field>,
    pub examples: Vec<Example>,
    pub modes: ModeSet,
    pub span: Span,
    pub code_span: Span,
    pub length_span: Span,
    pub reply_span: Span,
}

impl Command {
    /// The codes this command occupies (all values of a code parameter).
    pub fn codes(&self) -> Vec<u32> {
        match &self.code_param {
            None => vec![self.code],
            Some(p) => {
                let (lo, hi) = p.range.unwrap_or((0, p.mask >> p.mask.trailing_zeros()));
                let values: Vec<u32> = p.values.clone().unwrap_or_else(|| (lo..=hi).collect());
                values.into_iter().map(|v| (self.code & !p.mask) | ((v << p.mask.trailing_zeros()) & p.mask)).collect()
            }
        }
    }
    /// The data bytes taken by fixed-size fields.
    pub fn fixed_size(&self) -> u32 {
        self.fields.iter().map(|f| f.ty.fixed_size()).sum()
    }
    pub fn tail(&self) -> Option<&Field> {
        self.fields.iter().find(|f| matches!(f.ty, FieldType::Tail { .. }))
    }
}

#[derive(Debug, Clone)]
pub struct CodeParam {
    pub name: String,
    pub mask: u32,
    pub range: Option<(u32, u32)>,
    /// An explicit set of parameter values (GW1: PDO 0 and 4 in digital mode).
    pub values: Option<Vec<u32>>,
}

#[derive(Debug, Clone)]
pub struct Ack {
    pub field: String,
    pub positive: i64,
    pub negative: i64,
    pub span: Span,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldType {
    Unsigned(u8),
    Signed(u8),
    Bytes(u32),
    Tail { max: u32 },
}

impl FieldType {
    pub fn fixed_size(self) -> u32 {
        match self {
            FieldType::Unsigned(n) | FieldType::Signed(n) => u32::from(n),
            FieldType::Bytes(n) => n,
            FieldType::Tail { .. } => 0,
        }
    }
}

#[derive(Debug, Clone)]
pub struct Field {
    pub name: String,
    pub ty: FieldType,
    pub big_endian: bool,
    /// Byte offset within the data (after the code / length bytes).
    pub at: u32,
    pub explicit_at: bool,
    pub description: String,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub struct Example {
    pub bytes: Vec<u8>,
    pub fields: BTreeMap<String, (ExampleValue, Span)>,
    pub note: String,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ExampleValue {
    Int(i64),
    Bytes(Vec<u8>),
}

#[derive(Debug, Clone)]
pub struct RedundantPair {
    pub primary: u16,
    pub shadow: u16,
    pub description: String,
    pub span: Span,
}

#[derive(Debug, Clone)]
pub struct Erratum {
    pub id: String,
    pub location: String,
    pub datasheet: String,
    pub choice: String,
    pub reason: String,
    pub span: Span,
}

impl Device {
    pub fn object(&self, index: u16, mode: Option<&str>) -> Option<&Object> {
        self.objects.iter().find(|o| o.index == index && in_mode(&o.modes, mode))
    }
    /// The mode names, or a single `None` for a device without modes.
    pub fn mode_names(&self) -> Vec<Option<&str>> {
        if self.modes.is_empty() { vec![None] } else { self.modes.iter().map(|m| Some(m.name.as_str())).collect() }
    }
}
