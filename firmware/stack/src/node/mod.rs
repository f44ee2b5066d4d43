//! The CANopen node: one generated dictionary, its parameter store, and every protocol
//! engine, driven by received frames and the current time.
//!
//! ```text
//! board ──on_frame(frame, now)──▶ Node ──poll(now)──▶ frames to send
//!                                   │
//!                  write/raise/trigger_tpdo (device code)
//! ```
//! All times are microseconds from an arbitrary epoch; the node never reads a clock itself.

mod comm;
mod target;

use crate::emcy::{EmcyDefault, EmcyEvent, EmcyProducer, Reaction};
use crate::frame::CanFrame;
use crate::guarding::{GuardEvent, Guarding};
use crate::heartbeat::{Consumer, ConsumerEvent, Producer};
use crate::leds::{LedState, Leds};
use crate::nmt::{self, NmtCommand, NmtState};
use crate::od::{AccessContext, Area, Dictionary, ObjectDictionary, SdoAbort, Side};
use crate::pdo::{Dir, Rpdo, Tpdo};
use crate::sdo::SdoServer;
use crate::store::ParamStore;
use heapless::{Deque, Vec};

/// Reads an integer entry (up to 4 bytes, little-endian) without access checks.
pub fn read_u32(od: &mut impl ObjectDictionary, index: u16, sub: u8) -> Option<u32> {
    let mut buf = [0_u8; 4];
    let n = od.read(index, sub, 0, &mut buf, Side::Device).ok()?.copied;
    Some(buf.iter().take(n).rev().fold(0_u32, |acc, &b| acc << 8 | u32::from(b)))
}

/// How a device's node differs from a plain CiA 301 slave.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NodeConfig {
    /// 1..=127.
    pub node_id: u8,
    /// SDO server timeout.
    pub sdo_timeout_us: u64,
    /// An object whose value 1 makes the node enter Operational by itself after boot-up
    /// (CR3101 20F4h "CANopen StartUp mode").
    pub startup_object: Option<u16>,
    /// Save every persistent entry as soon as it is written (CR3101: "all parameters are
    /// saved automatically").
    pub auto_save: bool,
    /// An object holding the bus-off restart time in ms, 0 = no automatic restart
    /// (frenzel+berg 2180h "CAN Restart Time").
    pub restart_time_object: Option<u16>,
    /// An object whose value 0 suppresses the boot-up message (frenzel+berg 2110h).
    pub bootup_object: Option<u16>,
}

impl NodeConfig {
    pub const fn new(node_id: u8) -> Self {
        NodeConfig { node_id, sdo_timeout_us: 1_000_000, startup_object: None, auto_save: false, restart_time_object: None, bootup_object: None }
    }
}

/// The CAN controller's error state, as the board reports it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BusState {
    Active,
    Warning,
    Passive,
    BusOff,
}

/// What the device code may want to react to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeEvent {
    /// NMT reset node: the application's own objects go back to power-on values.
    ResetApplication,
    ResetCommunication,
    StateChanged(NmtState),
    /// An RPDO (by offset from 1400h) wrote the dictionary.
    RpdoReceived(u16),
    /// The bus-off restart time elapsed: restart the CAN controller.
    RestartController,
}

const TX_QUEUE: usize = 12;
const EVENTS: usize = 4;

/// Everything except the SDO server, which borrows it as its [`crate::sdo::SdoTarget`].
#[derive(Debug)]
pub struct Core<D, S, const P: usize> {
    od: D,
    store: S,
    cfg: NodeConfig,
    /// Node-ID in use; a new one takes effect at reset communication.
    node_id: u8,
    pending_node_id: Option<u8>,
    state: NmtState,
    started: bool,
    now_us: u64,
    tx: Deque<CanFrame, TX_QUEUE>,
    events: Deque<NodeEvent, EVENTS>,
    /// Frames dropped because the transmit queue was full.
    pub tx_overflows: u32,
    emcy: EmcyProducer,
    emcy_cob: Option<u16>,
    emcy_inhibit: u16,
    sync_cob: Option<u16>,
    /// 1006h communication cycle period in us (0: SYNC not monitored).
    sync_period_us: u32,
    /// When the last SYNC arrived; monitoring starts with the first one.
    last_sync_us: Option<u64>,
    /// The SYNC timeout was reported and waits for the next SYNC to end it.
    sync_lost: bool,
    heartbeat: Producer,
    consumer: Consumer,
    guarding: Guarding,
    guard_cob: u16,
    rpdos: Vec<Rpdo, P>,
    tpdos: Vec<Tpdo, P>,
    /// A Bloom filter of the objects valid TPDOs map: most writes skip the TPDO scan.
    tpdo_mapped: u64,
    bus: BusState,
    bus_off_since: Option<u64>,
}

