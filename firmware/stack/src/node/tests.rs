//! The node over a small hand-written dictionary: one RPDO and one TPDO that both map 2000h,
//! a heartbeat consumer, a switch object 2102h, and an app-backed DOMAIN 1F50h.2 owned by a
//! [`Recorder`] that also logs write indications. Generated dictionaries are tested through
//! the devices (`verification`, the simulator); these tests reach the node's own rules.

use super::{BusState, Node, NodeConfig, NodeEvent};
use crate::emcy::{EmcyDefault, EmcyEvent, Reaction};
use crate::frame::CanFrame;
use crate::od::image::{self, Patch, Span};
use crate::od::{
    Access, AppObjects, Area, CommObjects, DataType, EntryAccess, EntryFlags, EntryInfo, EntryKind, HostAccess, Limits, NodeDictionary, ReadLen, SdoAbort,
    Side, Storage, Table, WriteSource, read_slice,
};
use crate::store::NoStore;
use coforge_types::NmtState;
extern crate std;
use std::vec;
use std::vec::Vec;

const ID: u8 = 5;

const fn entry(index: u16, sub: u8, data_type: DataType, access: Access) -> EntryInfo {
    let size = match data_type {
        DataType::Unsigned8 => 1,
        _ => 4,
    };
    let flags = EntryFlags::new(HostAccess::Rw, Storage::Ram);
    EntryInfo {
        index,
        offset: 0,
        size,
        sub,
        last_sub: sub,
        limits: 0,
        kind: EntryKind::new(data_type, access),
        flags: if matches!(index, 0x2000 | 0x2001 | 0x2003) { flags.pdo_mappable() } else { flags },
    }
}

/// The largest value 1F50h.2 takes.
const PROGRAM_MAX: u16 = 4000;

/// 1F50h.2: a write-only DOMAIN the app keeps (CANopenIA's configuration download).
const PROGRAM: EntryInfo = EntryInfo {
    size: PROGRAM_MAX,
    kind: EntryKind::new(DataType::Domain, Access::Wo),
    flags: EntryFlags::new(HostAccess::Wo, Storage::App),
    ..entry(0x1F50, 2, U8, Access::Wo)
};

const U8: DataType = DataType::Unsigned8;
const U32: DataType = DataType::Unsigned32;
const ENTRY_COUNT: usize = 24;

/// Every entry with its default (`$NODEID` added where the flag says so).
const TABLE: [(EntryInfo, u32, bool); ENTRY_COUNT] = [
    (entry(0x1000, 0, U32, Access::Ro), 0x191, false),
    (entry(0x1001, 0, U8, Access::Ro), 0, false),
    (entry(0x1010, 1, U32, Access::Rw), 1, false),
    (entry(0x1011, 1, U32, Access::Rw), 1, false),
    (entry(0x1016, 0, U8, Access::Ro), 1, false),
    (entry(0x1016, 1, U32, Access::Rw), 0, false),
    (entry(0x1400, 0, U8, Access::Ro), 2, false),
    (entry(0x1400, 1, U32, Access::Rw), 0x200, true),
    (entry(0x1400, 2, U8, Access::Rw), 255, false),
    (entry(0x1600, 0, U8, Access::Rw), 1, false),
    (entry(0x1600, 1, U32, Access::Rw), 0x2000_0008, false),
    (entry(0x1600, 2, U32, Access::Rw), 0, false),
    (entry(0x1600, 3, U32, Access::Rw), 0, false),
    (entry(0x1600, 4, U32, Access::Rw), 0, false),
    (entry(0x1800, 0, U8, Access::Ro), 2, false),
    (entry(0x1800, 1, U32, Access::Rw), 0x180, true),
    (entry(0x1800, 2, U8, Access::Rw), 255, false),
    (entry(0x1A00, 0, U8, Access::Rw), 1, false),
    (entry(0x1A00, 1, U32, Access::Rw), 0x2000_0008, false),
    (PROGRAM, 0, false),
    (entry(0x2000, 0, U8, Access::Rw), 0, false),
    (entry(0x2001, 0, U8, Access::Rw), 0, false),
    (entry(0x2003, 0, U32, Access::Rw), 0, false),
    (entry(0x2102, 0, U8, Access::Ro), 1, false),
];

/// Bytes of each entry's slot in the value image: entry `i` lives at `4 * i`.
const SLOT: usize = 4;
const IMAGE: usize = SLOT * ENTRY_COUNT;

static ENTRIES: [EntryInfo; ENTRY_COUNT] = {
    let mut out = [entry(0, 0, U8, Access::Ro); ENTRY_COUNT];
    let mut i = 0;
    while i < out.len() {
        out[i] = TABLE[i].0;
        out[i].offset = (SLOT * i) as u16;
        i += 1;
    }
    out
};

/// The defaults' image: each default little-endian in its slot (a byte entry reads its first
/// byte), the `$NODEID` ones as patches.
const DEFAULT_IMAGE: [u8; IMAGE] = {
    let mut out = [0; IMAGE];
    let mut i = 0;
    while i < ENTRY_COUNT {
        let bytes = TABLE[i].1.to_le_bytes();
        let mut b = 0;
        while b < SLOT {
            out[SLOT * i + b] = bytes[b];
            b += 1;
        }
        i += 1;
    }
    out
};

