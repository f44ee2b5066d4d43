//! The whole chip: the CANopen node over the gateway's process image, the serial host, the
//! pins, DS401's events and error states, kept consistent after every input.
//!
//! After reset the CAN side is off: the chip sends the boot-up telegram `01 00` to the host
//! every 250 ms and lets it configure the dictionary until it enables CAN with `02 00` (or
//! `02 81`). Every input (a frame, a host byte, a poll) ends with [`Gw1::update`], which
//! reads the pins, raises and clears the pin emergencies, finds DS401 events and drives the
//! outputs; the node's events then become the host's unsolicited telegrams.

use crate::app::Typed;
use crate::board::{Board, FixedBoard, PinConfig};
use crate::ds401::{self, AnalogTrigger, DigitalMasks};
use crate::host::{Bytes, HostConfig, Request};
use crate::image::{IMAGE, IoImage};
use crate::serial::DeviceToHost;
use crate::{Mode, Node, Od, emcy, index, serial};
use coforge_link::{Deframer, Millis, Outbox};
use coforge_stack::device::{Assemble, AssembleError, Device, HostPort, MemoryRequest, NodeAccess, assembly_mode, mode_names};
use coforge_stack::frame::CanFrame;
use coforge_stack::leds::{LedState, Leds};
use coforge_stack::nmt::{NmtState, state_code};
use coforge_stack::node::{BusState, NodeEvent};
use coforge_stack::od::{EntryAccess, NodeDictionary, Side};
use coforge_stack::pdo::Dir;
use coforge_stack::store::{BlockStore, ParamStore};
use coforge_stack::time::{div_rem_u64, ms_of_us};
use coforge_stack::zerocopy::little_endian::I32;
use heapless::Deque;

/// Bytes waiting for the host: two of the longest telegrams (an emergency report is 10 bytes,
/// a PDO 10, a dictionary read of a 20-byte string 25) and some.
const HOST_OUT: usize = 64;
/// The boot-up telegram's period before CAN is enabled.
const BOOTUP_PERIOD_MS: u64 = 250;
/// The watchdog pin toggles this often while the chip runs.
const WATCHDOG_PERIOD_MS: u64 = 10;
/// Node events kept for the runtime.
const EVENTS: usize = 8;
/// Analog channels (mixed mode).
const CHANNELS: usize = 4;
/// The PDO numbers P of `3P`/`4P` (PDO P+1): 0, 1 (PDO2, mixed) and 4 (PDO5, digital only).
const PDO_SLOTS: usize = 5;

/// Before or after the host enabled CAN.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    Boot { next_bootup_ms: u64 },
    Running,
}

/// The CO401GW1 chip on board `B`, with parameter store `S` (1010h/1011h).
#[derive(Debug)]
pub struct Gw1<B, S> {
    node: Node<Typed<IoImage>, S>,
    board: B,
    pins: PinConfig,
    phase: Phase,
    host: serial::Decoder,
    host_out: Outbox<HOST_OUT>,
    config: HostConfig,
    /// The RPDO data last given to the host (`4P`), by P.
    given: [Option<Bytes>; PDO_SLOTS],
    /// The input bytes and analog inputs as the event rules last saw them.
    inputs_seen: [u8; IMAGE],
    analog_seen: [i16; CHANNELS],
    /// Each analog input at its last event (the deltas' reference).
    analog_sent: [i16; CHANNELS],
    /// Active emergency inputs: bit 0 EMY0#, bit 1 EMY1#.
    emergency_inputs: u8,
    bus_off: bool,
    /// A critical error holds the outputs in their error state.
    critical: bool,
    events: Deque<NodeEvent, EVENTS>,
    watchdog: bool,
    next_watchdog_ms: u64,
    /// The millisecond the LEDs and the watchdog pin were last driven for: once per
    /// millisecond is all a LED pattern or a 10 ms watchdog needs.
    shown_ms: u64,
    /// The time of the latest input.
    now_us: u64,
    /// Host telegrams refused: not a command, not allowed now, or refused by the dictionary
    /// (the protocol has no negative answer, so they get none).
    host_refusals: u32,
}

