//! The CANopen node: one generated dictionary, its parameter store, and every protocol
//! engine, driven by received frames and the current time.
//!
//! ```text
//! board ──on_frame(frame, now)──▶ Node ──poll(now)──▶ frames to send
//!                                   │
//!   write/raise/trigger_tpdo/trigger_mapped/send_frame (device code)
//! ```
//! All times are microseconds from an arbitrary epoch; the node never reads a clock itself.
//! Deadlines saturate at `u64::MAX` (584 000 years) rather than overflow.
//!
//! Every write that takes effect is indicated to the dictionary's app objects
//! ([`AppObjects::written`](crate::od::AppObjects::written)): SDO downloads, each entry an
//! RPDO writes, [`Node::write`] by the host or the device, 1010h/1011h commands that
//! succeeded, a streamed download once its last part is taken (with empty data). A refused
//! write, or one whose auto-save failed (answered `Hardware`), is not indicated; nor are
//! [`Node::od_mut`] accesses and the node's own bookkeeping (1001h, 1003h).
//!
//! - `target`: writes with their side effects, and the SDO server's view of the node;
//! - `comm`: the CiA 301 rules for writes to communication objects (PDO remapping and more);
//! - `process_data`: RPDOs and TPDOs at run time;
//! - `errors`: emergencies, 1029h reactions, bus states, indicators;
//! - `monitoring`: the services configured from the dictionary and their monitors.

mod comm;
mod errors;
mod monitoring;
mod process_data;
mod target;
#[cfg(test)]
mod tests;

use crate::emcy::{EmcyDefault, EmcyEvent, EmcyProducer};
use crate::frame::CanFrame;
use crate::guarding::{GuardEvent, Guarding};
use crate::heartbeat::{Consumer, ConsumerEvent, Producer};
use crate::leds::Leds;
use crate::nmt::{self, NmtCommand, NmtState};
use crate::od::{AccessContext, Area, EntryAccess, NodeDictionary, SdoAbort, Side, WriteSource};
use crate::pdo::mapping::Mapping;
use crate::pdo::slot::NEVER;
use crate::pdo::{Dir, Rpdo, Tpdo};
use crate::ring::Ring;
use crate::sdo::SdoServer;
use crate::store::ParamStore;
use heapless::Vec;

pub use crate::config::NodeConfig;

/// Reads an integer entry (up to 4 bytes, little-endian) without access checks.
pub fn read_u32(od: &mut impl EntryAccess, index: u16, sub: u8) -> Option<u32> {
    let mut buf = [0_u8; 4];
    let n = od.read(index, sub, 0, &mut buf, Side::Device).ok()?.copied;
    Some(le_u32(buf.get(..n).unwrap_or(&buf)))
}

/// Up to 4 little-endian bytes as a number (shorter values zero-extended).
pub(crate) fn le_u32(data: &[u8]) -> u32 {
    data.iter().take(4).rev().fold(0, |acc, &b| acc << 8 | u32::from(b))
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
#[repr(align(4))]
pub enum NodeEvent {
    /// NMT reset node: the application's own objects go back to power-on values.
    ResetApplication,
    ResetCommunication,
    StateChanged(NmtState),
    /// An RPDO (by offset from 1400h) wrote the dictionary.
    RpdoReceived(u16),
    /// The bus-off restart time elapsed: restart the CAN controller.
    RestartController,
    /// An emergency frame went into the transmit queue: its 8 data bytes as sent (error code,
    /// error register, manufacturer bytes). Not raised for a frame the full queue lost.
    EmergencySent([u8; 8]),
    /// An NMT module control frame addressed to this node or to all nodes arrived: its command
    /// specifier (byte 0), raised before the command takes effect, whether it changes the
    /// state or not, and for specifiers CiA 301 does not define.
    NmtReceived(u8),
}

const TX_QUEUE: usize = 12;
/// Events waiting for the device code; when full, the oldest is dropped for a new one.
const EVENTS: usize = 8;

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
    /// Powered on: the dictionary holds its defaults and stored parameters.
    powered: bool,
    /// The CAN side runs: frames are received and sent (CO401GW1's host enables it).
    can_enabled: bool,
    /// 1011h erased the store and the dictionary has not been reloaded since: a 1010h save
    /// keeps the store erased (see `store_command`).
    restore_pending: bool,
    now_us: u64,
    tx: Ring<CanFrame, TX_QUEUE>,
    events: Ring<NodeEvent, EVENTS>,
    /// Frames dropped because the transmit queue was full.
    pub tx_overflows: u32,
    emcy: EmcyProducer,
    emcy_cob: Option<u16>,
    emcy_inhibit: u16,
    sync_cob: Option<u16>,
    /// 1006h communication cycle period in us (0: SYNC not monitored).
    sync_period_us: u32,
    /// When the last SYNC arrived, [`NEVER`] before the first: monitoring starts with it.
    /// (Plain `u64`s here and in `bus_off_since`: `Option` would double each.)
    last_sync_us: u64,
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
    /// An RPDO length error is active (cleared by the next correct RPDO).
    rpdo_length_error: bool,
    bus: BusState,
    /// When the controller went bus-off; [`NEVER`] while it is not (or was restarted).
    bus_off_since: u64,
}