/// One span per slot: each has its entry's index, so a reset of an area takes exactly its
/// entries.
static SPANS: [Span; ENTRY_COUNT] = {
    let mut out = [Span { index: 0, start: 0, len: 0 }; ENTRY_COUNT];
    let mut i = 0;
    while i < ENTRY_COUNT {
        out[i] = Span { index: TABLE[i].0.index, start: (SLOT * i) as u16, len: SLOT as u16 };
        i += 1;
    }
    out
};

/// The entries whose default adds the node-ID (1400h.1 and 1800h.1).
static NODE_ID_DEFAULTS: [Patch; 2] = {
    let mut out = [Patch::new(0, 0, 0, true, 0); 2];
    let (mut i, mut n) = (0, 0);
    while i < ENTRY_COUNT {
        if TABLE[i].2 {
            out[n] = Patch::new(TABLE[i].0.index, (SLOT * i) as u16, 4, true, TABLE[i].1);
            n += 1;
        }
        i += 1;
    }
    assert!(n == out.len(), "every $NODEID entry has its patch");
    out
};

/// The owner of 1F50h.2: keeps what is written to it (streamed while `streaming` is set) and
/// logs every write indication.
#[derive(Debug, Default)]
pub(super) struct Recorder {
    /// Every indication, in order: index, sub-index, data, source.
    written: Vec<(u16, u8, Vec<u8>, WriteSource)>,
    /// 1F50h.2's value.
    program: Vec<u8>,
    streaming: bool,
    /// The parts of a streamed download so far.
    incoming: Vec<u8>,
    /// Streamed downloads that ended without success.
    aborted: usize,
}

impl AppObjects for Recorder {
    fn read(&mut self, _: &EntryInfo, _: u16, _: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        read_slice(&self.program, offset, buf)
    }

    fn write(&mut self, _: &EntryInfo, _: u16, _: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.program = data.to_vec();
        Ok(())
    }

    fn written(&mut self, index: u16, sub: u8, data: &[u8], by: WriteSource) {
        self.written.push((index, sub, data.to_vec(), by));
    }

    const STREAMING: bool = true;

    fn streams(&mut self, entry: &EntryInfo, index: u16, sub: u8) -> bool {
        assert_eq!((entry.index, index, sub), (0x1F50, 0x1F50, 2), "asked for app-backed entries only");
        self.streaming
    }

    fn write_part(&mut self, _: &EntryInfo, _: u16, _: u8, offset: usize, data: &[u8], last: bool) -> Result<(), SdoAbort> {
        assert_eq!(offset, self.incoming.len(), "in order, without gaps");
        self.incoming.extend_from_slice(data);
        if last {
            self.program = core::mem::take(&mut self.incoming);
        }
        Ok(())
    }

    fn abort_stream(&mut self, _: &EntryInfo, _: u16, _: u8) {
        self.incoming.clear();
        self.aborted += 1;
    }
}

/// The test dictionary: each entry's value in its slot of the image.
#[derive(Debug)]
pub(super) struct TestOd {
    image: [u8; IMAGE],
    emergencies: &'static [EmcyDefault],
    app: Recorder,
}

impl EntryAccess for TestOd {
    type App = Recorder;

    fn entries(&self) -> Table<'static> {
        Table::new(&ENTRIES)
    }

    fn limits(&self) -> &'static [Limits] {
        &[]
    }

    fn image(&self) -> &[u8] {
        &self.image
    }

    fn image_mut(&mut self) -> &mut [u8] {
        &mut self.image
    }

    fn app(&mut self) -> &mut Recorder {
        &mut self.app
    }
}

impl NodeDictionary for TestOd {
    type Mode = ();
    const MODES: &'static [()] = &[()];
    const PERSISTENT_SIZE: usize = 0;
    const SDO_BLOCK_TRANSFER: bool = false;
    const COMM: CommObjects = CommObjects { error_history: false, sync_cycle: false, heartbeat_consumer: true };

    fn persistent() -> &'static [Span] {
        &[]
    }

    fn stored() -> &'static [Span] {
        &SPANS
    }

    fn node_id_defaults() -> &'static [Patch] {
        &NODE_ID_DEFAULTS
    }

    fn defaults() -> &'static [u8] {
        static DEFAULTS: [u8; image::sparse_len(&DEFAULT_IMAGE)] = image::sparse(&DEFAULT_IMAGE);
        &DEFAULTS
    }

    fn mode_defaults(&self) -> &'static [Patch] {
        &[]
    }

    fn emergencies(&self) -> &'static [EmcyDefault] {
        self.emergencies
    }

    fn emergency_named(&self, _: &str) -> Option<EmcyDefault> {
        None
    }

    fn new(_: (), node_id: u8, app: Recorder) -> Self {
        let mut od = TestOd { image: [0; IMAGE], emergencies: &[], app };
        od.reset_area(Area::ALL, node_id);
        od
    }

    fn mode(&self) {}

    fn set_mode(&mut self, _: (), _: u8) {}

    fn mode_name(_: ()) -> &'static str {
        "test"
    }

    fn node_config(node_id: u8) -> NodeConfig {
        NodeConfig::new(node_id)
    }
}