impl<B: Board, S: ParamStore> Gw1<B, S> {
    /// Reads the pins as the chip does at reset; [`Device::start`] powers it on.
    pub fn new(mut board: B, store: S) -> Self {
        let pins = PinConfig::read(&mut board);
        let mode = if pins.mixed { Mode::Mixed } else { Mode::Digital };
        // Until the host enables CAN the node-ID only names the $NODEID defaults; the one in
        // use is chosen at enable.
        let node_id = pins.node_id.unwrap_or(1);
        let od = Od::new(mode, node_id, Typed(IoImage::default()));
        Gw1 {
            node: Node::new(od, store, crate::node_config(node_id)),
            board,
            pins,
            phase: Phase::Boot { next_bootup_ms: 0 },
            host: serial::decoder(),
            host_out: Outbox::default(),
            config: HostConfig::default(),
            given: Default::default(),
            inputs_seen: [0; IMAGE],
            analog_seen: [0; CHANNELS],
            analog_sent: [0; CHANNELS],
            emergency_inputs: 0,
            bus_off: false,
            critical: false,
            events: Deque::new(),
            watchdog: false,
            next_watchdog_ms: 0,
            shown_ms: u64::MAX,
            now_us: 0,
            host_refusals: 0,
        }
    }

    pub fn node(&self) -> &Node<Typed<IoImage>, S> {
        &self.node
    }

    pub fn node_mut(&mut self) -> &mut Node<Typed<IoImage>, S> {
        &mut self.node
    }

    pub fn board(&self) -> &B {
        &self.board
    }

    pub fn board_mut(&mut self) -> &mut B {
        &mut self.board
    }

    pub fn pins(&self) -> PinConfig {
        self.pins
    }

    /// The time of the latest input (for a console that acts between inputs).
    pub fn now_us(&self) -> u64 {
        self.now_us
    }

    /// Host telegrams that got no answer: refused, not a command of the protocol, or cut
    /// short by a pause.
    pub fn host_errors(&self) -> u32 {
        self.host_refusals
    }

    /// Host writes before enable that will not survive an NMT reset (see [`HostConfig`]).
    pub fn host_config_overflows(&self) -> u32 {
        self.config.overflows
    }

    /// Telegrams dropped because the runtime did not take the host's output.
    pub fn host_overflows(&self) -> u32 {
        self.host_out.overflows
    }

    /// Whether the outputs are in their error state.
    pub fn in_error_state(&self) -> bool {
        self.critical
    }

    /// The node-ID enable would use: the ID pins', or 100Bh's when they are all high.
    pub fn node_id_for_enable(&self) -> Option<u8> {
        self.pins.node_id.or_else(|| Some(self.node.od().node_id).filter(|id| (1..=127).contains(id)))
    }

    /// Enables the CAN side as `02 00` (or `02 81`, `alternate`) does; `false` if the chip
    /// refuses: no valid node-ID, the alternate command in mixed mode, or already enabled.
    pub fn enable(&mut self, alternate: bool, now_us: u64) -> bool {
        if !matches!(self.phase, Phase::Boot { .. }) {
            return false;
        }
        let Some(node_id) = self.node_id_for_enable() else { return false };
        let mode = match (self.pins.mixed, alternate) {
            (true, false) => Mode::Mixed,
            (true, true) => return false,
            (false, false) => Mode::Digital,
            (false, true) => Mode::DigitalAlt,
        };
        if node_id != self.node.node_id() {
            // The $NODEID defaults follow the node-ID: power on again with it, then write
            // again what the host configured.
            self.node.set_node_id(node_id);
            self.node.power_on(now_us);
            self.after_reset();
        }
        self.phase = Phase::Running;
        self.node.enable_can(mode, now_us);
        self.after_input(now_us);
        true
    }

