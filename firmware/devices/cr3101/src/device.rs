//! The whole CR3101: the CANopen node over the logger, the card slot polled for insertion and
//! removal, RPDO logging (mode `logging`) or the PDO read mode (mode `pdo_read`), the
//! redundant node-ID and bit-rate pairs read at power-on, the card status objects, the
//! emergencies and the status LEDs.

use crate::app::Typed;
use crate::board::{Board, StatusLeds, bitrate_kbit};
use crate::card::files::FILES;
use crate::card::record::COMPONENTS;
use crate::logger::{CardStatus, Logger};
use crate::{Mode, Node, Od, emcy, node_config};
use coforge_stack::device::{Device, NodeAccess};
use coforge_stack::emcy::{EmcyDefault, EmcyEvent};
use coforge_stack::frame::CanFrame;
use coforge_stack::leds::Leds;
use coforge_stack::nmt::NmtState;
use coforge_stack::node::{BusState, NodeEvent, read_u32};
use coforge_stack::od::NodeDictionary;
use coforge_stack::store::ParamStore;

/// The spec's default of 20F0h/20F1h and 20F2h/20F3h.
const SPEC_NODE_ID: u8 = 0x20;
const SPEC_BITRATE: u8 = 3;
/// How often the slot is polled for a card that came or went.
const CARD_POLL_US: u64 = 100_000;
/// How long CARD ACCESS stays lit after a card write.
const ACCESS_PULSE_US: u64 = 50_000;
/// An RPDO's COB-ID is not valid (bit 31).
const COB_INVALID: u32 = 1 << 31;

/// The CR3101 on board `B`, keeping its parameters (20F0h..20F5h, the communication
/// parameters) in store `S`; its card configuration lives on the card.
pub struct Cr3101<B: Board, S: ParamStore> {
    node: Node<Typed<Logger<B::Card>>, S>,
    board: B,
    /// The node-ID the pair holds until it is written: the board's factory setting.
    factory_node_id: u8,
    /// The PDO operating mode a runtime chose over 20F5h (a simulator's `--mode`).
    forced_mode: Option<Mode>,
    mode: Mode,
    bitrate_kbit: u16,
    /// The RPDOs' identifiers (1400h..1407h sub 1), when valid: which file a frame feeds.
    rpdo_ids: [Option<u16>; FILES],
    next_card_poll_us: u64,
    /// Bit n: file n + 1's 6200h emergency is active.
    full_reported: u8,
    card_writes: u32,
    access_until_us: u64,
    leds: StatusLeds,
}

impl<B: Board, S: ParamStore> core::fmt::Debug for Cr3101<B, S> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Cr3101").field("mode", &self.mode).field("bitrate_kbit", &self.bitrate_kbit).field("leds", &self.leds).finish_non_exhaustive()
    }
}

/// 6200h for file `n` (0-based): the file number in byte 3 (erratum CR-36).
fn file_limit(n: usize) -> EmcyDefault {
    EmcyDefault { manufacturer: [n as u8 + 1, 0, 0, 0, 0], ..emcy::FILE_LIMIT_EXCEEDED }
}

impl<B: Board, S: ParamStore> Cr3101<B, S> {
    /// The device on `board`, its parameters in `store`; `factory_node_id` is what 20F0h/20F1h
    /// hold until they are written (the manual's 0x20; a simulator gives each node its own).
    pub fn new(mut board: B, store: S, factory_node_id: u8) -> Self {
        let logger = Logger::new(&board.clock_at_power_on(), 0);
        let od = Od::new(Mode::Logging, factory_node_id, Typed(logger));
        Cr3101 {
            node: Node::new(od, store, node_config(factory_node_id)),
            board,
            factory_node_id,
            forced_mode: None,
            mode: Mode::Logging,
            bitrate_kbit: 125,
            rpdo_ids: [None; FILES],
            next_card_poll_us: 0,
            full_reported: 0,
            card_writes: 0,
            access_until_us: 0,
            leds: StatusLeds::default(),
        }
    }

    pub fn node(&self) -> &Node<Typed<Logger<B::Card>>, S> {
        &self.node
    }

    pub fn node_mut(&mut self) -> &mut Node<Typed<Logger<B::Card>>, S> {
        &mut self.node
    }

    pub fn logger(&self) -> &Logger<B::Card> {
        &self.node.od().app
    }

    pub fn logger_mut(&mut self) -> &mut Logger<B::Card> {
        &mut self.node.od_mut().app
    }

    pub fn board_mut(&mut self) -> &mut B {
        &mut self.board
    }

    /// Runs in `mode` from the next power-on, as if 20F5h said so (20F5h shows it too; it is
    /// not saved).
    pub fn set_pdo_mode(&mut self, mode: Mode) {
        self.forced_mode = Some(mode);
    }

    /// The PDO operating mode chosen at power-on (20F5h).
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The CAN bit rate chosen at power-on (20F2h/20F3h), for the runtime's CAN controller.
    pub fn bitrate_kbit(&self) -> u16 {
        self.bitrate_kbit
    }

    pub fn status_leds(&self) -> StatusLeds {
        self.leds
    }