/// A CANopen slave node over dictionary `D` and parameter store `S`; `N` is the SDO download
/// buffer (the largest writable value), `P` the PDOs per direction.
#[derive(Debug)]
pub struct Node<D, S, const N: usize, const P: usize> {
    core: Core<D, S, P>,
    sdo: SdoServer<N>,
}

impl<D: Dictionary, S: ParamStore, const N: usize, const P: usize> Node<D, S, N, P> {
    /// A node that has not booted yet; call [`Node::start`].
    pub fn new(od: D, store: S, cfg: NodeConfig) -> Self {
        let mut sdo = SdoServer::new();
        sdo.set_timeout_us(cfg.sdo_timeout_us);
        let core = Core {
            od,
            store,
            node_id: cfg.node_id,
            cfg,
            pending_node_id: None,
            state: NmtState::PreOperational,
            started: false,
            now_us: 0,
            tx: Deque::new(),
            events: Deque::new(),
            tx_overflows: 0,
            emcy: EmcyProducer::new(),
            emcy_cob: None,
            emcy_inhibit: 0,
            sync_cob: None,
            sync_period_us: 0,
            last_sync_us: None,
            sync_lost: false,
            heartbeat: Producer::default(),
            consumer: Consumer::default(),
            guarding: Guarding::default(),
            guard_cob: 0,
            rpdos: Vec::new(),
            tpdos: Vec::new(),
            tpdo_mapped: 0,
            bus: BusState::Active,
            bus_off_since: None,
        };
        Node { core, sdo }
    }

    /// Power-on: Initialisation with stored parameters, boot-up message, then
    /// Pre-operational (or Operational if the start-up object says so).
    pub fn start(&mut self, now_us: u64) {
        self.core.now_us = now_us;
        self.core.started = true;
        self.core.initialise(Area::ALL, now_us);
    }

    /// A frame received from the bus.
    pub fn on_frame(&mut self, frame: &CanFrame, now_us: u64) {
        self.core.now_us = now_us;
        if !self.core.started {
            return;
        }
        let sdo_rx = 0x600 + u16::from(self.core.node_id);
        if frame.id == sdo_rx && !frame.rtr {
            if nmt::allows_sdo(self.core.state)
                && let Some(response) = self.sdo.on_request(frame.payload(), now_us, &mut self.core)
            {
                self.core.send_sdo(response);
            }
            return;
        }
        if frame.id == nmt::NMT_COB_ID {
            if let Some(cmd) = NmtCommand::parse(frame.payload(), self.core.node_id) {
                if matches!(cmd, NmtCommand::ResetNode | NmtCommand::ResetCommunication | NmtCommand::Stop) {
                    self.sdo.reset();
                }
                self.core.nmt_command(cmd, now_us);
            }
            return;
        }
        self.core.on_other_frame(frame, now_us);
    }