type TestNode = Node<TestOd, NoStore, 8, 1>;

/// A started node with the spec emergencies `emergencies`, its boot-up sent and its events
/// taken.
fn node(cfg: NodeConfig, emergencies: &'static [EmcyDefault]) -> TestNode {
    let mut od = TestOd::new((), ID, Recorder::default());
    od.emergencies = emergencies;
    let mut n = Node::new(od, NoStore, cfg);
    n.start(0);
    frames(&mut n, 0);
    events(&mut n);
    n
}

fn frames(n: &mut TestNode, now: u64) -> Vec<CanFrame> {
    core::iter::from_fn(|| n.poll(now)).collect()
}

fn events(n: &mut TestNode) -> Vec<NodeEvent> {
    core::iter::from_fn(|| n.take_event()).collect()
}

/// The data of the emergency frames among `frames`.
fn emergencies(frames: &[CanFrame]) -> Vec<[u8; 8]> {
    frames.iter().filter(|f| f.id == 0x80 + u16::from(ID)).map(|f| f.data).collect()
}

fn nmt(n: &mut TestNode, cs: u8, target: u8) {
    n.on_frame(&CanFrame::data(0x000, &[cs, target]).unwrap(), 0);
}

/// An expedited SDO download: `Err` with the abort code if the node refuses it, and the
/// other frames the node sent meanwhile.
fn download_with(n: &mut TestNode, index: u16, sub: u8, value: &[u8]) -> (Result<(), u32>, Vec<CanFrame>) {
    let [lo, hi] = index.to_le_bytes();
    let mut request = [0x23 | ((4 - value.len() as u8) << 2), lo, hi, sub, 0, 0, 0, 0];
    request[4..4 + value.len()].copy_from_slice(value);
    n.on_frame(&CanFrame::data(0x600 + u16::from(ID), &request).unwrap(), 0);
    let (answers, others): (Vec<CanFrame>, Vec<CanFrame>) = frames(n, 0).into_iter().partition(|f| f.id == 0x580 + u16::from(ID));
    let [answer] = answers[..] else { panic!("one SDO answer, not {answers:?}") };
    let result = match answer.data[0] {
        0x60 => Ok(()),
        0x80 => Err(u32::from_le_bytes([answer.data[4], answer.data[5], answer.data[6], answer.data[7]])),
        other => panic!("SDO answer {other:02X}"),
    };
    (result, others)
}

fn download(n: &mut TestNode, index: u16, sub: u8, value: &[u8]) -> Result<(), u32> {
    download_with(n, index, sub, value).0
}

/// The payloads of the TPDO1 frames (0x185) among `frames`.
fn tpdo1(frames: &[CanFrame]) -> Vec<Vec<u8>> {
    frames.iter().filter(|f| f.id == 0x180 + u16::from(ID)).map(|f| f.payload().to_vec()).collect()
}

fn read_u8(n: &mut TestNode, index: u16) -> u8 {
    read(n, index, 0) as u8
}

fn read(n: &mut TestNode, index: u16, sub: u8) -> u32 {
    super::read_u32(n.od_mut(), index, sub).unwrap()
}

#[test]
fn nmt_commands_for_this_node_are_reported_before_they_act() {
    let mut n = node(NodeConfig::new(ID), &[]);
    nmt(&mut n, 0x01, ID);
    assert_eq!(events(&mut n), [NodeEvent::NmtReceived(0x01), NodeEvent::StateChanged(NmtState::Operational)]);
    nmt(&mut n, 0x01, 0);
    assert_eq!(events(&mut n), [NodeEvent::NmtReceived(0x01)], "broadcast, and reported though the state stays");
    nmt(&mut n, 0x80, ID + 1);
    assert_eq!(events(&mut n), [], "another node's command");
    assert_eq!(n.state(), NmtState::Operational);
    nmt(&mut n, 0x03, 0);
    assert_eq!(events(&mut n), [NodeEvent::NmtReceived(0x03)], "a specifier CiA 301 does not define");
    n.on_frame(&CanFrame::data(0x000, &[0x02, ID, 0]).unwrap(), 0);
    assert_eq!(events(&mut n), [], "not an NMT command: 3 bytes");
    nmt(&mut n, 0x81, ID);
    let after_reset = events(&mut n);
    assert_eq!(after_reset.first(), Some(&NodeEvent::NmtReceived(0x81)));
    assert_eq!(after_reset.get(1), Some(&NodeEvent::ResetApplication));
}

#[test]
fn every_emergency_queued_is_reported_with_its_bytes() {
    static SPEC: [EmcyDefault; 1] = [EmcyDefault {
        code: 0x8100,
        register: 0x11,
        manufacturer: [0, 0, 0, 0, 0x40],
        reaction: Reaction::None,
        event: Some(EmcyEvent::CanWarning),
        enabled_by: None,
    }];
    let mut n = node(NodeConfig::new(ID), &SPEC);
    n.on_bus_state(BusState::Warning, 1_000);
    n.on_bus_state(BusState::Passive, 2_000);
    n.on_bus_state(BusState::Active, 3_000);
    let sent = emergencies(&frames(&mut n, 3_000));
    assert_eq!(
        sent,
        [[0x00, 0x81, 0x11, 0, 0, 0, 0, 0x40], [0x20, 0x81, 0x11, 0, 0, 0, 0, 0], [0, 0, 0x11, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0, 0, 0]],
        "spec warning, CiA passive, two error resets"
    );
    let reported: Vec<[u8; 8]> = events(&mut n)
        .into_iter()
        .filter_map(|e| match e {
            NodeEvent::EmergencySent(data) => Some(data),
            _ => None,
        })
        .collect();
    assert_eq!(reported, sent, "one event per frame, its bytes as sent");
}