    /// What the pins set after every (re)load of the dictionary: 2101h, 100Bh, the image
    /// size, CFG0's default for the hardware inputs; then the host's configuration again.
    fn after_reset(&mut self) {
        let od = self.node.od_mut();
        od.system_configuration.set(self.pins.system_configuration);
        if let Some(id) = self.pins.node_id {
            od.node_id = id;
        }
        if !self.pins.hardware_inputs
            && let Some(enabled) = od.gateway_i_o_control.items.first_mut()
        {
            *enabled &= !1;
        }
        od.app.set_bytes(if self.pins.mixed { 8 } else { 16 });
        for (index, sub, data) in self.config.writes() {
            // Device side: 100Bh and 1018h.4 are the host's only before enable.
            let _ = self.node.write(index, sub, data, Side::Device);
        }
    }

    /// The periodic work: the boot-up telegram, the watchdog and the indicators.
    fn tick(&mut self, now_ms: u64) {
        if let Phase::Boot { next_bootup_ms } = self.phase
            && now_ms >= next_bootup_ms
        {
            self.phase = Phase::Boot { next_bootup_ms: now_ms.saturating_add(BOOTUP_PERIOD_MS) };
            self.send_host(&DeviceToHost::BootUp);
        }
        if now_ms >= self.next_watchdog_ms {
            self.next_watchdog_ms = now_ms.saturating_add(WATCHDOG_PERIOD_MS);
            self.watchdog = !self.watchdog;
        }
        if now_ms == self.shown_ms {
            return;
        }
        self.shown_ms = now_ms;
        let (run, error) = self.indicators(now_ms);
        self.board.set_indicators(run, error, self.watchdog);
    }

    /// The run and error LEDs `now_ms`: CiA 303-3, except that the run LED in Operational
    /// flickers off 5 % of the time (10 ms in 200 ms) to show the chip runs; both dark until
    /// CAN is enabled.
    pub fn indicators(&self, now_ms: u64) -> (bool, bool) {
        if !self.node.can_enabled() {
            return (false, false);
        }
        let Leds { run, error } = self.node.leds();
        let operational = run == LedState::On && self.node.state() == NmtState::Operational;
        let run_lit = if operational { div_rem_u64(now_ms, 200).1 >= 10 } else { run.level(now_ms) };
        (run_lit, error.level(now_ms))
    }

    /// The end of every input: pins and DS401, then the node's events.
    fn after_input(&mut self, now_us: u64) {
        self.now_us = self.now_us.max(now_us);
        self.update();
        self.take_node_events();
    }

    /// Reads the inputs and emergency pins, finds DS401 events, drives the outputs.
    pub fn update(&mut self) {
        let od = self.node.od_mut();
        if od.gateway_i_o_control.items.first().is_some_and(|e| e & 1 != 0) {
            let polarity = od.polarity_input_8_bit.items.first().copied().unwrap_or(0);
            if let Some(byte) = od.app.inputs.first_mut() {
                *byte = ds401::input_value(self.board.input_pins(), polarity);
            }
        }
        let emergency_inputs = !self.board.emergency_pins() & 0b11;
        self.emergency_inputs_changed(emergency_inputs);
        self.input_events();
        let critical = self.emergency_inputs & 1 != 0 || self.bus_off || self.node.is_active(&emcy::LIFE_GUARDING_ERROR);
        if critical && !self.critical {
            self.enter_error_state();
        }
        self.critical = critical;
        let od = self.node.od();
        let first = |a: &[u8]| a.first().copied().unwrap_or(0);
        let mut out = first(&od.app.outputs);
        if critical && od.output_reset_on_error_option == 0 {
            // 5200h = 0: only the pins show the error state, 6200h keeps its data.
            out = ds401::forced(out, first(&od.error_mode_output_8_bit.items), first(&od.error_value_output_8_bit.items));
        }
        self.board.set_output_pins(ds401::output_levels(out, first(&od.polarity_output_8_bit.items)));
    }