    /// Runs the timers and returns the next frame to send, if any. Call until `None`.
    pub fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        self.core.now_us = now_us;
        if !self.core.started {
            return None;
        }
        // A bus-off controller cannot send: frames wait in the queue for the restart.
        if self.core.bus == BusState::BusOff {
            self.core.check_restart(now_us);
            return None;
        }
        if let Some(frame) = self.core.tx.pop_front() {
            return Some(frame);
        }
        if nmt::allows_sdo(self.core.state)
            && let Some(segment) = self.sdo.poll(now_us, &mut self.core)
        {
            self.core.send_sdo(segment);
        }
        self.core.run_timers(now_us);
        self.core.tx.pop_front()
    }

    pub fn state(&self) -> NmtState {
        self.core.state
    }

    pub fn node_id(&self) -> u8 {
        self.core.node_id
    }

    /// Sets the node-ID used from the next reset communication on (CiA 301).
    pub fn set_node_id(&mut self, node_id: u8) {
        if (1..=127).contains(&node_id) {
            self.core.pending_node_id = Some(node_id);
        }
    }

    pub fn od(&self) -> &D {
        &self.core.od
    }

    /// Direct access for device code; writes that should trigger TPDOs or auto-save go
    /// through [`Node::write`].
    pub fn od_mut(&mut self) -> &mut D {
        &mut self.core.od
    }

    pub fn store(&self) -> &S {
        &self.core.store
    }

    /// A write by the device itself or its serial host, with the same side effects as an SDO
    /// download: communication-object checks, event-driven TPDOs, auto-save.
    pub fn write(&mut self, index: u16, sub: u8, data: &[u8], side: Side) -> Result<(), SdoAbort> {
        self.core.write(index, sub, data, side)
    }

    /// A read on behalf of `side`.
    pub fn read(&mut self, index: u16, sub: u8, offset: usize, buf: &mut [u8], side: Side) -> Result<crate::od::ReadLen, SdoAbort> {
        self.core.od.read(index, sub, offset, buf, side)
    }

    /// Raises an emergency (once until cleared) and applies its NMT reaction.
    pub fn raise(&mut self, e: &EmcyDefault) {
        self.core.raise(e, false);
    }

    /// Clears an emergency; sends "error reset" if it was active.
    pub fn clear(&mut self, e: &EmcyDefault) {
        self.core.clear(e);
    }

    /// The current error register (1001h).
    pub fn error_register(&self) -> u8 {
        self.core.emcy.register()
    }

    /// An application event for TPDO `number` (1-based: TPDO1 is 1800h).
    pub fn trigger_tpdo(&mut self, number: u16) {
        if let Some(t) = self.core.tpdos.iter_mut().find(|t| t.offset + 1 == number) {
            t.trigger();
        }
    }

    /// The CAN controller changed its error state.
    pub fn on_bus_state(&mut self, bus: BusState, now_us: u64) {
        self.core.now_us = now_us;
        self.core.on_bus_state(bus, now_us);
    }

    /// CiA 303-3 indicator states.
    pub fn leds(&self) -> Leds {
        self.core.leds()
    }

    /// The next event for the device code.
    pub fn take_event(&mut self) -> Option<NodeEvent> {
        self.core.events.pop_front()
    }

    /// Frames the node could not queue (its transmit queue was full).
    pub fn tx_overflows(&self) -> u32 {
        self.core.tx_overflows
    }
}

impl<D: Dictionary, S: ParamStore, const P: usize> Core<D, S, P> {
    fn ctx(&self) -> AccessContext {
        AccessContext { nmt: self.state, can_enabled: true }
    }

    fn send(&mut self, id: u16, data: &[u8]) {
        let Some(frame) = CanFrame::data(id, data) else { return };
        if self.tx.push_back(frame).is_err() {
            self.tx_overflows = self.tx_overflows.saturating_add(1);
        }
    }

    fn send_sdo(&mut self, payload: [u8; 8]) {
        self.send(0x580 + u16::from(self.node_id), &payload);
    }

    fn event(&mut self, e: NodeEvent) {
        // Device code that never drains events must not stop the node: oldest go first.
        if self.events.is_full() {
            self.events.pop_front();
        }
        let _ = self.events.push_back(e);
    }

    fn set_state(&mut self, state: NmtState) {
        if self.state != state {
            self.state = state;
            if state != NmtState::Operational {
                for r in &mut self.rpdos {
                    r.latched = None;
                    r.deadline_us = crate::pdo::slot::NEVER;
                }
            } else {
                let now = self.now_us;
                for t in &mut self.tpdos {
                    t.restart(now);
                }
            }
            self.event(NodeEvent::StateChanged(state));
        }
    }