#[test]
fn the_event_queue_keeps_the_newest_eight() {
    let mut n = node(NodeConfig::new(ID), &[]);
    for cs in 0x10..0x1A {
        nmt(&mut n, cs, ID);
    }
    let kept: Vec<NodeEvent> = (0x12..0x1A).map(NodeEvent::NmtReceived).collect();
    assert_eq!(events(&mut n), kept, "10 events: the 2 oldest are dropped");
    assert_eq!(n.take_event(), None);
}

/// The CAN warning as a datasheet lists it (CO401GW1 "can_error_warning").
static WARNING_ONLY: [EmcyDefault; 1] = [EmcyDefault {
    code: 0x8100,
    register: 0x11,
    manufacturer: [0, 0, 0, 0, 0x40],
    reaction: Reaction::None,
    event: Some(EmcyEvent::CanWarning),
    enabled_by: None,
}];

/// Operational, then a CAN warning, CAN passive, a too short RPDO and a lost heartbeat
/// (1016h.1 watches node 3 for 100 ms): the emergencies sent, 1001h, and the state after.
fn stack_events(cfg: NodeConfig) -> (Vec<[u8; 8]>, u8, NmtState) {
    let mut n = node(cfg, &WARNING_ONLY);
    assert_eq!(n.write(0x1016, 1, &(3_u32 << 16 | 100).to_le_bytes(), Side::Device), Ok(()));
    nmt(&mut n, 0x01, ID);
    n.on_frame(&CanFrame::data(0x703, &[0x05]).unwrap(), 0);
    let mut sent = Vec::new();
    n.on_bus_state(BusState::Warning, 1_000);
    n.on_bus_state(BusState::Passive, 2_000);
    n.on_frame(&CanFrame::data(0x205, &[]).unwrap(), 3_000);
    sent.extend(emergencies(&frames(&mut n, 3_000)));
    assert_eq!(n.state(), NmtState::Operational);
    sent.extend(emergencies(&frames(&mut n, 101_000)));
    let mut register = [0];
    n.read(0x1001, 0, 0, &mut register, Side::Bus).unwrap();
    assert_eq!(register[0], n.error_register(), "1001h mirrors the producer");
    (sent, register[0], n.state())
}

#[test]
fn by_default_unlisted_stack_events_send_their_cia_301_emergency() {
    let (sent, register, state) = stack_events(NodeConfig::new(ID));
    assert_eq!(
        sent,
        [
            [0x00, 0x81, 0x11, 0, 0, 0, 0, 0x40], // the listed CAN warning
            [0x20, 0x81, 0x11, 0, 0, 0, 0, 0],    // CAN passive, CiA 301
            [0x10, 0x82, 0x11, 0, 0, 0, 0, 0],    // RPDO length, CiA 301
            [0x30, 0x81, 0x11, 0, 0, 0, 0, 0],    // heartbeat consumer, CiA 301
        ]
    );
    assert_eq!(register, 0x11);
    assert_eq!(state, NmtState::PreOperational, "1029h sub 1 absent = 0: a communication error leaves Operational");
}

#[test]
fn listed_emergencies_only_sends_nothing_the_spec_does_not_list() {
    let cfg = NodeConfig { listed_emergencies_only: true, ..NodeConfig::new(ID) };
    let (sent, register, state) = stack_events(cfg);
    assert_eq!(sent, [[0x00, 0x81, 0x11, 0, 0, 0, 0, 0x40]], "only the listed CAN warning");
    assert_eq!(register, 0x11, "the warning's bits only");
    assert_eq!(state, NmtState::PreOperational, "the lost heartbeat still gets its 1029h reaction");
    // Without the listed warning active, the unlisted events leave 1001h at 0.
    let mut n = node(cfg, &WARNING_ONLY);
    n.on_bus_state(BusState::Passive, 1_000);
    nmt(&mut n, 0x01, ID);
    n.on_frame(&CanFrame::data(0x205, &[]).unwrap(), 2_000);
    assert_eq!(emergencies(&frames(&mut n, 2_000)), Vec::<[u8; 8]>::new());
    assert_eq!(n.error_register(), 0);
    assert!(!n.is_active(&EmcyDefault::for_event(EmcyEvent::CanPassive, &[])));
    n.on_bus_state(BusState::Active, 3_000);
    assert_eq!(emergencies(&frames(&mut n, 3_000)), Vec::<[u8; 8]>::new(), "no error reset for what was never sent");
}