/// A CANopen slave node over dictionary `D` and parameter store `S`; `N` is the SDO download
/// buffer (the largest writable value), `P` the PDOs per direction.
#[derive(Debug)]
pub struct Node<D, S, const N: usize, const P: usize> {
    core: Core<D, S, P>,
    sdo: SdoServer<N>,
}

impl<D: NodeDictionary, S: ParamStore, const N: usize, const P: usize> Node<D, S, N, P> {
    /// Empty queues as constants: all-zero values the compiler clears in one go.
    const NO_FRAMES: Ring<CanFrame, TX_QUEUE> = Ring::new(CanFrame { id: 0, rtr: false, dlc: 0, data: [0; 8] });
    const NO_EVENTS: Ring<NodeEvent, EVENTS> = Ring::new(NodeEvent::ResetApplication);

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
            powered: false,
            can_enabled: false,
            restore_pending: false,
            now_us: 0,
            tx: Self::NO_FRAMES,
            events: Self::NO_EVENTS,
            tx_overflows: 0,
            emcy: if cfg.combine_emcy_codes { EmcyProducer::combining() } else { EmcyProducer::new() },
            emcy_cob: None,
            emcy_inhibit: 0,
            sync_cob: None,
            sync_period_us: 0,
            last_sync_us: NEVER,
            sync_lost: false,
            heartbeat: Producer::default(),
            consumer: Consumer::default(),
            guarding: Guarding::default(),
            guard_cob: 0,
            rpdos: Vec::new(),
            tpdos: Vec::new(),
            tpdo_mapped: 0,
            rpdo_length_error: false,
            bus: BusState::Active,
            bus_off_since: NEVER,
        };
        Node { core, sdo }
    }

    /// Power-on with the CAN side enabled at once (every device but CO401GW1): Initialisation
    /// with stored parameters, boot-up message, then Pre-operational (or Operational if the
    /// start-up object says so).
    pub fn start(&mut self, now_us: u64) {
        self.power_on(now_us);
        let mode = self.core.od.mode();
        self.enable_can(mode, now_us);
    }

    /// Power-on with the CAN side still off: the spec defaults and the stored parameters are
    /// loaded, and nothing is received or sent until [`Node::enable_can`]. Meanwhile the
    /// serial host may configure the node, and entries writable by the host only "before the
    /// CAN interface is enabled" accept its writes.
    pub fn power_on(&mut self, now_us: u64) {
        self.core.now_us = now_us;
        self.core.powered = true;
        self.core.can_enabled = false;
        self.core.load_parameters(Area::ALL);
    }

    /// Enables the CAN side in `mode` (the mode may be chosen only now, as CO401GW1's enable
    /// command does): entries whose default depends on the mode take `mode`'s default, what
    /// was written before is kept, then boot-up. Ignored before [`Node::power_on`] and once
    /// enabled (only a power-on disables the CAN side again).
    pub fn enable_can(&mut self, mode: D::Mode, now_us: u64) {
        self.core.now_us = now_us;
        if !self.core.powered || self.core.can_enabled {
            return;
        }
        if mode != self.core.od.mode() {
            self.core.od.set_mode(mode, self.core.node_id);
        }
        self.core.can_enabled = true;
        self.core.boot(now_us);
    }

    /// Whether the CAN side runs.
    pub fn can_enabled(&self) -> bool {
        self.core.can_enabled
    }

    /// A frame received from the bus.
    pub fn on_frame(&mut self, frame: &CanFrame, now_us: u64) {
        self.core.now_us = now_us;
        if !self.core.can_enabled {
            return;
        }
        let sdo_rx = crate::sdo::request_id(self.core.node_id);
        if frame.id == sdo_rx && !frame.rtr {
            if nmt::allows_sdo(self.core.state)
                && let Some(response) = self.sdo.on_request(frame.payload(), now_us, &mut self.core)
            {
                self.core.send_sdo(response);
            }
            return;
        }
        if frame.id == nmt::NMT_COB_ID {
            let Some(cs) = nmt::addressed(frame.payload(), self.core.node_id) else { return };
            self.core.event(NodeEvent::NmtReceived(cs));
            if let Some(cmd) = NmtCommand::from_code(cs) {
                if matches!(cmd, NmtCommand::ResetNode | NmtCommand::ResetCommunication | NmtCommand::Stop) {
                    self.sdo.reset(&mut self.core);
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
        if !self.core.can_enabled {
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

    /// Loads the stored parameters of `area` again over what the dictionary holds now, and
    /// reloads the services from it: for a device that writes its own defaults (a loaded
    /// configuration) after an initialisation, so that what 1010h saved still wins.
    pub fn reload_stored(&mut self, area: Area) {
        // As at an initialisation: a store that cannot be read leaves what the entries hold.
        let _ = self.core.store.load(&mut self.core.od, area);
        let now_us = self.core.now_us;
        self.core.reload_all(now_us);
    }

    pub fn od(&self) -> &D {
        &self.core.od
    }

    /// Direct access for device code; writes that should trigger TPDOs or auto-save go
    /// through [`Node::write`] (or are followed by [`Node::trigger_mapped`]).
    pub fn od_mut(&mut self) -> &mut D {
        &mut self.core.od
    }

    pub fn store(&self) -> &S {
        &self.core.store
    }

    /// A write by the device itself or its serial host, with the same side effects as an SDO
    /// download: communication-object checks, event-driven TPDOs (with `tpdo_on_write`),
    /// auto-save, and the write indication (a `Side::Bus` write is indicated as an SDO one).
    pub fn write(&mut self, index: u16, sub: u8, data: &[u8], side: Side) -> Result<(), SdoAbort> {
        self.core.write_indicated(index, sub, data, WriteSource::of_side(side))
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

    /// Whether an emergency is active (raised and not cleared, nor forgotten by a reset).
    pub fn is_active(&self, e: &EmcyDefault) -> bool {
        self.core.emcy.is_active(e)
    }

    /// How often the set of active errors changed (raise, clear, NMT reset; wrapping). A
    /// device that mirrors conditions into emergencies syncs them only when its conditions or
    /// this count moved, instead of asking [`Node::is_active`] after every input.
    pub fn error_changes(&self) -> u8 {
        self.core.emcy.changes()
    }

    /// The current error register (1001h).
    pub fn error_register(&self) -> u8 {
        self.core.emcy.register()
    }

    /// An application event for every valid TPDO that maps `index`/`sub`: what a write of
    /// the entry does by itself unless the spec says `tpdo_on_write: false`. Each such TPDO
    /// goes out as its transmission type says (event-driven: at the next poll, inhibit time
    /// permitting; acyclic synchronous: at the next SYNC).
    pub fn trigger_mapped(&mut self, index: u16, sub: u8) {
        self.core.trigger_mapped(index, sub);
    }

    /// The checked mapping of PDO `number` (1-based: RPDO1 is 1400h/1600h, TPDO1
    /// 1800h/1A00h) as the node uses it; `None` if the dictionary has no such PDO.
    pub fn pdo_mapping(&self, dir: Dir, number: u16) -> Option<&Mapping> {
        let offset = number.checked_sub(1)?;
        match dir {
            Dir::Rx => self.core.rpdos.iter().find(|r| r.offset == offset).map(|r| &r.mapping),
            Dir::Tx => self.core.tpdos.iter().find(|t| t.offset == offset).map(|t| &t.mapping),
        }
    }

    /// The values PDO `number`'s mapping maps, packed as its frame carries them: the data
    /// bytes and their count. `None` if there is no such PDO or an entry cannot be read.
    pub fn pdo_data(&mut self, dir: Dir, number: u16) -> Option<([u8; 8], u8)> {
        let mapping = *self.pdo_mapping(dir, number)?;
        mapping.pack(&mut self.core.od).ok()
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

    /// Queues any frame from device code (a manager's NMT commands, say) behind the node's
    /// own: `false` if the transmit queue was full, which counts in [`Node::tx_overflows`].
    /// Like every node frame it goes out through [`Node::poll`] only while the CAN side is
    /// enabled and not bus-off, and the boot-up (power-on, NMT reset) empties the queue.
    pub fn send_frame(&mut self, frame: CanFrame) -> bool {
        self.core.queue(Some(frame))
    }
}

impl<D: NodeDictionary, S: ParamStore, const P: usize> Core<D, S, P> {
    fn ctx(&self) -> AccessContext {
        AccessContext { nmt: self.state, can_enabled: self.can_enabled }
    }

    /// Queues a frame; `false` if it was lost (an invalid identifier, or a full queue).
    fn send(&mut self, id: u16, data: &[u8]) -> bool {
        self.queue(CanFrame::data(id, data))
    }

    /// Sends the first `len` bytes of `data` (a packed PDO).
    fn send_payload(&mut self, id: u16, data: [u8; 8], len: u8) {
        self.queue(CanFrame::from_payload(id, data, len));
    }

    fn queue(&mut self, frame: Option<CanFrame>) -> bool {
        let Some(frame) = frame else { return false };
        let queued = self.tx.push_back(frame).is_ok();
        if !queued {
            self.tx_overflows = self.tx_overflows.saturating_add(1);
        }
        queued
    }

    fn send_sdo(&mut self, payload: [u8; 8]) {
        self.send(crate::sdo::response_id(self.node_id), &payload);
    }

    fn event(&mut self, e: NodeEvent) {
        // Device code that never drains events must not stop the node: oldest go first.
        self.events.push_back_evicting(e);
    }

    fn set_state(&mut self, state: NmtState) {
        if self.state != state {
            self.state = state;
            if state != NmtState::Operational {
                for r in &mut self.rpdos {
                    r.latched = None;
                    r.deadline_us = NEVER;
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

    /// Initialisation after an NMT reset of `area`.
    fn initialise(&mut self, area: Area, now_us: u64) {
        self.load_parameters(area);
        self.boot(now_us);
    }

    /// The node-ID set for the next reset, then the spec defaults of `area` and its stored
    /// parameters.
    fn load_parameters(&mut self, area: Area) {
        if let Some(id) = self.pending_node_id.take() {
            self.node_id = id;
        }
        self.od.reset_area(area, self.node_id);
        // A store that cannot be read leaves the defaults: the node must still boot.
        let _ = self.store.load(&mut self.od, area);
        if area == Area::ALL {
            // Every entry holds its default now: a save stores what it shows again.
            self.restore_pending = false;
        }
    }

    /// The communication side starts afresh: services from the dictionary, boot-up message,
    /// Pre-operational (or Operational, as the start-up object says).
    fn boot(&mut self, now_us: u64) {
        self.emcy.reset();
        self.rpdo_length_error = false;
        self.tx.clear();
        self.guarding.reset();
        self.state = NmtState::PreOperational;
        self.reload_all(now_us);
        self.mirror_error_register(0);
        self.last_sync_us = NEVER;
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
            self.last_sync_us = now_us;
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
            if D::COMM.heartbeat_consumer
                && let [code] = frame.payload()
            {
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

    fn run_timers(&mut self, now_us: u64) {
        if self.heartbeat.due(now_us) {
            self.send(0x700 + u16::from(self.node_id), &[nmt::state_code(self.state)]);
        }
        match self.guarding.check(now_us) {
            Some(GuardEvent::LifeLost) => self.raise_event(EmcyEvent::LifeGuarding),
            Some(GuardEvent::Warning) => self.raise_event(EmcyEvent::GuardingWarning),
            None => {}
        }
        if D::COMM.heartbeat_consumer
            && let Some(ConsumerEvent::Lost(_)) = self.consumer.check(now_us)
        {
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
}