    /// Initialisation after power-on or an NMT reset of `area`.
    fn initialise(&mut self, area: Area, now_us: u64) {
        if let Some(id) = self.pending_node_id.take() {
            self.node_id = id;
        }
        self.od.reset_area(area, self.node_id);
        // A store that cannot be read leaves the defaults: the node must still boot.
        let _ = self.store.load(&mut self.od, area);
        self.emcy.reset();
        self.tx.clear();
        self.guarding.reset();
        self.state = NmtState::PreOperational;
        self.reload_all(now_us);
        self.mirror_error_register(0);
        self.last_sync_us = None;
        self.sync_lost = false;
        if self.cfg.bootup_object.and_then(|i| read_u32(&mut self.od, i, 0)) != Some(0) {
            self.send(0x700 + u16::from(self.node_id), &[0x00]);
        }
        let operational = self.cfg.startup_object.and_then(|i| read_u32(&mut self.od, i, 0)) == Some(1);
        self.set_state(if operational { NmtState::Operational } else { NmtState::PreOperational });
    }

    fn nmt_command(&mut self, cmd: NmtCommand, now_us: u64) {
        match cmd {
            NmtCommand::Start => self.set_state(NmtState::Operational),
            NmtCommand::Stop => self.set_state(NmtState::Stopped),
            NmtCommand::EnterPreOperational => self.set_state(NmtState::PreOperational),
            NmtCommand::ResetNode => {
                self.event(NodeEvent::ResetApplication);
                self.initialise(Area::ALL, now_us);
            }
            NmtCommand::ResetCommunication => {
                self.event(NodeEvent::ResetCommunication);
                self.initialise(Area::COMMUNICATION, now_us);
            }
        }
    }

    fn on_other_frame(&mut self, frame: &CanFrame, now_us: u64) {
        let state = self.state;
        if Some(frame.id) == self.sync_cob && !frame.rtr && nmt::allows_emcy_and_sync(state) {
            // SYNC: no data, or the 1-byte counter.
            let counter = match frame.payload() {
                [] => None,
                [c] => Some(*c),
                _ => return,
            };
            self.last_sync_us = Some(now_us);
            if core::mem::take(&mut self.sync_lost) {
                self.clear_event(EmcyEvent::SyncTimeout);
            }
            if nmt::allows_pdo(state) {
                self.on_sync(counter);
            }
            return;
        }
        if frame.id == self.guard_cob {
            // Guarding is answered in every state, Stopped included.
            if frame.rtr {
                self.on_guard_request(now_us);
            }
            return;
        }
        if (0x701..=0x77F).contains(&frame.id) && !frame.rtr {
            if let [code] = frame.payload() {
                let node = (frame.id - 0x700) as u8;
                match self.consumer.on_heartbeat(node, *code, now_us) {
                    Some(ConsumerEvent::Recovered(_)) => self.clear_event(EmcyEvent::HeartbeatTimeout),
                    Some(ConsumerEvent::Lost(_)) | None => {}
                }
            }
            return;
        }
        if !nmt::allows_pdo(state) {
            return;
        }
        if frame.rtr {
            if let Some(i) = self.tpdos.iter().position(|t| t.comm.valid() && t.comm.id() == frame.id && t.comm.rtr_allowed()) {
                self.on_tpdo_rtr(i, now_us);
            }
            return;
        }
        if let Some(i) = self.rpdos.iter().position(|r| r.comm.valid() && r.comm.id() == frame.id) {
            self.on_rpdo(i, frame.payload());
        }
    }

    fn on_guard_request(&mut self, now_us: u64) {
        // CiA 301: a node with a heartbeat producer time does not answer guarding.
        if self.heartbeat.period_ms() != 0 {
            return;
        }
        let (byte, warned, lost) = self.guarding.on_request(nmt::state_code(self.state), now_us);
        self.send(self.guard_cob, &[byte]);
        if warned {
            self.clear_event(EmcyEvent::GuardingWarning);
        }
        if lost {
            self.clear_event(EmcyEvent::LifeGuarding);
        }
    }