    /// EMY0# and EMY1#: their emergencies and 1002h bits 0 and 4.
    fn emergency_inputs_changed(&mut self, active: u8) {
        if active == self.emergency_inputs {
            return;
        }
        self.emergency_inputs = active;
        let od = self.node.od_mut();
        od.status_register.set(u32::from(active & 1) | u32::from(active & 2) << 3);
        for (bit, e) in [(1, &emcy::APPLICATION_EMERGENCY_0), (2, &emcy::APPLICATION_EMERGENCY_1)] {
            match (active & bit != 0, self.node.is_active(e)) {
                (true, false) => self.node.raise(e),
                (false, true) => self.node.clear(e),
                _ => {}
            }
        }
    }

    /// A critical error begins: with 5200h = 1 the error state is written into 6200h, with
    /// 5201h = 1 (mixed mode) the analog error values into 6411h.
    fn enter_error_state(&mut self) {
        let od = self.node.od_mut();
        if od.output_reset_on_error_option == 1 {
            let (modes, values) = (od.error_mode_output_8_bit.items, od.error_value_output_8_bit.items);
            for ((out, mode), value) in od.app.outputs.iter_mut().zip(modes).zip(values) {
                *out = ds401::forced(*out, mode, value);
            }
        }
        if od.mode() == Mode::Mixed && od.analog_output_reset_on_error_option == 1 {
            let (modes, values) = (od.error_mode_analog_output.items, od.error_value_analog_output.items);
            for ((out, mode), value) in od.write_analog_output.items.iter_mut().zip(modes).zip(values) {
                if mode != 0 {
                    out.set(ds401::analog_error_value(value.get()));
                }
            }
        }
    }

    /// DS401 events: a digital byte whose change passes its masks, an analog input whose
    /// change meets its trigger conditions, each triggers the TPDOs that map it.
    fn input_events(&mut self) {
        let running = self.node.can_enabled();
        let od = self.node.od();
        // Unchanged data is never an event (`ds401`): most inputs change no input at all.
        // Whole-array compares (word loads), not slices (a byte-wise `memcmp`).
        let bytes = u32::from(od.app.bytes());
        let in_use = u128::MAX.checked_shr(128 - 8 * bytes.min(16)).unwrap_or(0);
        let digital_same = (u128::from_le_bytes(self.inputs_seen) ^ u128::from_le_bytes(od.app.inputs)) & in_use == 0;
        let analog_same = od.mode() != Mode::Mixed || od.read_analog_input.items.map(|v| v.get()) == self.analog_seen;
        if digital_same && analog_same {
            return;
        }
        let masks = |i: usize| DigitalMasks {
            any_change: od.interrupt_mask_any_change.items.get(i).copied().unwrap_or(0),
            low_to_high: od.interrupt_mask_low_to_high.items.get(i).copied().unwrap_or(0),
            high_to_low: od.interrupt_mask_high_to_low.items.get(i).copied().unwrap_or(0),
        };
        let mut digital = 0_u16;
        for (i, (seen, &now)) in self.inputs_seen.iter_mut().zip(&od.app.inputs).enumerate().take(usize::from(od.app.bytes())) {
            if ds401::digital_event(od.global_interrupt_enable != 0, masks(i), *seen, now) {
                digital |= 1 << i;
            }
            *seen = now;
        }
        let mut analog = 0_u8;
        if od.mode() == Mode::Mixed {
            for ch in 0..CHANNELS {
                let now = od.read_analog_input.items.get(ch).map_or(0, |v| v.get());
                let get = |a: &[I32]| a.get(ch).map_or(0, |v| v.get());
                let trigger = AnalogTrigger {
                    conditions: od.analog_input_interrupt_trigger.items.get(ch).copied().unwrap_or(0),
                    upper_limit: get(&od.analog_input_upper_limit.items),
                    lower_limit: get(&od.analog_input_lower_limit.items),
                    delta: get(&od.analog_input_interrupt_delta.items),
                    negative_delta: get(&od.analog_input_negative_delta.items),
                    positive_delta: get(&od.analog_input_positive_delta.items),
                };
                let (Some(seen), Some(sent)) = (self.analog_seen.get_mut(ch), self.analog_sent.get_mut(ch)) else { continue };
                if ds401::analog_event(od.analog_input_interrupt_enable != 0, trigger, *sent, *seen, now) {
                    analog |= 1 << ch;
                    *sent = now;
                }
                *seen = now;
            }
        }
        if !running {
            return;
        }
        // Each changed byte triggers its 8-bit entry and the 16- and 32-bit views that hold
        // it, each view entry once however many of its bytes changed.
        let (mut words, mut longs) = (0_u8, 0_u8);
        for i in (0..IMAGE as u8).filter(|i| digital & 1 << i != 0) {
            self.node.trigger_mapped(index::DIGITAL_INPUT_8_BIT, i + 1);
            (words, longs) = (words | 1 << (i / 2), longs | 1 << (i / 4));
        }
        for w in (0..8_u8).filter(|w| words & 1 << w != 0) {
            self.node.trigger_mapped(index::READ_DIGITAL_INPUT_16_BIT, w + 1);
        }
        for l in (0..4_u8).filter(|l| longs & 1 << l != 0) {
            self.node.trigger_mapped(index::READ_DIGITAL_INPUT_32_BIT, l + 1);
        }
        for ch in (0..CHANNELS as u8).filter(|ch| analog & 1 << ch != 0) {
            self.node.trigger_mapped(index::READ_ANALOG_INPUT, ch + 1);
        }
    }