    /// A redundant pair's value at power-on: both halves agreeing on a value `valid` takes;
    /// otherwise `fallback` (erratum CR-47).
    fn pair(first: u8, second: u8, valid: impl Fn(u8) -> bool, fallback: u8) -> u8 {
        if first == second && valid(first) { first } else { fallback }
    }

    /// Power-on: the stored parameters are loaded, the node-ID and bit rate taken from their
    /// pairs and the PDO operating mode from 20F5h, then CAN starts.
    fn power_on(&mut self, now_us: u64) {
        self.load_parameters(now_us);
        let od = self.node.od();
        let node_id = Self::pair(od.node_id_setting, od.node_id_setting_shadow, |id| (1..=127).contains(&id), self.factory_node_id);
        let code = Self::pair(od.baud_rate_setting, od.baud_rate_setting_shadow, |c| bitrate_kbit(c).is_some(), SPEC_BITRATE);
        self.bitrate_kbit = bitrate_kbit(code).unwrap_or(125);
        // Mode 2 (the configurator's low-level access) is not documented: logging (CR-30).
        self.mode = if od.pdo_operating_mode == 1 { Mode::PdoRead } else { Mode::Logging };
        if node_id != self.node.node_id() {
            self.node.set_node_id(node_id);
            self.load_parameters(now_us);
        }
        self.node.enable_can(self.mode, now_us);
    }

    /// The stored parameters over the spec defaults, then what the runtime set: the factory
    /// node-ID in a pair that still holds the spec's, the mode it chose.
    fn load_parameters(&mut self, now_us: u64) {
        self.node.power_on(now_us);
        let (factory, forced) = (self.factory_node_id, self.forced_mode);
        let od = self.node.od_mut();
        if (od.node_id_setting, od.node_id_setting_shadow) == (SPEC_NODE_ID, SPEC_NODE_ID) {
            (od.node_id_setting, od.node_id_setting_shadow) = (factory, factory);
        }
        if let Some(mode) = forced {
            od.pdo_operating_mode = u8::from(mode == Mode::PdoRead);
        }
    }

    /// Reads the RPDOs' identifiers again (after anything that may have changed them).
    fn refresh_rpdo_ids(&mut self) {
        let od = self.node.od_mut();
        for (n, id) in self.rpdo_ids.iter_mut().enumerate() {
            *id = read_u32(od, 0x1400 + n as u16, 1).filter(|cob| cob & COB_INVALID == 0).map(|cob| (cob & 0x7FF) as u16);
        }
    }

    /// The file an RPDO frame of identifier `id` feeds.
    fn rpdo_file(&self, id: u16) -> Option<usize> {
        self.rpdo_ids.iter().position(|&r| r == Some(id))
    }

    /// Logging mode: RPDO n's payload, laid out as file n's relevant components (as many as
    /// fit 8 bytes), goes into file n. A payload shorter than that is not processed and gets
    /// CiA 301's EMCY 8210h, which the next whole one ends (erratum CR-49); a file that takes
    /// no value (not allocated, direct reading, no card) ignores the frame.
    fn log(&mut self, n: usize, payload: &[u8]) {
        let Ok(layout) = self.logger().file(n).map(|f| f.layout()) else { return };
        let sizes = (0..COMPONENTS).filter_map(|c| layout.component(c).map(|r| (c, r.len())));
        let carried = sizes.clone().scan(0, |end, (_, size)| {
            *end += size;
            (*end <= 8).then_some(*end)
        });
        let needed = carried.last().unwrap_or(0);
        let length_error = EmcyDefault::for_event(EmcyEvent::RpdoLength, self.node.od().emergencies());
        if payload.len() < needed {
            self.node.raise(&length_error);
            return;
        }
        self.mirror(&length_error, false);
        let logger = self.logger_mut();
        let mut at = 0;
        for (c, size) in sizes {
            let Some(value) = payload.get(at..at + size) else { break };
            at += size;
            if logger.write_component(n, c, value).is_err() {
                return;
            }
        }
        logger.end_input(n);
    }

    /// PDO read mode: RPDO1 asks for a part of a record; TPDO1 answers (erratum CR-30). A
    /// request the card cannot answer gets no answer.
    fn answer(&mut self, request: &[u8]) {
        let [file, p0, p1, p2, p3, part, ..] = *request else { return };
        let record = u32::from_le_bytes([p0, p1, p2, p3]);
        let Some(data) = self.logger_mut().read_part(usize::from(file), record, part) else { return };
        let cob = read_u32(self.node.od_mut(), 0x1800, 1).filter(|cob| cob & COB_INVALID == 0);
        if let Some(frame) = cob.and_then(|cob| CanFrame::data((cob & 0x7FF) as u16, &data)) {
            self.node.send_frame(frame);
        }
    }

