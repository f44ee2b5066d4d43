//! Node scanning: what a manager reads of a node when it appears (CiA 301 objects every node
//! has, and optionally its PDO configuration), one SDO transfer at a time.
//!
//! [`NodeScan`] walks one node: 1000h, 1018h.1..=4, then (if configured) the communication and
//! mapping parameters of its first TPDOs and RPDOs, then (if configured) a write of its
//! heartbeat producer time 1017h. [`Scanner`] queues the nodes to scan, runs one `NodeScan` at
//! a time and keeps the completed records in a bounded cache.
//!
//! What a node may lack is not an error: 1018h.2..=4 read as 0, a PDO whose communication
//! parameter cannot be read is recorded as not valid, a mapping that cannot be read is
//! recorded up to the last entry read, and a refused 1017h write is ignored. A node that does
//! not answer, or refuses 1000h or 1018h.1 (which CiA 301 makes mandatory), aborts its scan.

use crate::node::le_u32;
use crate::sdo::client::{AbortSource, SdoResult};
use heapless::Vec;

/// Mapping entries a classic CAN PDO can have.
pub const MAX_MAPPED: usize = 8;

/// What to read besides 1000h and 1018h.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ScanConfig {
    /// How many TPDOs and RPDOs (each, from the first) to read; 0 for none.
    pub pdos: u8,
    /// A heartbeat producer time to write to the node's 1017h.
    pub heartbeat_ms: Option<u16>,
}

/// One PDO of a scanned node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PdoInfo {
    /// Sub-index 1 of the communication parameter (bit 31 set: not valid).
    pub cob_id: u32,
    /// Sub-index 2: the transmission type.
    pub transmission: u8,
    count: u8,
    mapping: [u32; MAX_MAPPED],
}

impl PdoInfo {
    /// A PDO the node does not have.
    pub const ABSENT: PdoInfo = PdoInfo { cob_id: 0x8000_0000, transmission: 0, count: 0, mapping: [0; MAX_MAPPED] };

    /// Whether the PDO exists and is valid (bit 31 of the COB-ID clear).
    pub const fn is_valid(&self) -> bool {
        self.cob_id & 0x8000_0000 == 0
    }

    /// The mapping entries (index << 16 | sub << 8 | bits), in order.
    pub fn mapping(&self) -> &[u32] {
        self.mapping.get(..usize::from(self.count)).unwrap_or_default()
    }
}

/// What a scan found out about one node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Scanned<const PDOS: usize> {
    pub node: u8,
    /// 1000h.
    pub device_type: u32,
    /// 1018h.1..=4: vendor-ID, product code, revision number, serial number (0 if absent).
    pub identity: [u32; 4],
    pub tpdos: [PdoInfo; PDOS],
    pub rpdos: [PdoInfo; PDOS],
}

/// An SDO transfer a scan asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScanTransfer {
    Read { node: u8, index: u16, sub: u8 },
    Write { node: u8, index: u16, sub: u8, data: [u8; 2] },
}

/// The start and end of a node's scan.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScanEvent {
    Started(u8),
    Complete(u8),
    /// The node did not answer, or refused a mandatory object: the abort code.
    Aborted {
        node: u8,
        code: u32,
    },
}

/// How a scan goes on after a transfer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    Continue,
    Complete,
    Aborted(u32),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dir {
    Tx,
    Rx,
}

/// The object a scan reads next.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Step {
    DeviceType,
    Identity(u8),
    /// Sub-index 1 (COB-ID) or 2 (transmission type) of PDO `n`'s communication parameter.
    Comm {
        dir: Dir,
        n: u8,
        sub: u8,
    },
    MapCount {
        dir: Dir,
        n: u8,
    },
    MapEntry {
        dir: Dir,
        n: u8,
        sub: u8,
    },
    Heartbeat,
    Done,
}