/// Operational with TPDO1 (type 255) and RPDO1 both mapping 2000h.
fn operational(cfg: NodeConfig) -> TestNode {
    let mut n = node(cfg, &[]);
    nmt(&mut n, 0x01, ID);
    frames(&mut n, 0);
    n
}

#[test]
fn by_default_every_write_of_a_mapped_entry_triggers_its_tpdo() {
    let mut n = operational(NodeConfig::new(ID));
    assert_eq!(n.write(0x2000, 0, &[7], Side::Device), Ok(()));
    assert_eq!(tpdo1(&frames(&mut n, 0)), [[7]], "a device write");
    assert_eq!(n.write(0x2000, 0, &[8], Side::Host), Ok(()));
    assert_eq!(tpdo1(&frames(&mut n, 0)), [[8]], "a host write");
    let (result, sent) = download_with(&mut n, 0x2000, 0, &[9]);
    assert_eq!((result, tpdo1(&sent)), (Ok(()), vec![vec![9]]), "an SDO download");
    n.on_frame(&CanFrame::data(0x205, &[10]).unwrap(), 0);
    assert_eq!(tpdo1(&frames(&mut n, 0)), [[10]], "an RPDO");
    assert_eq!(n.write(0x2001, 0, &[1], Side::Device), Ok(()));
    assert_eq!(tpdo1(&frames(&mut n, 0)), Vec::<Vec<u8>>::new(), "2001h is not mapped");
    n.trigger_mapped(0x2000, 0);
    assert_eq!(tpdo1(&frames(&mut n, 0)), [[10]], "trigger_mapped works with the setting on too");
}

#[test]
fn without_tpdo_on_write_only_the_device_triggers_tpdos() {
    let mut n = operational(NodeConfig { tpdo_on_write: false, ..NodeConfig::new(ID) });
    assert_eq!(n.write(0x2000, 0, &[7], Side::Device), Ok(()));
    assert_eq!(n.write(0x2000, 0, &[8], Side::Host), Ok(()));
    let (result, sent) = download_with(&mut n, 0x2000, 0, &[9]);
    assert_eq!((result, tpdo1(&sent)), (Ok(()), vec![]), "an SDO download");
    n.on_frame(&CanFrame::data(0x205, &[10]).unwrap(), 0);
    assert_eq!(tpdo1(&frames(&mut n, 0)), Vec::<Vec<u8>>::new(), "no write sends TPDO1");
    assert_eq!(read_u8(&mut n, 0x2000), 10, "though every write took effect");
    n.trigger_mapped(0x2001, 0);
    n.trigger_mapped(0x2000, 1);
    assert_eq!(tpdo1(&frames(&mut n, 0)), Vec::<Vec<u8>>::new(), "2001h and 2000h.1 are not mapped");
    n.trigger_mapped(0x2000, 0);
    assert_eq!(tpdo1(&frames(&mut n, 0)), [[10]], "the device's trigger sends the current value");
    // An invalid TPDO is not triggered.
    assert_eq!(n.write(0x1800, 1, &(0x8000_0180_u32 + u32::from(ID)).to_le_bytes(), Side::Device), Ok(()));
    n.trigger_mapped(0x2000, 0);
    assert_eq!(tpdo1(&frames(&mut n, 0)), Vec::<Vec<u8>>::new());
}

/// The mapping writes of the CiA 301 remapping procedure, with sub 0 as a byte.
const MAPPING_WRITES: [(u16, u8, u32); 4] = [(0x1A00, 0, 0), (0x1A00, 1, 0x2001_0008), (0x1600, 0, 0), (0x1600, 1, 0x2001_0008)];

fn value_of(sub: u8, value: u32) -> Vec<u8> {
    if sub == 0 { vec![value as u8] } else { value.to_le_bytes().to_vec() }
}

#[test]
fn while_the_remapping_object_reads_0_no_side_writes_a_mapping() {
    let mut n = node(NodeConfig { remapping_object: Some(0x2102), ..NodeConfig::new(ID) }, &[]);
    assert_eq!(n.write(0x2102, 0, &[0], Side::Host), Ok(()));
    // The procedure's first step is allowed: communication parameters are no mapping.
    assert_eq!(download(&mut n, 0x1800, 1, &(0x8000_0180 + u32::from(ID)).to_le_bytes()), Ok(()));
    assert_eq!(download(&mut n, 0x1400, 1, &(0x8000_0200 + u32::from(ID)).to_le_bytes()), Ok(()));
    for (index, sub, value) in MAPPING_WRITES {
        let data = value_of(sub, value);
        assert_eq!(download(&mut n, index, sub, &data), Err(0x0800_0021), "{index:04X}.{sub} over SDO");
        assert_eq!(n.write(index, sub, &data, Side::Host), Err(SdoAbort::DataTransferLocal), "{index:04X}.{sub} by the host");
        assert_eq!(n.write(index, sub, &data, Side::Device), Err(SdoAbort::DataTransferLocal), "{index:04X}.{sub} by the device");
    }
    assert_eq!((read(&mut n, 0x1A00, 0), read(&mut n, 0x1A00, 1)), (1, 0x2000_0008), "TPDO1 mapping unchanged");
    assert_eq!((read(&mut n, 0x1600, 0), read(&mut n, 0x1600, 1)), (1, 0x2000_0008), "RPDO1 mapping unchanged");
    // Any non-zero value enables remapping again: the procedure goes through.
    assert_eq!(n.write(0x2102, 0, &[2], Side::Host), Ok(()));
    for (index, sub, value) in MAPPING_WRITES {
        assert_eq!(download(&mut n, index, sub, &value_of(sub, value)), Ok(()), "{index:04X}.{sub}");
    }
    assert_eq!(download(&mut n, 0x1A00, 0, &[1]), Ok(()));
    assert_eq!(download(&mut n, 0x1800, 1, &(0x180 + u32::from(ID)).to_le_bytes()), Ok(()));
    nmt(&mut n, 0x01, ID);
    frames(&mut n, 0);
    assert_eq!(n.write(0x2001, 0, &[0x42], Side::Device), Ok(()));
    assert_eq!(tpdo1(&frames(&mut n, 0)), [[0x42]], "TPDO1 now maps 2001h");
}