    fn on_rpdo(&mut self, i: usize, data: &[u8]) {
        let Some(r) = self.rpdos.get(i).copied() else { return };
        if data.len() < usize::from(r.mapping.len()) || r.mapping.is_empty() {
            // CiA 301: a PDO shorter than its mapping is not processed.
            self.raise_event(EmcyEvent::RpdoLength);
            return;
        }
        // A PDO of the right length ends the length error.
        self.clear_event(EmcyEvent::RpdoLength);
        let now = self.now_us;
        if let Some(slot) = self.rpdos.get_mut(i)
            && slot.received(now)
        {
            self.clear_event(EmcyEvent::RpdoTimeout);
        }
        if r.comm.synchronous() {
            let mut buf = [0_u8; 8];
            let n = data.len().min(8);
            if let (Some(dst), Some(src)) = (buf.get_mut(..n), data.get(..n)) {
                dst.copy_from_slice(src);
            }
            if let Some(slot) = self.rpdos.get_mut(i) {
                slot.latched = Some((buf, n as u8));
            }
        } else {
            self.apply_rpdo(&r, data);
        }
    }

    /// Writes a received payload to the mapped objects. An entry the dictionary refuses (a
    /// value out of range) keeps its value; the others are written, with their side effects.
    fn apply_rpdo(&mut self, r: &Rpdo, data: &[u8]) {
        let entries = self.od.entries();
        let mut at = 0;
        for m in r.mapping.entries() {
            let end = at + usize::from(m.bytes);
            if let (Some(src), Some(info)) = (data.get(at..end), m.info(entries))
                && self.od.write_entry(info, m.sub, src).is_ok()
            {
                self.after_write(info.index, m.sub);
            }
            at = end;
        }
        self.event(NodeEvent::RpdoReceived(r.offset));
    }

    fn on_sync(&mut self, counter: Option<u8>) {
        for i in 0..self.rpdos.len() {
            let Some(r) = self.rpdos.get_mut(i) else { continue };
            if let Some((buf, n)) = r.latched.take() {
                let r = *r;
                self.apply_rpdo(&r, buf.get(..usize::from(n)).unwrap_or(&[]));
            }
        }
        let now = self.now_us;
        for i in 0..self.tpdos.len() {
            let Some(t) = self.tpdos.get_mut(i) else { continue };
            if !t.comm.valid() || !t.comm.synchronous() && t.comm.transmission_type != 252 {
                continue;
            }
            if t.comm.transmission_type == 252 {
                let mapping = t.mapping;
                let mut buf = [0_u8; 8];
                if let Ok(n) = mapping.pack(&mut self.od, &mut buf)
                    && let Some(t) = self.tpdos.get_mut(i)
                {
                    t.sampled = Some((buf, n as u8));
                }
            } else if t.on_sync(counter) {
                self.send_tpdo(i, now);
            }
        }
    }

    fn on_tpdo_rtr(&mut self, i: usize, now_us: u64) {
        let Some(t) = self.tpdos.get(i) else { return };
        if t.comm.transmission_type == 252 {
            if let Some((buf, n)) = t.sampled {
                let id = t.comm.id();
                self.send(id, buf.get(..usize::from(n)).unwrap_or(&[]));
            }
        } else {
            self.send_tpdo(i, now_us);
        }
    }

    fn send_tpdo(&mut self, i: usize, now_us: u64) {
        let Some(t) = self.tpdos.get(i) else { return };
        let (mapping, id) = (t.mapping, t.comm.id());
        let mut buf = [0_u8; 8];
        if let Ok(n) = mapping.pack(&mut self.od, &mut buf) {
            self.send(id, buf.get(..n).unwrap_or(&[]));
        }
        if let Some(t) = self.tpdos.get_mut(i) {
            t.sent(now_us);
        }
    }