/// The scan of one node.
#[derive(Debug, Clone)]
pub struct NodeScan<const PDOS: usize> {
    record: Scanned<PDOS>,
    step: Step,
    config: ScanConfig,
}

impl<const PDOS: usize> NodeScan<PDOS> {
    pub const fn new(node: u8, config: ScanConfig) -> Self {
        let record = Scanned { node, device_type: 0, identity: [0; 4], tpdos: [PdoInfo::ABSENT; PDOS], rpdos: [PdoInfo::ABSENT; PDOS] };
        NodeScan { record, step: Step::DeviceType, config }
    }

    pub const fn node(&self) -> u8 {
        self.record.node
    }

    /// What was read so far (all of it once complete).
    pub const fn record(&self) -> &Scanned<PDOS> {
        &self.record
    }

    /// The transfer the scan needs now; `None` once it has ended.
    pub fn transfer(&self) -> Option<ScanTransfer> {
        let node = self.record.node;
        let read = |index: u16, sub: u8| Some(ScanTransfer::Read { node, index, sub });
        match self.step {
            Step::DeviceType => read(0x1000, 0),
            Step::Identity(sub) => read(0x1018, sub),
            Step::Comm { dir, n, sub } => read(comm_index(dir, n), sub),
            Step::MapCount { dir, n } => read(comm_index(dir, n) + 0x200, 0),
            Step::MapEntry { dir, n, sub } => read(comm_index(dir, n) + 0x200, sub),
            Step::Heartbeat => self.config.heartbeat_ms.map(|ms| ScanTransfer::Write { node, index: 0x1017, sub: 0, data: ms.to_le_bytes() }),
            Step::Done => None,
        }
    }

    /// The outcome of the transfer [`transfer`](Self::transfer) asked for; `value` holds the
    /// uploaded bytes.
    pub fn on_result(&mut self, result: &SdoResult, value: &[u8]) -> Progress {
        let read = match *result {
            SdoResult::Uploaded { len } => Some(value.get(..len).map_or(0, le_u32)),
            SdoResult::Downloaded => Some(0),
            // The node is silent or broken: nothing more to learn from it.
            SdoResult::Aborted { code, by: AbortSource::Client } => return self.abort(code),
            SdoResult::Aborted { .. } => None,
        };
        self.step = match (self.step, read) {
            (Step::DeviceType, None) | (Step::Identity(1), None) => {
                let code = match *result {
                    SdoResult::Aborted { code, .. } => code,
                    _ => 0,
                };
                return self.abort(code);
            }
            (Step::DeviceType, Some(v)) => {
                self.record.device_type = v;
                Step::Identity(1)
            }
            (Step::Identity(sub), v) => {
                if let Some(slot) = self.record.identity.get_mut(usize::from(sub).wrapping_sub(1)) {
                    *slot = v.unwrap_or(0);
                }
                if sub < 4 { Step::Identity(sub + 1) } else { self.first_pdo() }
            }
            (Step::Comm { dir, n, sub: 1 }, Some(cob_id)) => {
                self.pdo(dir, n, |p| p.cob_id = cob_id);
                Step::Comm { dir, n, sub: 2 }
            }
            (Step::Comm { dir, n, sub: 1 }, None) => {
                self.pdo(dir, n, |p| *p = PdoInfo::ABSENT);
                self.next_pdo(dir, n)
            }
            (Step::Comm { dir, n, .. }, t) => {
                self.pdo(dir, n, |p| p.transmission = t.unwrap_or(0) as u8);
                Step::MapCount { dir, n }
            }
            (Step::MapCount { dir, n }, v) => {
                let count = v.map_or(0, |c| c.min(MAX_MAPPED as u32) as u8);
                self.pdo(dir, n, |p| p.count = count);
                if count == 0 { self.next_pdo(dir, n) } else { Step::MapEntry { dir, n, sub: 1 } }
            }
            (Step::MapEntry { dir, n, sub }, Some(entry)) => {
                let mut count = 0;
                self.pdo(dir, n, |p| {
                    if let Some(slot) = p.mapping.get_mut(usize::from(sub).wrapping_sub(1)) {
                        *slot = entry;
                    }
                    count = p.count;
                });
                if sub < count { Step::MapEntry { dir, n, sub: sub + 1 } } else { self.next_pdo(dir, n) }
            }
            (Step::MapEntry { dir, n, sub }, None) => {
                // The mapping ends at the last entry the node gave.
                self.pdo(dir, n, |p| p.count = sub - 1);
                self.next_pdo(dir, n)
            }
            (Step::Heartbeat | Step::Done, _) => Step::Done,
        };
        if self.step == Step::Heartbeat && self.config.heartbeat_ms.is_none() {
            self.step = Step::Done;
        }
        if self.step == Step::Done { Progress::Complete } else { Progress::Continue }
    }