#[test]
fn without_a_remapping_object_mappings_follow_cia_301_alone() {
    let mut n = node(NodeConfig::new(ID), &[]);
    assert_eq!(n.write(0x2102, 0, &[0], Side::Host), Ok(()));
    assert_eq!(download(&mut n, 0x1A00, 0, &[0]), Err(SdoAbort::DataTransferState.code()), "TPDO1 is valid");
    assert_eq!(n.write(0x1A00, 1, &0x2001_0008_u32.to_le_bytes(), Side::Device), Ok(()), "the device may");
    assert_eq!(download(&mut n, 0x1800, 1, &(0x8000_0180 + u32::from(ID)).to_le_bytes()), Ok(()));
    assert_eq!(download(&mut n, 0x1A00, 0, &[0]), Ok(()));
}

#[test]
fn device_frames_queue_behind_the_nodes_own_and_count_when_lost() {
    let mut n = node(NodeConfig::new(ID), &[]);
    let nmt_start = CanFrame::data(0x000, &[0x01, 0]).unwrap();
    let queued: Vec<bool> = (0..13).map(|i| n.send_frame(CanFrame { data: [i, 0, 0, 0, 0, 0, 0, 0], ..nmt_start })).collect();
    assert_eq!(queued, [[true; 12].as_slice(), &[false]].concat(), "the queue holds 12 frames");
    assert_eq!(n.tx_overflows(), 1, "the lost one is counted");
    let sent = frames(&mut n, 0);
    assert_eq!(sent.iter().map(|f| f.data[0]).collect::<Vec<u8>>(), (0..12).collect::<Vec<u8>>(), "sent in order, unchanged");
    assert!(sent.iter().all(|f| f.id == 0 && f.dlc == 2));
    assert!(n.send_frame(nmt_start), "room again once sent");
    assert_eq!(frames(&mut n, 0), [nmt_start]);
}

#[test]
fn device_frames_wait_for_the_can_side() {
    let mut n: TestNode = Node::new(TestOd::new((), ID, Recorder::default()), NoStore, NodeConfig::new(ID));
    n.power_on(0);
    let frame = CanFrame::data(0x123, &[1, 2, 3]).unwrap();
    assert!(n.send_frame(frame));
    assert_eq!(frames(&mut n, 0), [], "nothing goes out before the CAN side is enabled");
    n.enable_can((), 0);
    assert_eq!(frames(&mut n, 0), [CanFrame::data(0x700 + u16::from(ID), &[0]).unwrap()], "the boot-up empties the queue");
    assert!(n.send_frame(frame));
    n.on_bus_state(BusState::BusOff, 0);
    assert_eq!(frames(&mut n, 0), [], "a bus-off controller sends nothing");
}

/// One SDO request and the node's answer to it (other frames are dropped).
fn sdo(n: &mut TestNode, request: [u8; 8]) -> [u8; 8] {
    n.on_frame(&CanFrame::data(0x600 + u16::from(ID), &request).unwrap(), 0);
    let answers: Vec<[u8; 8]> = frames(n, 0).into_iter().filter(|f| f.id == 0x580 + u16::from(ID)).map(|f| f.data).collect();
    let [answer] = answers[..] else { panic!("one SDO answer, not {answers:?}") };
    answer
}

/// The abort code of an SDO answer, or `Ok` for any other answer.
fn outcome(answer: [u8; 8]) -> Result<(), u32> {
    if answer[0] == 0x80 { Err(u32::from_le_bytes([answer[4], answer[5], answer[6], answer[7]])) } else { Ok(()) }
}

fn initiate_segmented(index: u16, sub: u8, size: usize) -> [u8; 8] {
    let [lo, hi] = index.to_le_bytes();
    let [s0, s1, s2, s3] = (size as u32).to_le_bytes();
    [0x21, lo, hi, sub, s0, s1, s2, s3]
}

/// Download segment `i` of a transfer (toggle from `i`), `last` if no more follow.
fn download_segment(i: usize, chunk: &[u8], last: bool) -> [u8; 8] {
    let mut frame = [0; 8];
    frame[0] = (i as u8 & 1) << 4 | (7 - chunk.len() as u8) << 1 | u8::from(last);
    frame[1..1 + chunk.len()].copy_from_slice(chunk);
    frame
}