    fn run_timers(&mut self, now_us: u64) {
        if self.heartbeat.due(now_us) {
            self.send(0x700 + u16::from(self.node_id), &[nmt::state_code(self.state)]);
        }
        match self.guarding.check(now_us) {
            Some(GuardEvent::LifeLost) => self.raise_event(EmcyEvent::LifeGuarding),
            Some(GuardEvent::Warning) => self.raise_event(EmcyEvent::GuardingWarning),
            None => {}
        }
        if let Some(ConsumerEvent::Lost(_)) = self.consumer.check(now_us) {
            self.raise_event(EmcyEvent::HeartbeatTimeout);
        }
        self.check_deadlines(now_us);
        if nmt::allows_pdo(self.state) {
            for i in 0..self.tpdos.len() {
                if self.tpdos.get_mut(i).is_some_and(|t| t.comm.valid() && t.due(now_us)) {
                    self.send_tpdo(i, now_us);
                }
            }
        }
        self.send_emcy();
    }

    /// The next queued emergency, if the state and the inhibit time allow it now.
    fn send_emcy(&mut self) {
        if nmt::allows_emcy_and_sync(self.state)
            && let Some(cob) = self.emcy_cob
            && let Some(frame) = self.emcy.next(self.now_us, self.emcy_inhibit)
        {
            self.send(cob, &frame);
        }
    }

    /// Bus-off: tells the board to restart the controller once the restart time has passed.
    fn check_restart(&mut self, now_us: u64) {
        let Some(since) = self.bus_off_since else { return };
        let restart_ms = self.cfg.restart_time_object.and_then(|i| read_u32(&mut self.od, i, 0));
        if restart_ms.is_some_and(|ms| ms != 0 && now_us.saturating_sub(since) >= u64::from(ms) * 1000) {
            self.bus_off_since = None;
            self.event(NodeEvent::RestartController);
        }
    }

    /// SYNC cycle (1006h) and RPDO deadline monitoring.
    fn check_deadlines(&mut self, now_us: u64) {
        let period = u64::from(self.sync_period_us);
        if period != 0
            && nmt::allows_emcy_and_sync(self.state)
            && !self.sync_lost
            && self.last_sync_us.is_some_and(|t| now_us.saturating_sub(t) > period + period / 2)
        {
            // Reported once; the next SYNC ends it.
            self.sync_lost = true;
            self.raise_event(EmcyEvent::SyncTimeout);
        }
        if nmt::allows_pdo(self.state) {
            // Every RPDO records its own timeout; one emergency covers them all.
            let mut overdue = false;
            for r in &mut self.rpdos {
                overdue |= r.overdue(now_us);
            }
            if overdue {
                self.raise_event(EmcyEvent::RpdoTimeout);
            }
        }
    }

    fn on_bus_state(&mut self, bus: BusState, now_us: u64) {
        let was = core::mem::replace(&mut self.bus, bus);
        if was == bus {
            return;
        }
        match bus {
            BusState::BusOff => {
                self.bus_off_since = Some(now_us);
                self.raise_event(EmcyEvent::BusOff);
            }
            BusState::Warning => self.raise_event(EmcyEvent::CanWarning),
            BusState::Passive => self.raise_event(EmcyEvent::CanPassive),
            BusState::Active => {}
        }
        if was == BusState::BusOff && bus != BusState::BusOff {
            self.bus_off_since = None;
            self.clear_event(EmcyEvent::BusOff);
            // "Return from bus-off" is an event, not a condition: raised and cleared at once.
            self.raise_event(EmcyEvent::BusOffRecovered);
            self.clear_event(EmcyEvent::BusOffRecovered);
        }
        if matches!(bus, BusState::Active) {
            self.clear_event(EmcyEvent::CanWarning);
            self.clear_event(EmcyEvent::CanPassive);
        }
    }