    fn abort(&mut self, code: u32) -> Progress {
        self.step = Step::Done;
        Progress::Aborted(code)
    }

    fn pdos(&self) -> u8 {
        self.config.pdos.min(u8::try_from(PDOS).unwrap_or(u8::MAX))
    }

    fn first_pdo(&self) -> Step {
        if self.pdos() == 0 { Step::Heartbeat } else { Step::Comm { dir: Dir::Tx, n: 0, sub: 1 } }
    }

    fn next_pdo(&self, dir: Dir, n: u8) -> Step {
        match dir {
            _ if n + 1 < self.pdos() => Step::Comm { dir, n: n + 1, sub: 1 },
            Dir::Tx => Step::Comm { dir: Dir::Rx, n: 0, sub: 1 },
            Dir::Rx => Step::Heartbeat,
        }
    }

    fn pdo(&mut self, dir: Dir, n: u8, f: impl FnOnce(&mut PdoInfo)) {
        let pdos = match dir {
            Dir::Tx => &mut self.record.tpdos,
            Dir::Rx => &mut self.record.rpdos,
        };
        if let Some(p) = pdos.get_mut(usize::from(n)) {
            f(p);
        }
    }
}

/// The communication parameter of PDO `n` (0-based): 1800h + n for a TPDO, 1400h + n for an
/// RPDO; the mapping parameter is 200h above it.
const fn comm_index(dir: Dir, n: u8) -> u16 {
    match dir {
        Dir::Tx => 0x1800 + n as u16,
        Dir::Rx => 0x1400 + n as u16,
    }
}

/// Scans queued nodes one at a time and caches up to `NODES` completed records.
#[derive(Debug, Clone)]
pub struct Scanner<const NODES: usize, const PDOS: usize> {
    config: ScanConfig,
    /// Nodes waiting for a scan, one bit each (bit n: node n).
    pending: u128,
    /// Nodes scanned to the end, cached or not any more.
    done: u128,
    current: Option<NodeScan<PDOS>>,
    /// Completed scans, oldest first: a full cache forgets its oldest record.
    cache: Vec<Scanned<PDOS>, NODES>,
}

impl<const NODES: usize, const PDOS: usize> Scanner<NODES, PDOS> {
    pub const fn new(config: ScanConfig) -> Self {
        Scanner { config, pending: 0, done: 0, current: None, cache: Vec::new() }
    }

    pub fn set_config(&mut self, config: ScanConfig) {
        self.config = config;
    }

    /// Queues a scan of `node` (1..=127); a node being scanned is scanned again afterwards.
    pub fn request(&mut self, node: u8) {
        if (1..=127).contains(&node) {
            self.pending |= 1 << node;
        }
    }

    /// Whether `node` was scanned to the end (even if its record has left the cache), or is
    /// being scanned or queued.
    pub fn knows(&self, node: u8) -> bool {
        let bit = if node < 128 { 1 << node } else { 0 };
        (self.pending | self.done) & bit != 0 || self.current.as_ref().is_some_and(|s| s.node() == node)
    }