/// A segmented download with the size indicated: `Err` with the abort code of the first
/// request the node refuses.
fn download_segmented(n: &mut TestNode, index: u16, sub: u8, value: &[u8]) -> Result<(), u32> {
    outcome(sdo(n, initiate_segmented(index, sub, value.len())))?;
    let chunks: Vec<&[u8]> = value.chunks(7).collect();
    for (i, chunk) in chunks.iter().enumerate() {
        let answer = sdo(n, download_segment(i, chunk, i + 1 == chunks.len()));
        outcome(answer)?;
        assert_eq!(answer[0], 0x20 | (i as u8 & 1) << 4, "segment {i} acknowledged");
    }
    Ok(())
}

/// The write indications so far, taken.
fn indications(n: &mut TestNode) -> Vec<(u16, u8, Vec<u8>, WriteSource)> {
    core::mem::take(&mut n.od_mut().app.written)
}

#[test]
fn sdo_host_and_device_writes_are_indicated_after_they_took_effect() {
    let mut n = operational(NodeConfig::new(ID));
    let (result, sent) = download_with(&mut n, 0x2000, 0, &[9]);
    assert_eq!((result, tpdo1(&sent)), (Ok(()), vec![vec![9]]), "written, TPDO1 triggered");
    assert_eq!(indications(&mut n), [(0x2000, 0, vec![9], WriteSource::Sdo)], "an expedited download");
    assert_eq!(download_segmented(&mut n, 0x2003, 0, &[1, 2, 3, 4]), Ok(()));
    assert_eq!(indications(&mut n), [(0x2003, 0, vec![1, 2, 3, 4], WriteSource::Sdo)], "a segmented download");
    assert_eq!(download_segmented(&mut n, 0x1F50, 2, b"config"), Ok(()));
    assert_eq!(n.od().app.program, b"config", "an app-backed entry");
    assert_eq!(indications(&mut n), [(0x1F50, 2, b"config".to_vec(), WriteSource::Sdo)]);
    assert_eq!(n.write(0x2001, 0, &[3], Side::Host), Ok(()));
    assert_eq!(n.write(0x2001, 0, &[4], Side::Device), Ok(()));
    assert_eq!(n.write(0x2001, 0, &[5], Side::Bus), Ok(()));
    let expected = [(0x2001, 0, vec![3], WriteSource::Host), (0x2001, 0, vec![4], WriteSource::Device), (0x2001, 0, vec![5], WriteSource::Sdo)];
    assert_eq!(indications(&mut n), expected, "the node's write names its side; the bus's is an SDO download");
    assert_eq!(read_u8(&mut n, 0x2001), 5);
}

#[test]
fn refused_and_failed_writes_are_not_indicated() {
    let mut n = operational(NodeConfig::new(ID));
    assert_eq!(download(&mut n, 0x2102, 0, &[0]), Err(SdoAbort::ReadOnly.code()));
    assert_eq!(download(&mut n, 0x2000, 0, &[1, 2]), Err(SdoAbort::LengthTooHigh.code()));
    assert_eq!(download_segmented(&mut n, 0x2003, 0, &[1, 2, 3, 4, 5]), Err(SdoAbort::LengthTooHigh.code()));
    assert_eq!(download(&mut n, 0x9999, 0, &[1]), Err(SdoAbort::NoObject.code()));
    assert_eq!(n.write(0x2003, 0, &[1, 2], Side::Host), Err(SdoAbort::LengthTooLow));
    assert_eq!(n.write(0x2102, 0, &[0], Side::Bus), Err(SdoAbort::ReadOnly));
    assert_eq!(n.write(0x2000, 0, &[], Side::Device), Err(SdoAbort::LengthTooLow));
    assert_eq!(n.write(0x1A00, 0, &[0], Side::Host), Err(SdoAbort::DataTransferState), "a communication rule");
    assert_eq!(download(&mut n, 0x1010, 1, b"sav!"), Err(SdoAbort::DataTransfer.code()), "a wrong signature");
    assert_eq!(download(&mut n, 0x1010, 1, b"save"), Err(SdoAbort::Hardware.code()), "a store that fails");
    assert_eq!(indications(&mut n), [], "nothing was written");
    assert_eq!(read_u8(&mut n, 0x2000), 0);
    assert_eq!(download(&mut n, 0x1011, 1, b"load"), Ok(()));
    assert_eq!(indications(&mut n), [(0x1011, 1, b"load".to_vec(), WriteSource::Sdo)], "a restore that succeeded is a write");
}