    /// The spec emergency for a stack event. Events whose frame is device-specific are only
    /// sent if the spec lists them: the guarding warning, and bus-off and its end (a node
    /// cannot send while bus-off; datasheets differ in what goes out on the return).
    fn event_emcy(&self, event: EmcyEvent) -> Option<EmcyDefault> {
        let spec = self.od.emergencies();
        match event {
            EmcyEvent::GuardingWarning | EmcyEvent::BusOff | EmcyEvent::BusOffRecovered => spec.iter().find(|e| e.event == Some(event)).copied(),
            _ => Some(EmcyDefault::for_event(event, spec)),
        }
    }

    fn raise_event(&mut self, event: EmcyEvent) {
        match self.event_emcy(event) {
            Some(e) => self.raise(&e, event.is_communication_error()),
            // Without an emergency to send, a communication error still gets its 1029h reaction.
            None if event.is_communication_error() => self.react(Reaction::ErrorBehaviour, true),
            None => {}
        }
    }

    fn clear_event(&mut self, event: EmcyEvent) {
        if let Some(e) = self.event_emcy(event) {
            self.clear(&e);
        }
    }

    fn raise(&mut self, e: &EmcyDefault, communication: bool) {
        if let Some(index) = e.enabled_by
            && read_u32(&mut self.od, index, 0) == Some(0)
        {
            return;
        }
        let Some(change) = self.emcy.raise(e) else { return };
        self.mirror_error_register(change.register);
        if let Some(entry) = change.history {
            self.push_history(entry);
        }
        // Sent before the reaction: an error that stops the node must still be reported.
        self.send_emcy();
        self.react(e.reaction, communication);
    }

    fn clear(&mut self, e: &EmcyDefault) {
        if let Some(change) = self.emcy.clear(e) {
            self.mirror_error_register(change.register);
        }
    }

    /// 1029h: what a communication (sub 1) or application (sub 2) error does to the state.
    fn react(&mut self, reaction: Reaction, communication: bool) {
        let behaviour = match reaction {
            Reaction::None => return,
            Reaction::PreOperational => 0,
            Reaction::Stopped => 2,
            Reaction::ErrorBehaviour => {
                let sub = if communication { 1 } else { 2 };
                read_u32(&mut self.od, 0x1029, sub).or_else(|| read_u32(&mut self.od, 0x1029, 1)).unwrap_or(0)
            }
        };
        match behaviour {
            0 if self.state == NmtState::Operational => self.set_state(NmtState::PreOperational),
            2 => self.set_state(NmtState::Stopped),
            _ => {}
        }
    }

    fn mirror_error_register(&mut self, register: u8) {
        let ctx = self.ctx();
        let _ = self.od.write(0x1001, 0, &[register], Side::Device, &ctx);
    }

    /// 1003h: newest error at sub 1, older ones shift down, sub 0 counts them.
    fn push_history(&mut self, entry: u32) {
        let slots = (1..=254_u8).take_while(|&s| self.od.entry(0x1003, s).is_ok()).count() as u8;
        if slots == 0 {
            return;
        }
        let ctx = self.ctx();
        let count = read_u32(&mut self.od, 0x1003, 0).unwrap_or(0).min(u32::from(slots)) as u8;
        let mut sub = count.saturating_add(1).min(slots);
        while sub > 1 {
            if let Some(older) = read_u32(&mut self.od, 0x1003, sub - 1) {
                let _ = self.od.write(0x1003, sub, &older.to_le_bytes(), Side::Device, &ctx);
            }
            sub -= 1;
        }
        let _ = self.od.write(0x1003, 1, &entry.to_le_bytes(), Side::Device, &ctx);
        let _ = self.od.write(0x1003, 0, &[count.saturating_add(1).min(slots)], Side::Device, &ctx);
    }

    fn leds(&self) -> Leds {
        let run = match self.state {
            NmtState::Stopped => LedState::SingleFlash,
            NmtState::PreOperational => LedState::Blinking,
            NmtState::Operational => LedState::On,
        };
        let error = match self.bus {
            BusState::BusOff => LedState::On,
            _ if self.guarding.lost() || self.consumer.any_lost() => LedState::DoubleFlash,
            _ if self.sync_lost => LedState::TripleFlash,
            BusState::Warning | BusState::Passive => LedState::SingleFlash,
            BusState::Active => LedState::Off,
        };
        Leds { run, error }
    }

