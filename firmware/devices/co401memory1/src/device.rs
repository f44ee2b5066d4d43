//! The whole module: the CANopen node over the memory objects, the serial host, the CAN
//! monitoring channel and the supply guard, kept consistent after every input.

use crate::app::Typed;
use crate::board::{Board, Config, ConfigError, FixedBoard, StatusOutputs};
use crate::memory::BANK_SIZE;
use crate::memory::MemoryApp;
use crate::monitor::{Monitor, monitored_id};
use crate::supply::Supply;
use crate::{Mode, Node, Od, emcy, node_config, serial};
use coforge_link::{Deframer, Millis, Outbox};
use coforge_stack::device::{Assemble, AssembleError, Device, HostPort, MemoryRequest, NodeAccess, assembly_mode, mode_names};
use coforge_stack::frame::CanFrame;
use coforge_stack::leds::Leds;
use coforge_stack::nmt::NmtState;
use coforge_stack::node::{BusState, NodeEvent};
use coforge_stack::store::NoStore;
use coforge_storage::BankStatus;
use embedded_storage::Storage;
use heapless::Deque;

/// How often the background scrub checks one block (64 blocks: a full pass in 64 s).
const SCRUB_PERIOD_US: u64 = 1_000_000;
/// Frames the serial host asked to transmit that wait for the bus.
const RAW_TX: usize = 4;
/// Answer bytes waiting for the host: the longest answer (11 bytes) and some.
const HOST_OUT: usize = 24;

/// The CO401Memory1 module on banks of type `S` and board `B`.
#[derive(Debug)]
pub struct Memory1<S, B> {
    pub(crate) node: Node<Typed<MemoryApp<S>>, NoStore>,
    pub(crate) board: B,
    config: Config,
    host: serial::Decoder,
    pub(crate) host_out: Outbox<HOST_OUT>,
    pub(crate) monitor: Monitor,
    pub(crate) supply: Supply,
    pub(crate) raw_tx: Deque<CanFrame, RAW_TX>,
    pub(crate) bus_off: bool,
    /// The bank status last reported (EMCY, TPDO1, outputs).
    reported: [BankStatus; 2],
    outputs: StatusOutputs,
    /// The conditions last mirrored into emergencies, and the node's error-change count right
    /// after: nothing to do while both stay the same.
    emcy_synced: Option<([bool; 4], u8)>,
    /// When `poll` samples the supply next.
    next_sample_us: u64,
    next_scrub_us: u64,
    /// Serial frames that were not a command of the protocol.
    pub(crate) host_rejects: u32,
}

impl<S: Storage, B: Board> Memory1<S, B> {
    /// Reads the configuration pins and mounts the banks (repairing what a power cut left).
    pub fn new(banks: [S; 2], mut board: B) -> Result<Self, ConfigError> {
        let config = Config::read(&mut board)?;
        let od = Od::new(Mode::Default, config.node_id, Typed(MemoryApp::new(banks)));
        Ok(Memory1 {
            node: Node::new(od, NoStore, node_config(config.node_id)),
            board,
            config,
            host: serial::decoder(),
            host_out: Outbox::default(),
            monitor: Monitor::default(),
            supply: Supply::Normal,
            raw_tx: Deque::new(),
            bus_off: false,
            reported: [BankStatus::default(); 2],
            outputs: StatusOutputs::default(),
            emcy_synced: None,
            next_sample_us: 0,
            next_scrub_us: SCRUB_PERIOD_US,
            host_rejects: 0,
        })
    }

    /// Serial frames dropped: cut short by a pause, or not a command of the protocol.
    pub fn host_errors(&self) -> u32 {
        self.host_rejects.wrapping_add(self.host.truncated)
    }

    pub fn config(&self) -> Config {
        self.config
    }

    pub fn outputs(&self) -> StatusOutputs {
        self.outputs
    }

    pub fn state(&self) -> NmtState {
        self.node.state()
    }

    /// Answers that could not wait for the host (it never took the earlier ones).
    pub fn host_overflows(&self) -> u32 {
        self.host_out.overflows
    }

    pub fn node(&self) -> &Node<Typed<MemoryApp<S>>, NoStore> {
        &self.node
    }

    pub fn node_mut(&mut self) -> &mut Node<Typed<MemoryApp<S>>, NoStore> {
        &mut self.node
    }

    pub fn board_mut(&mut self) -> &mut B {
        &mut self.board
    }

    /// Reads the supply: 5F00h and the write guard.
    fn sample_supply(&mut self) {
        let mv = self.board.supply_mv();
        self.supply = self.supply.next(mv);
        let od = self.node.od_mut();
        od.app.set_writes_allowed(self.supply.writes_allowed());
        od.supply_voltage_monitor.set(mv);
    }