#[test]
fn an_rpdo_indicates_each_mapped_entry_in_mapping_order() {
    let mut n = node(NodeConfig::new(ID), &[]);
    let rpdo1 = 0x200 + u32::from(ID);
    // RPDO1 maps 2001h, a dummy byte, 2003h and 2000h (CiA 301 remapping procedure).
    let mapping = [(0x1400, 1, 0x8000_0000 | rpdo1), (0x1600, 0, 0), (0x1600, 1, 0x2001_0008), (0x1600, 2, 0x0005_0008)];
    let mapping = [&mapping[..], &[(0x1600, 3, 0x2003_0020), (0x1600, 4, 0x2000_0008), (0x1600, 0, 4), (0x1400, 1, rpdo1)]].concat();
    for (index, sub, value) in mapping {
        assert_eq!(n.write(index, sub, &value_of(sub, value), Side::Device), Ok(()), "{index:04X}.{sub}");
    }
    assert_eq!(indications(&mut n).len(), 8, "each configuration write");
    nmt(&mut n, 0x01, ID);
    n.on_frame(&CanFrame::data(0x205, &[0x11, 0xEE, 0x44, 0x33, 0x22, 0x11, 0x22]).unwrap(), 0);
    let expected =
        [(0x2001, 0, vec![0x11], WriteSource::Rpdo), (0x2003, 0, vec![0x44, 0x33, 0x22, 0x11], WriteSource::Rpdo), (0x2000, 0, vec![0x22], WriteSource::Rpdo)];
    assert_eq!(indications(&mut n), expected, "three entries, the dummy byte skipped");
    assert_eq!((read_u8(&mut n, 0x2001), read(&mut n, 0x2003, 0), read_u8(&mut n, 0x2000)), (0x11, 0x1122_3344, 0x22));
    n.on_frame(&CanFrame::data(0x205, &[0x11, 0xEE]).unwrap(), 0);
    assert_eq!(indications(&mut n), [], "a PDO shorter than its mapping writes nothing");
}

/// A node whose 1F50h.2 streams, and CANopenIA's configuration file.
fn streaming_node() -> (TestNode, Vec<u8>) {
    let mut n = node(NodeConfig::new(ID), &[]);
    n.od_mut().app.streaming = true;
    (n, (0..2217_u32).map(|i| (i * 13 + i / 7) as u8).collect())
}

#[test]
fn a_download_streams_into_an_app_entry_through_the_nodes_small_buffer() {
    let (mut n, file) = streaming_node();
    assert_eq!(download_segmented(&mut n, 0x1F50, 2, &file), Ok(()), "2,217 bytes through an 8-byte buffer");
    assert_eq!(n.od().app.program, file);
    assert_eq!(indications(&mut n), [(0x1F50, 2, vec![], WriteSource::Sdo)], "indicated once, complete");
    assert_eq!(n.od().app.aborted, 0);
    n.od_mut().app.streaming = false;
    assert_eq!(download_segmented(&mut n, 0x1F50, 2, &file), Err(SdoAbort::OutOfMemory.code()), "not streaming: the buffer decides");
    assert_eq!(download_segmented(&mut n, 0x1F50, 2, b"whole"), Ok(()));
    assert_eq!((n.od().app.program.as_slice(), n.od().app.aborted), (&b"whole"[..], 0));
}

#[test]
fn nmt_commands_that_drop_a_streamed_download_abort_it_once() {
    let (mut n, file) = streaming_node();
    for (cs, what) in [(0x82, "reset communication"), (0x81, "reset node"), (0x02, "stop")] {
        n.od_mut().app.aborted = 0;
        assert_eq!(outcome(sdo(&mut n, initiate_segmented(0x1F50, 2, file.len()))), Ok(()));
        assert_eq!(outcome(sdo(&mut n, download_segment(0, &file[..7], false))), Ok(()));
        nmt(&mut n, cs, ID);
        frames(&mut n, 0);
        assert_eq!(n.od().app.aborted, 1, "{what}");
        nmt(&mut n, 0x80, ID);
        frames(&mut n, 0);
        assert_eq!(download_segmented(&mut n, 0x1F50, 2, &file), Ok(()), "after {what}");
        assert_eq!((n.od().app.program.as_slice(), n.od().app.aborted), (file.as_slice(), 1), "after {what}");
    }
    nmt(&mut n, 0x01, ID);
    assert_eq!(outcome(sdo(&mut n, initiate_segmented(0x1F50, 2, file.len()))), Ok(()));
    nmt(&mut n, 0x80, ID);
    assert_eq!(n.od().app.aborted, 1, "a state change SDO survives leaves the transfer running");
}

#[test]
fn the_node_keeps_a_stream_within_the_entrys_maximum() {
    let (mut n, _) = streaming_node();
    assert_eq!(outcome(sdo(&mut n, initiate_segmented(0x1F50, 2, usize::from(PROGRAM_MAX) + 1))), Err(SdoAbort::LengthTooHigh.code()));
    assert_eq!(n.od().app.aborted, 0, "refused at initiation: no stream");
    // Without a size, the part that goes past 4,000 bytes is refused.
    let [lo, hi] = 0x1F50_u16.to_le_bytes();
    assert_eq!(outcome(sdo(&mut n, [0x20, lo, hi, 2, 0, 0, 0, 0])), Ok(()));
    let parts = usize::from(PROGRAM_MAX).div_ceil(7);
    for i in 0..parts - 1 {
        assert_eq!(outcome(sdo(&mut n, download_segment(i, &[i as u8; 7], false))), Ok(()), "segment {i}");
    }
    assert_eq!(outcome(sdo(&mut n, download_segment(parts - 1, &[0; 7], true))), Err(SdoAbort::LengthTooHigh.code()));
    assert_eq!(n.od().app.aborted, 1);
    assert_eq!(indications(&mut n), [], "nothing completed");
}
