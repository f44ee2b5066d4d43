#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! coforge-stack's manager on the virtual bus with simulated CO401Memory1 modules: the exact
//! event sequence of booting, scanning, starting, stopping, emergencies and a lost heartbeat;
//! a caller's SDO transfer served before the scanner's next; 126 nodes on one bus.

use coforge_sim::devices::{DeviceKind, StoreAt};
use coforge_sim::vbus::VirtualBus;
use coforge_stack::manager::monitor::{MonitorEvent, NodeState};
use coforge_stack::manager::scan::{ScanConfig, ScanEvent};
use coforge_stack::manager::{Manager, ManagerEvent};
use coforge_stack::nmt::NmtCommand;
use coforge_stack::sdo::client::SdoResult;

/// The manager as the bus's master, with every event it reported and when (ms).
struct Net<const NODES: usize> {
    bus: VirtualBus,
    manager: Manager<NODES, 2>,
    buf: [u8; 64],
    events: Vec<(u64, ManagerEvent)>,
}

impl<const NODES: usize> Net<NODES> {
    fn new(ids: impl IntoIterator<Item = u8>, scan: ScanConfig) -> Self {
        let kind = DeviceKind::find("co401memory1").unwrap();
        let nodes = ids.into_iter().map(|id| kind.create(None, id, &StoreAt::Memory).unwrap()).collect();
        let mut net = Net { bus: VirtualBus::new(nodes), manager: Manager::new(scan), buf: [0; 64], events: Vec::new() };
        net.manager.monitor_mut().set_consumer_ms(None, 250);
        net.pump();
        net
    }

    fn now_us(&self) -> u64 {
        self.bus.now_us()
    }

    /// Frames both ways until the bus is quiet; events taken as they come.
    fn pump(&mut self) {
        loop {
            let now = self.now_us();
            while let Some(frame) = self.bus.recv() {
                self.manager.on_frame(&frame, now, &mut self.buf);
                self.take_events();
            }
            let sent = self.manager.poll(now, &mut self.buf);
            self.take_events();
            match sent {
                Some(frame) => self.bus.send(frame),
                None => return,
            }
        }
    }

    fn take_events(&mut self) {
        let ms = self.now_us() / 1000;
        while let Some(e) = self.manager.take_event() {
            self.events.push((ms, e));
        }
    }

    fn run_ms(&mut self, ms: u64) {
        for _ in 0..ms {
            self.bus.advance_ms(1);
            self.pump();
        }
    }

    fn take(&mut self) -> Vec<ManagerEvent> {
        self.events.drain(..).map(|(_, e)| e).collect()
    }
}

fn node(e: MonitorEvent) -> ManagerEvent {
    ManagerEvent::Node(e)
}

fn scan(e: ScanEvent) -> ManagerEvent {
    ManagerEvent::Scan(e)
}

#[test]
fn boot_scan_start_stop_emergency_and_loss_in_order() {
    let mut net = Net::<8>::new([2, 3, 4], ScanConfig { pdos: 2, heartbeat_ms: Some(100) });
    net.run_ms(50);
    let mut expected = vec![node(MonitorEvent::BootUp(2)), node(MonitorEvent::BootUp(3)), node(MonitorEvent::BootUp(4))];
    // Blank EEPROMs: each module reports its bank 1, then banks 1 and 2 (CO401Memory1 combines
    // the codes of its active errors).
    for bits in [0x10, 0x30] {
        expected.extend([2, 3, 4].map(|n| node(MonitorEvent::Emergency { node: n, code: 0x1000, register: 0x01, data: [0x00, bits, 0, 0, 0] })));
    }
    for n in [2, 3, 4] {
        expected.extend([scan(ScanEvent::Started(n)), scan(ScanEvent::Complete(n))]);
    }
    assert_eq!(net.take(), expected, "boot-ups, then one scan after the other (all within 50 ms)");
    let scanned = net.manager.scanned(3).unwrap();
    assert_eq!(scanned.device_type, 0x0003_0191, "1000h: DS401, digital in and out");
    assert_eq!(scanned.identity, [0x58, 0x0140_1FFE, 0x0001_0078, 0], "1018h.1..=4 as the spec has them");
    assert_eq!((scanned.tpdos[0].cob_id, scanned.tpdos[0].mapping()), (0x183, &[0x6000_0108, 0x6000_0208][..]), "TPDO1 as the spec maps it");
    assert!(!scanned.tpdos[1].is_valid() && !scanned.rpdos[1].is_valid(), "the second PDOs are disabled by default");
    assert_eq!(scanned.rpdos[0].cob_id, 0x203);

    // The 1017h each scan wrote starts the heartbeats: monitoring runs.
    net.run_ms(150);
    let started: Vec<_> = net.take();
    assert_eq!(started, [2, 3, 4].map(|n| node(MonitorEvent::HeartbeatStarted { node: n, state: NodeState::PreOperational })));

    assert!(net.manager.nmt(NmtCommand::Start, 0));
    net.pump();
    net.run_ms(100);
    assert_eq!(net.take(), [2, 3, 4].map(|n| node(MonitorEvent::StateChanged { node: n, from: NodeState::PreOperational, to: NodeState::Operational })));

    assert!(net.manager.nmt(NmtCommand::Stop, 3));
    net.pump();
    net.run_ms(100);
    assert_eq!(net.take(), [node(MonitorEvent::StateChanged { node: 3, from: NodeState::Operational, to: NodeState::Stopped })]);

    // The manager clears node 4's bank errors with the memory command 91h (6200h.1 and .2).
    for bank in [1, 2] {
        net.buf[0] = 0x91;
        net.manager.download(4, 0x6200, bank, 1).unwrap();
        net.pump();
    }
    net.run_ms(10);
    // Each memory command ends one error: an error reset with the error register left.
    assert_eq!(
        net.take(),
        [
            ManagerEvent::Sdo(SdoResult::Downloaded),
            node(MonitorEvent::EmergencyCleared { node: 4, register: 0x01 }),
            ManagerEvent::Sdo(SdoResult::Downloaded),
            node(MonitorEvent::EmergencyCleared { node: 4, register: 0 }),
        ]
    );

    // Node 4's supply drops below 15 V and comes back.
    net.bus.nodes[2].console("supply 14000").unwrap();
    net.run_ms(20);
    let low = net.take();
    assert!(
        matches!(low.as_slice(), [ManagerEvent::Node(MonitorEvent::Emergency { node: 4, code: 0x1000, register, data: [0x00, 0x40, 0, 0, 0] })] if register & 1 == 1),
        "{low:?}"
    );
    net.bus.nodes[2].console("supply 24000").unwrap();
    net.run_ms(20);
    assert_eq!(net.take(), [node(MonitorEvent::EmergencyCleared { node: 4, register: 0 })]);
    assert!(net.manager.status(4).is_some_and(|s| !s.emergency_active));

    // Node 2 leaves the bus: lost after the consumer time (250 ms) from its last heartbeat.
    net.bus.nodes.remove(0);
    net.run_ms(400);
    let lost = std::mem::take(&mut net.events);
    assert_eq!(lost.iter().map(|(_, e)| *e).collect::<Vec<_>>(), [node(MonitorEvent::HeartbeatLost(2))]);

    // A reset of node 3: boot-up, a new scan, and heartbeats again.
    assert!(net.manager.nmt(NmtCommand::ResetNode, 3));
    net.pump();
    net.run_ms(150);
    let events = net.take();
    assert_eq!(
        events[..6],
        [
            node(MonitorEvent::BootUp(3)),
            node(MonitorEvent::Emergency { node: 3, code: 0x1000, register: 0x01, data: [0x00, 0x10, 0, 0, 0] }),
            node(MonitorEvent::Emergency { node: 3, code: 0x1000, register: 0x01, data: [0x00, 0x30, 0, 0, 0] }),
            scan(ScanEvent::Started(3)),
            scan(ScanEvent::Complete(3)),
            node(MonitorEvent::HeartbeatStarted { node: 3, state: NodeState::PreOperational })
        ]
    );
}