    /// The node's events: NMT resets re-apply the pins and the host's configuration first
    /// (the stack has reloaded the dictionary before any of its events is read, so the NMT
    /// command's report must see 2E01h as the host set it), then the rest become unsolicited
    /// telegrams as 2E01h enables them; all go on to the runtime.
    fn take_node_events(&mut self) {
        // Most inputs raise no event: nothing to gather, nothing to update again.
        let Some(first) = self.node.take_event() else { return };
        // The newest EVENTS: a ring, not a `Vec` whose `remove(0)` would link `memmove`.
        let mut events: Deque<NodeEvent, EVENTS> = Deque::new();
        let _ = events.push_back(first);
        while let Some(event) = self.node.take_event() {
            if events.is_full() {
                events.pop_front();
            }
            let _ = events.push_back(event);
        }
        if events.iter().any(|e| *e == NodeEvent::ResetApplication) {
            self.node.od_mut().app.outputs = [0; IMAGE];
        }
        let reset = events.iter().any(|e| matches!(e, NodeEvent::ResetApplication | NodeEvent::ResetCommunication));
        if reset {
            self.after_reset();
        }
        let control = self.node.od().gateway_transfer_control;
        let mut report_state = false;
        for event in events {
            match event {
                NodeEvent::StateChanged(_) | NodeEvent::NmtReceived(_) => report_state |= control.auto_send_nmt_state != 0,
                NodeEvent::RpdoReceived(p) => {
                    if control.auto_send_received_pdo_data & 1 << p.min(15) != 0 {
                        self.send_rpdo(p as u8, false);
                    }
                }
                NodeEvent::EmergencySent(frame) => {
                    if control.report_emergencies != 0 {
                        self.send_host(&emergency_report(frame));
                    }
                }
                NodeEvent::ResetApplication | NodeEvent::ResetCommunication | NodeEvent::RestartController => {}
            }
            if self.events.is_full() {
                self.events.pop_front();
            }
            let _ = self.events.push_back(event);
        }
        if report_state {
            let state = self.nmt_state_code();
            self.send_host(&DeviceToHost::NmtStateAnswer { state });
        }
        if reset {
            // The reset reloaded what the outputs and the event rules read.
            self.update();
        }
    }

    /// The state byte of `50`: 00 (boot-up) until CAN is enabled.
    fn nmt_state_code(&self) -> u8 {
        if self.node.can_enabled() { state_code(self.node.state()) } else { 0x00 }
    }

    fn send_host(&mut self, telegram: &DeviceToHost<'_>) {
        self.host_out.push_with(|out| telegram.encode(out).ok());
    }