    /// Brings everything derived from the banks, the supply state last sampled and the monitor
    /// up to date: 2101h, 2105h, the emergencies, TPDO1 and the status outputs. The
    /// emergencies follow the conditions, so an NMT reset that forgets them raises them again.
    /// Every input samples the supply before it acts (a write must see the supply of its
    /// moment) and updates after.
    fn update(&mut self, force: bool) {
        let od = self.node.od_mut();
        od.system_configuration.set(self.config.system_configuration);
        let status = [od.app.status(0), od.app.status(1)];
        let [bank1, bank2] = status;
        let active = [bank1.is_error(), bank2.is_error(), self.supply >= Supply::Low, self.supply >= Supply::Critical];
        // An NMT reset forgets the emergencies and changes the count: they are raised again.
        if self.emcy_synced != Some((active, self.node.error_changes())) {
            let emergencies = [&emcy::MEMORY_BANK1_ERROR, &emcy::MEMORY_BANK2_ERROR, &emcy::VOLTAGE_LOW, &emcy::VOLTAGE_LOW_CRITICAL];
            for (e, active) in emergencies.into_iter().zip(active) {
                match (active, self.node.is_active(e)) {
                    (true, false) => self.node.raise(e),
                    (false, true) => self.node.clear(e),
                    _ => {}
                }
            }
            self.emcy_synced = Some((active, self.node.error_changes()));
        }
        if status != self.reported || force {
            self.reported = status;
            self.node.trigger_tpdo(1);
        }
        let outputs = StatusOutputs {
            mem1_error: bank1.is_error(),
            mem2_error: bank2.is_error(),
            new_can_data: self.monitor.is_fresh(),
            voltage_low: self.supply != Supply::Normal,
        };
        self.node.od_mut().api_state_register = outputs.register();
        if outputs != self.outputs || force {
            self.outputs = outputs;
            self.board.set_outputs(outputs);
        }
    }
}

impl<S: Storage, B: Board> Device for Memory1<S, B> {
    /// Power-on: boot-up message, then pre-operational.
    fn start(&mut self, now_us: u64) {
        self.node.start(now_us);
        self.sample_supply();
        self.update(true);
    }

    /// A frame from the bus. Frames on the monitored identifier go to the monitoring channel.
    fn on_frame(&mut self, frame: &CanFrame, now_us: u64) {
        // The frame may write the memory: the guard must know the supply of this moment.
        self.sample_supply();
        let monitored = monitored_id(self.node.od().rpdo2_comm.cob_id_used_by_rpdo.get());
        if monitored == Some(frame.id) && !frame.rtr {
            self.monitor.capture(frame.payload());
            let od = self.node.od_mut();
            od.can_monitoring_byte.items = [0; 8];
            for (dst, &b) in od.can_monitoring_byte.items.iter_mut().zip(frame.payload()) {
                *dst = b;
            }
        } else {
            self.node.on_frame(frame, now_us);
        }
        self.update(false);
    }

    /// Runs the timers, the supply guard and the scrub; returns the next frame to send.
    fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        let scrub = now_us >= self.next_scrub_us;
        if scrub {
            self.next_scrub_us = now_us.saturating_add(SCRUB_PERIOD_US);
            // A lost block shows in the bank status, which the update below reports.
            let _ = self.node.od_mut().app.banks_mut().scrub_next();
        }
        // Every other input updates after itself; here only the supply can have moved, and
        // sampling it once a millisecond is plenty (it falls over milliseconds, not cycles).
        // (No division: a 64-bit one costs a Cortex-M0 1 KiB of flash.)
        if scrub || now_us >= self.next_sample_us {
            self.next_sample_us = now_us.saturating_add(1000);
            self.sample_supply();
            self.update(false);
        }
        if !self.bus_off
            && let Some(frame) = self.raw_tx.pop_front()
        {
            return Some(frame);
        }
        self.node.poll(now_us)
    }

    /// The CAN controller's error state changed.
    fn on_bus_state(&mut self, bus: BusState, now_us: u64) {
        self.bus_off = bus == BusState::BusOff;
        self.node.on_bus_state(bus, now_us);
        self.sample_supply();
        self.update(false);
    }

    fn take_event(&mut self) -> Option<NodeEvent> {
        self.node.take_event()
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

    fn host_port(&mut self) -> Option<&mut dyn HostPort> {
        Some(self)
    }
}

/// The RS232 host interface: one answer per command, queued until the runtime sends it.
impl<S: Storage, B: Board> HostPort for Memory1<S, B> {
    fn on_host_byte(&mut self, byte: u8, now_ms: u64) {
        // The framing compares wrapping differences of a 32-bit millisecond clock.
        let now_ms = now_ms as Millis;
        let (code, len) = match self.host.push(byte, now_ms) {
            None => return,
            Some(Err(_)) => {
                self.host_rejects = self.host_rejects.wrapping_add(1);
                return;
            }
            Some(Ok(frame)) => (frame.code, frame.data.len()),
        };
        // The data is copied out of the decoder (the answer needs the whole module), and only
        // once a frame is complete.
        let data = *self.host.buffer();
        let frame = coforge_link::Frame { code, length_code: None, network: None, data: data.get(..len).unwrap_or(&[]) };
        self.sample_supply();
        self.answer(&frame);
        self.update(false);
    }

    fn host_output(&mut self, _now_ms: u64, out: &mut [u8]) -> usize {
        self.host_out.take(out)
    }
}

/// The module on a [`FixedBoard`] whose pins give `node_id`, with its two banks from the
/// runtime (the simulator's EEPROM images).
impl<S: Storage> Assemble<S> for Memory1<S, FixedBoard> {
    fn mode_names(f: &mut dyn FnMut(&'static str)) {
        mode_names::<Od<Typed<MemoryApp<S>>>>(f);
    }

    fn assemble(mode: Option<&str>, node_id: u8, memory: &mut dyn FnMut(MemoryRequest) -> Option<S>) -> Result<Self, AssembleError> {
        // The module has one mode; its node-ID comes from the pins the board sets.
        assembly_mode::<Od<Typed<MemoryApp<S>>>>(mode, node_id)?;
        let mut bank = |name| memory(MemoryRequest { name, capacity: BANK_SIZE }).ok_or(AssembleError::NoMemory(name));
        let banks = [bank("bank1")?, bank("bank2")?];
        Memory1::new(banks, FixedBoard::new(node_id)).map_err(|_| AssembleError::Config("reserved configuration pins"))
    }
}