    /// Starts the scan of the lowest queued node if none is running.
    pub fn start_next(&mut self) -> Option<ScanEvent> {
        if self.current.is_some() || self.pending == 0 {
            return None;
        }
        let node = self.pending.trailing_zeros() as u8;
        self.pending &= !(1 << node);
        self.current = Some(NodeScan::new(node, self.config));
        Some(ScanEvent::Started(node))
    }

    /// The transfer the running scan needs.
    pub fn transfer(&self) -> Option<ScanTransfer> {
        self.current.as_ref()?.transfer()
    }

    /// The outcome of that transfer; the end of the scan, if it ended.
    pub fn on_result(&mut self, result: &SdoResult, value: &[u8]) -> Option<ScanEvent> {
        let scan = self.current.as_mut()?;
        let node = scan.node();
        match scan.on_result(result, value) {
            Progress::Continue => None,
            Progress::Aborted(code) => {
                self.current = None;
                Some(ScanEvent::Aborted { node, code })
            }
            Progress::Complete => {
                let record = *scan.record();
                self.current = None;
                self.done |= 1 << node;
                self.store(record);
                Some(ScanEvent::Complete(node))
            }
        }
    }

    fn store(&mut self, record: Scanned<PDOS>) {
        if let Some(i) = self.cache.iter().position(|r| r.node == record.node) {
            self.cache.remove(i);
        } else if self.cache.is_full() && !self.cache.is_empty() {
            self.cache.remove(0);
        }
        // Room was made above; a cache of capacity 0 keeps nothing.
        let _ = self.cache.push(record);
    }

    /// The last completed scan of `node`.
    pub fn scanned(&self, node: u8) -> Option<&Scanned<PDOS>> {
        self.cache.iter().find(|r| r.node == node)
    }