    /// Polls the slot: a card that came is mounted, one that went is let go.
    fn poll_card(&mut self, now_us: u64) {
        if now_us < self.next_card_poll_us {
            return;
        }
        self.next_card_poll_us = now_us.saturating_add(CARD_POLL_US);
        let sensed = self.board.sense_card();
        let inserted = self.logger().status().inserted;
        match (sensed, inserted) {
            (Some(sense), false) => {
                if let Some(card) = self.board.take_card() {
                    let logger = self.logger_mut();
                    logger.set_now(now_us);
                    // A card without a usable volume shows as unusable until it leaves.
                    if let Err(card) = logger.insert(card, sense.write_protected) {
                        self.board.return_card(card);
                    }
                }
            }
            (None, true) => {
                if let Some(card) = self.logger_mut().remove() {
                    self.board.return_card(card);
                }
            }
            _ => {}
        }
    }

    /// Brings what mirrors the logger up to date: 2001h, 1002h, the emergencies, the LEDs.
    fn update(&mut self, now_us: u64) {
        let status = self.logger().status();
        let battery_ok = self.board.battery_ok();
        let operational = self.node.state() == NmtState::Operational;
        self.logger_mut().set_operational(operational);
        let conditions = self.logger_mut().take_conditions();
        let od = self.node.od_mut();
        let CardStatus { inserted, write_protected, capacity, unusable } = status;
        od.status_of_the_memory_card.memory_card_inserted = inserted.into();
        od.status_of_the_memory_card.write_protect_status = write_protected.into();
        od.status_of_the_memory_card.capacity_of_the_memory_card.set(capacity);
        // 1002h: bit 0 card inserted, bit 1 NOT write protected, bit 2 battery good (CR-10).
        od.state_register.set(u32::from(inserted) | u32::from(inserted && !write_protected) << 1 | u32::from(battery_ok) << 2);

        self.mirror(&emcy::LOW_BATTERY, !battery_ok);
        if conditions.no_card_access {
            self.mirror(&emcy::NO_MEMORY_CARD, true);
        } else if inserted && !unusable {
            self.mirror(&emcy::NO_MEMORY_CARD, false);
        }
        for n in 0..FILES {
            let bit = 1 << n;
            let e = file_limit(n);
            if conditions.file_wrapped & bit != 0 {
                // Ring mode goes on at record 0: an event, sent and ended at once.
                self.node.raise(&e);
                self.node.clear(&e);
            }
            let full = conditions.file_full & bit != 0;
            if full != (self.full_reported & bit != 0) {
                if full {
                    self.node.raise(&e)
                } else {
                    self.node.clear(&e)
                }
                self.full_reported ^= bit;
            }
        }

        let errors = self.logger().card_errors;
        let writes = self.logger().card_writes();
        if writes != self.card_writes {
            self.card_writes = writes;
            self.access_until_us = now_us.saturating_add(ACCESS_PULSE_US);
        }
        let leds = StatusLeds {
            card_error: unusable || errors > 0,
            card_access: now_us < self.access_until_us,
            on: true,
            error: self.node.error_register() != 0,
            can: operational,
        };
        if leds != self.leds {
            self.leds = leds;
            self.board.set_leds(leds);
        }
    }

    /// Keeps emergency `e` active exactly while `active`.
    fn mirror(&mut self, e: &EmcyDefault, active: bool) {
        match (active, self.node.is_active(e)) {
            (true, false) => self.node.raise(e),
            (false, true) => self.node.clear(e),
            _ => {}
        }
    }
}

impl<B: Board, S: ParamStore> Device for Cr3101<B, S> {
    fn start(&mut self, now_us: u64) {
        self.power_on(now_us);
        self.refresh_rpdo_ids();
        self.next_card_poll_us = 0;
        self.poll_card(now_us);
        self.update(now_us);
    }

    /// RPDO frames of the files (logging) or the read request (PDO read mode) go to the
    /// logger in operational state; everything else to the node.
    fn on_frame(&mut self, frame: &CanFrame, now_us: u64) {
        self.logger_mut().set_now(now_us);
        let operational = self.node.state() == NmtState::Operational;
        match self.rpdo_file(frame.id) {
            Some(n) if operational && !frame.rtr && self.mode == Mode::Logging => self.log(n, frame.payload()),
            Some(0) if operational && !frame.rtr => self.answer(frame.payload()),
            _ => {
                self.node.on_frame(frame, now_us);
                // An NMT command (a reset) or a write to 1400h..1407h may have moved them.
                if frame.id == 0 || core::mem::take(&mut self.logger_mut().rpdo_parameters_written) {
                    self.refresh_rpdo_ids();
                }
            }
        }
        self.update(now_us);
    }

    fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        self.poll_card(now_us);
        self.logger_mut().check(now_us);
        self.update(now_us);
        self.node.poll(now_us)
    }

    fn on_bus_state(&mut self, bus: BusState, now_us: u64) {
        self.node.on_bus_state(bus, now_us);
    }

    fn take_event(&mut self) -> Option<NodeEvent> {
        let event = self.node.take_event();
        if matches!(event, Some(NodeEvent::ResetApplication | NodeEvent::ResetCommunication)) {
            self.refresh_rpdo_ids();
        }
        event
    }

    fn leds(&self) -> Leds {
        self.node.leds()
    }

    fn node(&self) -> &dyn NodeAccess {
        &self.node
    }

    fn node_mut(&mut self) -> &mut dyn NodeAccess {
        &mut self.node
    }
}