#[test]
fn a_callers_transfer_goes_before_the_scanners_next() {
    let mut net = Net::<8>::new([5], ScanConfig { pdos: 2, heartbeat_ms: None });
    assert!(net.manager.scanned(5).is_some(), "the scan ran during the boot");
    net.manager.scan(5);
    // The scanner's first transfer starts at the next poll; queue the caller's behind it.
    let now = net.now_us();
    let first = net.manager.poll(now, &mut net.buf).unwrap();
    assert_eq!(first.data[..4], [0x40, 0x00, 0x10, 0x00], "the scan reads 1000h first");
    net.manager.upload(5, 0x1018, 2).unwrap();
    assert_eq!(net.manager.upload(5, 0x1018, 3), Err(coforge_stack::sdo::client::StartError::Busy));
    net.bus.send(first);
    let log_start = net.bus.log.len();
    net.pump();
    let requests: Vec<[u8; 4]> = net.bus.log[log_start..].iter().filter(|(_, f)| f.id == 0x605).map(|(_, f)| f.data[..4].try_into().unwrap()).collect();
    assert_eq!(requests[0], [0x40, 0x18, 0x10, 0x02], "the caller's upload right after the scanner's transfer in progress");
    assert_eq!(requests[1], [0x40, 0x18, 0x10, 0x01], "then the scan goes on");
    let results: Vec<_> = net.take().into_iter().filter(|e| matches!(e, ManagerEvent::Sdo(_))).collect();
    assert_eq!(results, [ManagerEvent::Sdo(SdoResult::Uploaded { len: 4 })]);
}

#[test]
fn scans_126_nodes_on_one_bus() {
    let mut net = Net::<31>::new(1..=126, ScanConfig { pdos: 2, heartbeat_ms: Some(100) });
    net.run_ms(2000);
    let boots = net.events.iter().filter(|(_, e)| matches!(e, ManagerEvent::Node(MonitorEvent::BootUp(_)))).count();
    let complete: Vec<u64> = net.events.iter().filter(|(_, e)| matches!(e, ManagerEvent::Scan(ScanEvent::Complete(_)))).map(|(ms, _)| *ms).collect();
    let hb = net.events.iter().filter(|(_, e)| matches!(e, ManagerEvent::Node(MonitorEvent::HeartbeatStarted { .. }))).count();
    assert_eq!(boots, 126);
    assert_eq!(complete.len(), 126, "every node scanned");
    assert_eq!(hb, 126, "every node's heartbeat monitored");
    assert_eq!(net.manager.events_dropped, 0);
    assert_eq!(net.manager.scans().len(), 31, "the cache keeps the last 31");
    assert_eq!(net.manager.scans().first().map(|s| s.node), Some(96));
    assert!((1..=126).all(|n| net.manager.status(n).is_some_and(|s| s.state == NodeState::PreOperational)));
    assert!(complete.iter().all(|&ms| ms == 0), "the virtual bus takes no time per frame: all scans end at once");
}