    /// Every cached record, oldest first.
    pub fn cached(&self) -> &[Scanned<PDOS>] {
        &self.cache
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CONFIG: ScanConfig = ScanConfig { pdos: 2, heartbeat_ms: Some(100) };

    fn read(n: u32) -> (SdoResult, [u8; 4]) {
        (SdoResult::Uploaded { len: 4 }, n.to_le_bytes())
    }

    fn refused() -> (SdoResult, [u8; 4]) {
        (SdoResult::Aborted { code: 0x0602_0000, by: AbortSource::Server }, [0; 4])
    }

    /// Answers each transfer the scan asks for with `answer`, until it ends: the transfers
    /// asked for, in order, and how the scan ended.
    fn run(scan: &mut NodeScan<2>, mut answer: impl FnMut(ScanTransfer) -> (SdoResult, [u8; 4])) -> (heapless::Vec<ScanTransfer, 64>, Progress) {
        let mut asked = heapless::Vec::new();
        while let Some(t) = scan.transfer() {
            asked.push(t).expect("a bounded scan");
            let (result, value) = answer(t);
            match scan.on_result(&result, &value) {
                Progress::Continue => {}
                end => return (asked, end),
            }
        }
        (asked, Progress::Continue)
    }

    #[test]
    fn what_a_node_lacks_is_recorded_not_fatal() {
        let mut scan = NodeScan::<2>::new(9, CONFIG);
        let (asked, end) = run(&mut scan, |t| match t {
            ScanTransfer::Read { index: 0x1000, .. } => read(0x0003_0191),
            ScanTransfer::Read { index: 0x1018, sub: 1, .. } => read(0x58),
            ScanTransfer::Read { index: 0x1018, .. } => refused(),
            // TPDO1: COB-ID 189h, type 254, three entries of which the third cannot be read.
            ScanTransfer::Read { index: 0x1800, sub: 1, .. } => read(0x189),
            ScanTransfer::Read { index: 0x1800, sub: 2, .. } => read(254),
            ScanTransfer::Read { index: 0x1A00, sub: 0, .. } => read(3),
            ScanTransfer::Read { index: 0x1A00, sub: 3, .. } => refused(),
            ScanTransfer::Read { index: 0x1A00, sub, .. } => read(0x6000_0008 | u32::from(sub) << 8),
            // The other PDOs do not exist.
            ScanTransfer::Read { .. } => refused(),
            ScanTransfer::Write { .. } => (SdoResult::Downloaded, [0; 4]),
        });
        assert_eq!(end, Progress::Complete);
        let r = scan.record();
        assert_eq!((r.node, r.device_type, r.identity), (9, 0x0003_0191, [0x58, 0, 0, 0]));
        assert_eq!((r.tpdos[0].cob_id, r.tpdos[0].transmission, r.tpdos[0].mapping()), (0x189, 254, &[0x6000_0108, 0x6000_0208][..]));
        assert!(r.tpdos[0].is_valid());
        assert!(!r.tpdos[1].is_valid() && !r.rpdos[0].is_valid() && !r.rpdos[1].is_valid());
        // 1000h, 1018h.1..4, TPDO1 (2 comm + count + 3 entries), TPDO2, RPDO1, RPDO2 (one
        // refused read each), the 1017h write.
        assert_eq!(asked.len(), 1 + 4 + 6 + 3 + 1);
        assert_eq!(asked.last(), Some(&ScanTransfer::Write { node: 9, index: 0x1017, sub: 0, data: [100, 0] }));
    }

    #[test]
    fn a_silent_node_or_a_missing_mandatory_object_aborts() {
        let mut scan = NodeScan::<2>::new(9, CONFIG);
        let timeout = SdoResult::Aborted { code: 0x0504_0000, by: AbortSource::Client };
        assert_eq!(scan.on_result(&timeout, &[]), Progress::Aborted(0x0504_0000));
        assert_eq!(scan.transfer(), None);
        let mut scan = NodeScan::<2>::new(9, CONFIG);
        let (_, end) = run(&mut scan, |t| if matches!(t, ScanTransfer::Read { index: 0x1000, .. }) { read(0x191) } else { refused() });
        assert_eq!(end, Progress::Aborted(0x0602_0000), "1018h.1 is mandatory");
        // A timeout in the middle ends the scan too.
        let mut scan = NodeScan::<2>::new(9, ScanConfig { pdos: 0, heartbeat_ms: None });
        let (asked, end) = run(&mut scan, |t| match t {
            ScanTransfer::Read { index: 0x1018, sub: 3, .. } => (timeout, [0; 4]),
            _ => read(1),
        });
        assert_eq!((asked.len(), end), (4, Progress::Aborted(0x0504_0000)));
    }

    #[test]
    fn the_scanner_queues_caches_and_forgets_the_oldest() {
        let mut s = Scanner::<2, 2>::new(ScanConfig::default());
        for n in [7, 3, 5] {
            s.request(n);
        }
        s.request(0);
        s.request(128);
        let mut order = heapless::Vec::<u8, 4>::new();
        while let Some(ScanEvent::Started(n)) = s.start_next() {
            order.push(n).expect("three scans");
            assert!(s.knows(n));
            let mut end = None;
            while end.is_none() {
                end = s.on_result(&SdoResult::Uploaded { len: 4 }, &[1, 0, 0, 0]);
            }
            assert_eq!(end, Some(ScanEvent::Complete(n)));
        }
        assert_eq!(order, [3, 5, 7], "lowest node-ID first; 0 and 128 are no nodes");
        assert_eq!(s.cached().iter().map(|r| r.node).collect::<heapless::Vec<u8, 2>>(), [5, 7], "node 3 left the full cache");
        assert!(s.knows(3), "scanned, though no longer cached");
        assert!(s.scanned(3).is_none() && s.scanned(7).is_some_and(|r| r.device_type == 1));
    }
}