    /// Re-reads every communication parameter the engines cache.
    fn reload_all(&mut self, now_us: u64) {
        self.reload_services(now_us);
        self.rpdos.clear();
        self.tpdos.clear();
        for offset in 0..0x200 {
            if self.rpdos.len() < P && self.od.entry(Dir::Rx.comm_base() + offset, 1).is_ok() {
                let r = Rpdo::load(&mut self.od, offset);
                let _ = self.rpdos.push(r);
            }
            if self.tpdos.len() < P && self.od.entry(Dir::Tx.comm_base() + offset, 1).is_ok() {
                let t = Tpdo::load(&mut self.od, offset, now_us);
                let _ = self.tpdos.push(t);
            }
        }
        self.refresh_tpdo_filter();
    }

    /// The filter bit of one object; a set bit means "maybe mapped".
    pub(super) const fn filter_bit(index: u16, sub: u8) -> u64 {
        1 << ((index ^ index >> 6 ^ (sub as u16).wrapping_mul(7)) & 63)
    }

    pub(super) fn refresh_tpdo_filter(&mut self) {
        let entries = self.od.entries();
        self.tpdo_mapped = self
            .tpdos
            .iter()
            .filter(|t| t.comm.valid())
            .flat_map(|t| t.mapping.entries())
            .filter_map(|m| m.info(entries).map(|i| Self::filter_bit(i.index, m.sub)))
            .fold(0, |acc, bit| acc | bit);
    }

    /// SYNC, EMCY, heartbeat, guarding and consumer parameters.
    fn reload_services(&mut self, now_us: u64) {
        self.reload_sync();
        self.reload_emcy();
        self.reload_guarding();
        self.reload_heartbeat(now_us);
        self.reload_consumer();
    }

    pub(super) fn reload_sync(&mut self) {
        self.sync_cob = read_u32(&mut self.od, 0x1005, 0).map(|c| (c & 0x7FF) as u16).or(Some(0x080));
        self.sync_period_us = read_u32(&mut self.od, 0x1006, 0).unwrap_or(0);
    }

    pub(super) fn reload_emcy(&mut self) {
        self.emcy_cob = match read_u32(&mut self.od, 0x1014, 0) {
            Some(c) if c & crate::pdo::COB_INVALID != 0 => None,
            Some(c) => Some((c & 0x7FF) as u16),
            None => Some(0x080 + u16::from(self.node_id)),
        };
        self.emcy_inhibit = read_u32(&mut self.od, 0x1015, 0).unwrap_or(0) as u16;
    }

    pub(super) fn reload_guarding(&mut self) {
        self.guard_cob = read_u32(&mut self.od, 0x100E, 0).map_or(0x700 + u16::from(self.node_id), |c| (c & 0x7FF) as u16);
        let guard_ms = read_u32(&mut self.od, 0x100C, 0).unwrap_or(0) as u16;
        let factor = read_u32(&mut self.od, 0x100D, 0).unwrap_or(0) as u8;
        self.guarding.configure(guard_ms, factor);
    }

    pub(super) fn reload_heartbeat(&mut self, now_us: u64) {
        let period = read_u32(&mut self.od, 0x1017, 0).unwrap_or(0) as u16;
        if period != self.heartbeat.period_ms() {
            self.heartbeat.configure(period, now_us);
        }
    }

    pub(super) fn reload_consumer(&mut self) {
        let count = read_u32(&mut self.od, 0x1016, 0).unwrap_or(0).min(127) as u8;
        let od = &mut self.od;
        let entries = (1..=count).map(|sub| read_u32(od, 0x1016, sub).unwrap_or(0));
        let mut list: Vec<u32, { crate::heartbeat::MAX_CONSUMED }> = Vec::new();
        for e in entries.filter(|&e| Consumer::decode(e).is_some()) {
            let _ = list.push(e);
        }
        self.consumer.configure(list.into_iter());
    }
}