    /// `4P` with RPDO P+1's data; unless `always`, only if it differs from what the host was
    /// last given.
    fn send_rpdo(&mut self, pdo: u8, always: bool) -> bool {
        let Some(data) = self.rpdo_data(pdo) else { return false };
        let Some(given) = self.given.get_mut(usize::from(pdo)) else { return false };
        if !always && given.as_ref() == Some(&data) {
            return true;
        }
        *given = Some(data.clone());
        self.send_host(&DeviceToHost::ReadRpdoAnswer { pdo, data: &data });
        true
    }

    /// The PDO numbers P the mode has: PDO1, and PDO2 (mixed) or PDO5 (digital only).
    fn pdo_exists(&self, pdo: u8) -> bool {
        match pdo {
            0 => true,
            1 => self.pins.mixed,
            4 => !self.pins.mixed,
            _ => false,
        }
    }

    /// The data of RPDO P+1 as its mapping lays it out, from the dictionary (dummy entries
    /// read as zero).
    fn rpdo_data(&mut self, pdo: u8) -> Option<Bytes> {
        let (data, len) = self.node.pdo_data(Dir::Rx, u16::from(pdo) + 1)?;
        Bytes::from_slice(data.get(..usize::from(len))?).ok()
    }

    /// `3P`: the host's bytes into the entries TPDO P+1 maps, as the PDO lays them out.
    /// Entries the host may not write (below 3000h, a dummy) keep their values; bytes past the
    /// mapping are ignored, a mapped entry the data does not cover is left as it is.
    fn write_tpdo(&mut self, pdo: u8, data: &[u8]) {
        let Some(mapping) = self.node.pdo_mapping(Dir::Tx, u16::from(pdo) + 1).copied() else { return };
        let entries = self.node.od().entries();
        let mut at = 0;
        for e in mapping.entries() {
            let end = at + usize::from(e.bytes());
            if let (Some(bytes), Some(info)) = (data.get(at..end), e.info(entries)) {
                let _ = self.node.write(e.index(info), e.sub, bytes, Side::Host);
            }
            at = end;
        }
    }

    /// Serves one host command; `false` if it is refused (the chip then answers nothing).
    fn serve(&mut self, request: Request, now_ms: u64) -> bool {
        let booting = matches!(self.phase, Phase::Boot { .. });
        match request {
            Request::Enable { alternate } if booting => {
                if !self.enable(alternate, now_ms.saturating_mul(1000)) {
                    return false;
                }
                self.send_host(&DeviceToHost::EnableCanAnswer);
            }
            // Enabled already: confirmed again, nothing changes.
            Request::Enable { alternate } => {
                if alternate && self.pins.mixed {
                    return false;
                }
                self.send_host(&DeviceToHost::EnableCanAnswer);
            }
            Request::WriteOd { index, sub, data } => {
                // The ID pins decide the node-ID unless they are all high.
                if index == index::NODE_ID && self.pins.node_id.is_some() {
                    return false;
                }
                if self.node.write(index, sub, &data, Side::Host).is_err() {
                    return false;
                }
                if booting {
                    self.config.record(index, sub, &data);
                }
                self.send_host(&DeviceToHost::WriteOdAnswer);
            }
            Request::ReadOd { index, sub } => {
                let mut buf = [0_u8; serial::MAX_DATA - 3];
                let Ok(read) = self.node.read(index, sub, 0, &mut buf, Side::Host) else { return false };
                let data = buf.get(..read.copied).unwrap_or(&[]);
                self.host_out.push_with(|out| DeviceToHost::ReadOdAnswer { index, sub, data }.encode(out).ok());
            }
            Request::WriteTpdo { pdo, data } => {
                if !self.pdo_exists(pdo) {
                    return false;
                }
                self.write_tpdo(pdo, &data);
                self.send_host(&DeviceToHost::WriteTpdoAnswer { pdo });
            }
            Request::ReadRpdo { pdo } => return self.pdo_exists(pdo) && self.send_rpdo(pdo, true),
            Request::NmtState => {
                let state = self.nmt_state_code();
                self.send_host(&DeviceToHost::NmtStateAnswer { state });
            }
            Request::EmergencyAck => {}
        }
        true
    }
}

/// `51` with the emergency frame's bytes.
fn emergency_report(frame: [u8; 8]) -> DeviceToHost<'static> {
    let [lo, hi, register, m0, m1, m2, m3, m4] = frame;
    DeviceToHost::EmergencyReport { error_code: u16::from_le_bytes([lo, hi]), error_register: register, manufacturer: [m0, m1, m2, m3, m4] }
}

impl<B: Board, S: ParamStore> Device for Gw1<B, S> {
    /// Power-on: the pins' settings, then the boot phase (CAN off, boot-up telegrams).
    fn start(&mut self, now_us: u64) {
        self.node.power_on(now_us);
        self.after_reset();
        self.phase = Phase::Boot { next_bootup_ms: ms_of_us(now_us) };
        self.tick(ms_of_us(now_us));
        self.after_input(now_us);
    }

    /// A frame from the bus; ignored until CAN is enabled (the node drops it).
    fn on_frame(&mut self, frame: &CanFrame, now_us: u64) {
        self.node.on_frame(frame, now_us);
        self.after_input(now_us);
    }

    fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        self.tick(ms_of_us(now_us));
        // The frame's EMCY, if it is one, is reported with the events below.
        let frame = self.node.poll(now_us);
        self.after_input(now_us);
        // The pins read just now may have queued a TPDO or an EMCY: out in this pass, not
        // the next (its events are reported by the next input).
        frame.or_else(|| self.node.poll(now_us))
    }

    fn on_bus_state(&mut self, bus: BusState, now_us: u64) {
        self.bus_off = bus == BusState::BusOff;
        self.node.on_bus_state(bus, now_us);
        self.after_input(now_us);
    }

    fn take_event(&mut self) -> Option<NodeEvent> {
        self.events.pop_front()
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

/// The UART: one telegram in, at most one answer out; refused telegrams get none.
impl<B: Board, S: ParamStore> HostPort for Gw1<B, S> {
    fn on_host_byte(&mut self, byte: u8, now_ms: u64) {
        // The framing compares wrapping differences of a 32-bit millisecond clock.
        let request = match self.host.push(byte, now_ms as Millis) {
            None => return,
            Some(Ok(frame)) => Request::parse(&frame),
            Some(Err(_)) => None,
        };
        let served = request.is_some_and(|r| self.serve(r, now_ms));
        if !served {
            self.host_refusals = self.host_refusals.wrapping_add(1);
        }
        self.after_input(now_ms.saturating_mul(1000));
    }

    fn host_output(&mut self, now_ms: u64, out: &mut [u8]) -> usize {
        self.tick(now_ms);
        self.host_out.take(out)
    }
}

/// The chip on a [`FixedBoard`] whose ID pins give `node_id` (0: all high, the host sets
/// 100Bh) and whose CFG1 gives the mode (mixed: high; the digital modes: low, the host's
/// enable command then chooses between them), with a parameter store from the runtime.
impl<M: embedded_storage::Storage> Assemble<M> for Gw1<FixedBoard, BlockStore<M>> {
    fn mode_names(f: &mut dyn FnMut(&'static str)) {
        mode_names::<Od<Typed<IoImage>>>(f);
    }

    fn assemble(mode: Option<&str>, node_id: u8, memory: &mut dyn FnMut(MemoryRequest) -> Option<M>) -> Result<Self, AssembleError> {
        // Node-ID 0 is the programmable one: every other must be valid.
        let mode = if node_id == 0 { assembly_mode::<Od<Typed<IoImage>>>(mode, 1)? } else { assembly_mode::<Od<Typed<IoImage>>>(mode, node_id)? };
        let size = <Od<Typed<IoImage>> as NodeDictionary>::PERSISTENT_SIZE;
        let request = MemoryRequest { name: "parameters", capacity: BlockStore::<M>::capacity_for(size) };
        let storage = memory(request).ok_or(AssembleError::NoMemory(request.name))?;
        Ok(Gw1::new(FixedBoard::new(node_id, mode == Mode::Mixed), BlockStore::new(storage, 0)))
    }
}
