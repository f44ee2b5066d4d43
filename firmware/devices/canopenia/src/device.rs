//! The coprocessor: the CANopen node, the manager beside it, and the remote-access engine
//! between them and the host (manual chapters 6 and 7).
//!
//! - **Commands** W and R read and write the local dictionary with the host's access rules
//!   and the side effects of an SDO write (an event TPDO, a reloaded service). S and U go to
//!   another node through the manager's SDO client, one at a time: a second one while one
//!   runs is answered at once with the busy bit, W and R are served meanwhile, and the answer
//!   comes when the transfer ends. U with 5F01h.04 bit 4 set answers a scanned entry from the
//!   cache, at once. S and U addressed to the coprocessor's own node-ID are served from its
//!   dictionary with the bus's access rules, as the SDO server would.
//! - **Every accepted command gets exactly one answer**, in the form of its start byte
//!   (network, CRC or none, 8- or 16-bit length). A command is accepted when its answer fits
//!   the output queue (besides the answer a running S or U is owed); otherwise it is refused,
//!   and counted, like a frame with a bad CRC or a letter the protocol does not have.
//! - **Indications D**: every local entry written from the bus (an SDO download; an RPDO, one
//!   D per mapped entry); with 5F01h.04 bit 2 every TPDO of a scanned node, split by its
//!   scanned mapping; the coprocessor's own node-ID, NMT state and hardware state (5F00h.01..03)
//!   when they change; and every status the manager records of a node (5F04h, sub-index =
//!   node-ID). An indication never takes the room an owed answer needs: it is dropped and
//!   counted instead. Indications use the start byte of the host's latest command (11h first).
//! - **The manager's command entries**: 5F0Ah.1 sends an NMT master message, 5F01h.1 resets
//!   the coprocessor (129: reset application, 130: reset communication), 5F01h.0Ah scans a
//!   node again.
//! - **Manager control** (5F01h.04, applied after every input): KEEP_OP starts a node whose
//!   scan completed or whose heartbeat reports stopped or pre-operational; HB receive all
//!   writes 5F01h.05 into scanned nodes' 1017h, monitors every node with 5F01h.06 and resets
//!   a node whose heartbeat is lost; PDO receive all and use scanned entries as above; RPDO
//!   transmit all sends S of an entry a scanned node maps into an RPDO as that PDO
//!   ([`crate::rpdo_transmit`]), answered at once.
//! - **AUTORUN** (the pin, read at power-on) or a loaded file's autostart: the coprocessor
//!   starts itself, after power-on and after every reset.
//! - **Configuration loading** ([`crate::config`]): the activation sequence puts the
//!   coprocessor into bootloader mode as node 70h (its manager and autostart off); 1F51h.1 = 1
//!   starts the application again, confirmed by an error-reset emergency from node 70h (as the
//!   manual's trace shows, erratum COIA-52). The active file sets the node-ID, whether the
//!   manager runs (FUNC bit 3), autostart (bit 1) and the NMT start of every node (bit 2), and
//!   its values are written after every initialisation, before what 1010h saved.

use crate::app::Typed;
use crate::config::program::{ProgramRequest, checked_active};
use crate::config::slots::{ConfigMemory, NoMemory};
use crate::config::{Settings, apply};
use crate::errors;
use crate::host::{self, Command, MAX_VALUE, Request};
use crate::objects::{Coprocessor, Written};
use crate::rpdo_transmit::{self, RpdoTransmit};
use crate::serial::{self, DeviceToHost};
use crate::{Mode, Node, Od, cache, index, status};
use coforge_link::start_crc::reencode;
use coforge_link::{Deframer, Millis, Outbox};
use coforge_stack::device::{Assemble, AssembleError, Device, HostPort, MemoryRequest, NodeAccess, assembly_mode, mode_names};
use coforge_stack::frame::CanFrame;
use coforge_stack::leds::Leds;
use coforge_stack::manager::monitor::{MonitorEvent, NodeState};
use coforge_stack::manager::scan::{MAX_MAPPED, ScanConfig, ScanEvent};
use coforge_stack::manager::{Manager, ManagerEvent, nmt_frame};
use coforge_stack::nmt::{NmtCommand, state_code};
use coforge_stack::node::{BusState, NodeEvent};
use coforge_stack::od::{Area, EntryAccess, NodeDictionary, Side};
use coforge_stack::sdo::client::{SdoResult, StartError};
use coforge_stack::store::{BlockStore, ParamStore};
use heapless::Deque;

/// Scans the manager keeps (node records, each with this many PDOs each way).
pub const SCANS: usize = 8;
pub const SCAN_PDOS: usize = 4;
/// The longest frame the device sends: start byte, 16-bit length, 35 payload bytes, CRC.
const MAX_FRAME: usize = 1 + 2 + 35 + 2;
/// The host's output queue: an owed answer, a running S or U's answer, indications.
const OUT: usize = 6 * MAX_FRAME;
/// Node events kept for the runtime.
const EVENTS: usize = 8;
/// 5F01h.04 bits (manual section 9.2).
const KEEP_OP: u32 = 1 << 0;
const HB_RECEIVE_ALL: u32 = 1 << 1;
const PDO_RECEIVE_ALL: u32 = 1 << 2;
const RPDO_TRANSMIT_ALL: u32 = 1 << 3;
const USE_SCANNED: u32 = 1 << 4;
/// 5F00h.03 bits this firmware can see: INIT, ERPA, TXOR, BOFF.
const HW_INIT: u8 = 1 << 0;
const HW_ERROR_PASSIVE: u8 = 1 << 2;
const HW_TX_OVERRUN: u8 = 1 << 4;
const HW_BUS_OFF: u8 = 1 << 7;
/// The node-ID of bootloader mode (manual section 4.2).
pub const BOOTLOADER_NODE_ID: u8 = 0x70;

/// The remote operation the SDO client runs for the host, and its command's start byte.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Remote {
    read: bool,
    node: u8,
    index: u16,
    sub: u8,
    start: u8,
}

/// The CANopenIA coprocessor with parameter store `S` (1010h/1011h) and configuration memory
/// `M` (two binary EDS slots; [`NoMemory`]: none, files cannot be loaded).
#[derive(Debug)]
pub struct Canopenia<S, M = NoMemory> {
    node: Node<Typed<Coprocessor<M>>, S>,
    manager: Manager<SCANS, SCAN_PDOS>,
    host: serial::Decoder,
    out: Outbox<OUT>,
    remote: Option<Remote>,
    /// With 5F01h.04 bit 3: host writes collected into scanned nodes' RPDOs.
    rpdos: RpdoTransmit,
    /// The manager's caller buffer: the value S writes, where U's value lands.
    sdo_buf: [u8; MAX_VALUE],
    /// The start byte of indications: the host's latest command's.
    start: u8,
    /// 5F00h.01..03 as the host was last told.
    shown: [u8; 3],
    /// 5F00h.03: what has happened since power-on.
    hardware: u8,
    events: Deque<NodeEvent, EVENTS>,
    /// The AUTORUN pin: start operational without a master.
    autorun: bool,
    /// The node-ID the runtime gives (pins, board): used when no file sets one.
    hardware_node_id: u8,
    /// The chip's serial number (1018h.4, the activation key of section 4.2), if the runtime
    /// gives one; otherwise 1018h.4 keeps the spec's default.
    serial_number: Option<u32>,
    /// What the active configuration file sets besides dictionary values.
    settings: Settings,
    /// A change of program 1F50h/1F51h asked for, carried out once the node's answer left
    /// (a reset empties the transmit queue).
    program_change: Option<ProgramRequest>,
    /// The time of the latest input.
    now_us: u64,
    /// The heartbeat times the manager was last given (5F01h.05/.06, or 0 with HB receive all
    /// off).
    heartbeat_ms: (u16, u16),
    /// Host frames that got no answer: a bad start byte, CRC or length, a letter the
    /// protocol does not have, or no room for the answer.
    pub host_refusals: u32,
    /// Indications not sent: no room, or a value longer than an indication carries.
    pub indications_dropped: u32,
    /// Values of the active file the dictionary refused when they were applied (none for a
    /// file that passed the check; counted, not expected).
    pub config_write_errors: u32,
}

impl<S: ParamStore> Canopenia<S, NoMemory> {
    /// A coprocessor without configuration memory: it runs the firmware's own dictionary.
    pub fn new(node_id: u8, store: S) -> Self {
        Canopenia::with_configuration(node_id, store, NoMemory)
    }
}

impl<S: ParamStore, M: ConfigMemory> Canopenia<S, M> {
    /// A coprocessor whose configuration files live in `memory` (at least
    /// [`ConfigSlots::CAPACITY`](crate::config::slots::ConfigSlots::CAPACITY) bytes); the
    /// active file's node-ID, if it sets one, replaces `node_id`.
    pub fn with_configuration(node_id: u8, store: S, memory: M) -> Self {
        let app = Coprocessor::new(memory);
        let settings = settings_of(&app);
        let own_id = settings.node_id.unwrap_or(node_id);
        let od = Od::new(Mode::Default, own_id, Typed(app));
        Canopenia {
            node: Node::new(od, store, crate::node_config(own_id)),
            manager: Manager::new(ScanConfig { pdos: SCAN_PDOS as u8, heartbeat_ms: None }),
            host: serial::decoder(),
            out: Outbox::default(),
            remote: None,
            rpdos: RpdoTransmit::default(),
            sdo_buf: [0; MAX_VALUE],
            start: serial::FRAMING.start_byte,
            shown: [0; 3],
            hardware: 0,
            events: Deque::new(),
            autorun: false,
            hardware_node_id: node_id,
            serial_number: None,
            settings,
            program_change: None,
            now_us: 0,
            // No times given yet: the first input gives them.
            heartbeat_ms: (u16::MAX, u16::MAX),
            host_refusals: 0,
            indications_dropped: 0,
            config_write_errors: 0,
        }
    }

    /// What the active configuration sets (the firmware's own settings without one).
    pub fn settings(&self) -> Settings {
        self.settings
    }

    /// Whether the coprocessor is in bootloader mode.
    pub fn in_bootloader(&self) -> bool {
        self.node.od().app.program.in_bootloader()
    }

    /// The manager runs in the application, unless the active file turns it off.
    fn manager_runs(&self) -> bool {
        self.settings.manager && !self.in_bootloader()
    }

    /// AUTORUN or the file's autostart; never in bootloader mode.
    fn autostart(&self) -> bool {
        (self.autorun || self.settings.autostart) && !self.in_bootloader()
    }

    /// After power-on or a reset: the coprocessor starts itself, and as boot-up manager starts
    /// every node.
    fn after_boot(&mut self, now_us: u64) {
        if self.autostart() {
            self.own_nmt(NmtCommand::Start, now_us);
        }
        if self.settings.nmt_master && self.manager_runs() {
            self.manager.nmt(NmtCommand::Start, 0);
        }
    }

    /// The active file's values for `area`, then what 1010h saved over them. The files are
    /// lent out of the dictionary's app part while their values are written into it.
    fn apply_configuration(&mut self, area: Area) {
        if self.in_bootloader() {
            return;
        }
        let Some(slots) = self.node.od_mut().app.program.lend() else { return };
        let entries = crate::od::entries(Mode::Default);
        let node_id = self.node.node_id();
        let mut failed = 0_u32;
        if let Some(file) = checked_active(&slots, entries) {
            // Straight into the dictionary (lengths and limits checked): the services are
            // reloaded from it once, after all of them, not after each.
            let od = self.node.od_mut();
            failed = apply::apply(&file, entries, area, node_id, &mut |index, sub, data| {
                od.entry(index, sub).and_then(|info| od.write_entry(info, index, sub, data)).is_ok()
            });
            self.node.reload_stored(area);
        }
        self.node.od_mut().app.program.give_back(slots);
        self.config_write_errors = self.config_write_errors.saturating_add(failed);
    }

    /// 1F50h/1F51h asked for another program and the node's frames have left: the
    /// coprocessor resets into it.
    fn change_program(&mut self, request: ProgramRequest, now_us: u64) {
        match request {
            ProgramRequest::EnterBootloader => {
                self.node.od_mut().app.program.entered(true);
                self.node.set_node_id(BOOTLOADER_NODE_ID);
            }
            ProgramRequest::StartApplication => {
                // The bootloader confirms the start with an error-reset emergency (section
                // 4.2's trace), from its own node-ID; the reset waits until it has left.
                if let Some(frame) = CanFrame::data(0x80 + u16::from(self.node.node_id()), &[0; 8]) {
                    self.node.send_frame(frame);
                }
                self.node.od_mut().app.program.entered(false);
                self.settings = settings_of(&self.node.od().app);
                self.node.set_node_id(self.settings.node_id.unwrap_or(self.hardware_node_id));
                self.program_change = Some(ProgramRequest::Restart);
                return;
            }
            ProgramRequest::Restart => {}
        }
        self.own_nmt(NmtCommand::ResetNode, now_us);
    }

    /// The chip's unique serial number, shown in 1018h.4 from the next initialisation on (a
    /// loaded file does not change it).
    pub fn set_serial_number(&mut self, serial: u32) {
        self.serial_number = Some(serial);
    }

    /// The AUTORUN pin; read at power-on and at every reset of the coprocessor.
    pub fn set_autorun(&mut self, high: bool) {
        self.autorun = high;
    }

    pub fn node(&self) -> &Node<Typed<Coprocessor<M>>, S> {
        &self.node
    }

    pub fn node_mut(&mut self) -> &mut Node<Typed<Coprocessor<M>>, S> {
        &mut self.node
    }

    pub fn manager(&self) -> &Manager<SCANS, SCAN_PDOS> {
        &self.manager
    }

    pub fn manager_mut(&mut self) -> &mut Manager<SCANS, SCAN_PDOS> {
        &mut self.manager
    }

    fn manager_control(&self) -> u32 {
        self.node.od().device_control.manager_control.get()
    }

    /// Room an answer owed to a running S or U keeps in the output queue.
    fn reserved(&self) -> usize {
        if self.remote.is_some() { MAX_FRAME } else { 0 }
    }

    /// Queues `message` with the options of start byte `start`; `false` if it does not fit.
    fn push(&mut self, message: &DeviceToHost<'_>, start: u8) -> bool {
        let mut frame = [0_u8; MAX_FRAME];
        let Ok(n) = message.encode(&mut frame) else { return false };
        let frame = frame.get(..n).unwrap_or(&[]);
        if start == serial::FRAMING.start_byte {
            // Already in its form: copied, not encoded again.
            return self.out.push_with(|out| out.get_mut(..n).map(|dst| dst.copy_from_slice(frame)).map(|()| n));
        }
        self.out.push_with(|out| reencode(&serial::FRAMING, frame, start, out).ok())
    }

    /// An answer: the room for it was kept when its command was accepted.
    fn answer(&mut self, request: &Request, err: u16, data: &[u8], start: u8) {
        let data = if err == 0 { data } else { &[] };
        let message = match *request {
            Request::WriteLocal { index, sub, .. } => DeviceToHost::WriteLocalResponse { index, sub, err },
            Request::ReadLocal { index, sub } => DeviceToHost::ReadLocalResponse { index, sub, err, data },
            Request::WriteRemote { node, index, sub, .. } => DeviceToHost::WriteRemoteResponse { node_id: node, index, sub, err },
            Request::ReadRemote { node, index, sub } => DeviceToHost::ReadRemoteResponse { node_id: node, index, sub, err, data },
        };
        self.push(&message, start);
    }

    /// An indication, if it leaves room for the answers that may be owed.
    fn indicate(&mut self, node_id: u8, index: u16, sub: u8, data: &[u8]) {
        let fits = data.len() <= MAX_VALUE && self.out.free() >= 1 + 2 + 5 + data.len() + 2 + MAX_FRAME + self.reserved();
        if !(fits && self.push(&DeviceToHost::NewDataIndication { node_id, index, sub, data }, self.start)) {
            self.indications_dropped = self.indications_dropped.saturating_add(1);
        }
    }

    /// Serves one accepted command.
    fn serve(&mut self, command: Command, start: u8) {
        let request = match command {
            Command::Refuse { request, err } => return self.answer(&request, err, &[], start),
            Command::Serve(request) => request,
        };
        match request {
            Request::WriteLocal { index, sub, ref data } => {
                let err = self.node.write(index, sub, data, Side::Host).err().map_or(0, errors::of_abort);
                self.answer(&request, err, &[], start);
            }
            Request::ReadLocal { index, sub } => self.read_local(&request, index, sub, Side::Host, start),
            Request::WriteRemote { node, .. } | Request::ReadRemote { node, .. } if node == self.node.node_id() => self.serve_own(&request, start),
            Request::WriteRemote { node, index, sub, ref data } => {
                match self.write_into_rpdo(node, index, sub, data) {
                    Some(Ok(())) => return self.answer(&request, 0, &[], start),
                    Some(Err(rpdo_transmit::Refusal::Length)) => return self.answer(&request, serial::errors::INVALID_COMMAND_LENGTH, &[], start),
                    None => {}
                }
                if let Some(err) = self.remote_refusal(node) {
                    return self.answer(&request, err, &[], start);
                }
                let len = data.len();
                self.sdo_buf.iter_mut().zip(data).for_each(|(d, s)| *d = *s);
                let started = self.manager.download(node, index, sub, len);
                self.start_remote(&request, started, Remote { read: false, node, index, sub, start });
            }
            Request::ReadRemote { node, index, sub } => {
                if let Some(err) = self.remote_refusal(node) {
                    return self.answer(&request, err, &[], start);
                }
                let cached =
                    (self.manager_control() & USE_SCANNED != 0).then(|| self.manager.scanned(node).and_then(|s| cache::value(s, index, sub))).flatten();
                if let Some((bytes, len)) = cached {
                    return self.answer(&request, 0, bytes.get(..len).unwrap_or(&[]), start);
                }
                let started = self.manager.upload(node, index, sub);
                self.start_remote(&request, started, Remote { read: true, node, index, sub, start });
            }
        }
    }

    /// With RPDO transmit all: S of an entry a scanned RPDO of `node` maps goes into that PDO
    /// (`None`: it is not one, an SDO download is the way).
    fn write_into_rpdo(&mut self, node: u8, index: u16, sub: u8, data: &[u8]) -> Option<Result<(), rpdo_transmit::Refusal>> {
        if self.manager_control() & RPDO_TRANSMIT_ALL == 0 || !self.manager_runs() {
            return None;
        }
        let times = self.pdo_times();
        let scan = self.manager.scanned(node)?;
        match self.rpdos.on_host_write(scan, index, sub, data, times, self.now_us) {
            Ok(true) => Some(Ok(())),
            Ok(false) => None,
            Err(refusal) => Some(Err(refusal)),
        }
    }

    /// The manager's default PDO times, 5F01h.07..09.
    fn pdo_times(&self) -> rpdo_transmit::Times {
        let c = &self.node.od().device_control;
        rpdo_transmit::Times {
            update_ms: c.default_pdo_update_time,
            event_ms: c.default_pdo_transmission_event_time.get(),
            inhibit_100us: c.default_pdo_transmission_inhibit_time.get(),
        }
    }

    /// R, or S/U addressed to the coprocessor itself (with the bus's rules).
    fn read_local(&mut self, request: &Request, index: u16, sub: u8, side: Side, start: u8) {
        let mut buf = [0_u8; MAX_VALUE];
        let (err, len) = match self.node.read(index, sub, 0, &mut buf, side) {
            Ok(read) if read.total > MAX_VALUE => (serial::errors::RECEIVE_BUFFER_TOO_SMALL, 0),
            Ok(read) => (0, read.copied),
            Err(abort) => (errors::of_abort(abort), 0),
        };
        self.answer(request, err, buf.get(..len).unwrap_or(&[]), start);
    }

    fn serve_own(&mut self, request: &Request, start: u8) {
        match *request {
            Request::WriteRemote { index, sub, ref data, .. } => {
                let err = self.node.write(index, sub, data, Side::Bus).err().map_or(0, errors::of_abort);
                self.answer(request, err, &[], start);
            }
            Request::ReadRemote { index, sub, .. } => self.read_local(request, index, sub, Side::Bus, start),
            _ => {}
        }
    }

    /// Why S or U to `node` cannot start now.
    fn remote_refusal(&self, node: u8) -> Option<u16> {
        if !self.manager_runs() {
            // Bootloader mode, or a file without the CANopen manager.
            Some(serial::errors::NOT_SUPPORTED)
        } else if self.remote.is_some() {
            Some(serial::errors::BUSY)
        } else if !(1..=127).contains(&node) {
            Some(serial::errors::INVALID_COMMAND)
        } else {
            None
        }
    }

    fn start_remote(&mut self, request: &Request, started: Result<(), StartError>, remote: Remote) {
        match started {
            Ok(()) => self.remote = Some(remote),
            Err(StartError::Busy) => self.answer(request, serial::errors::BUSY, &[], remote.start),
            Err(StartError::NodeId) => self.answer(request, serial::errors::INVALID_COMMAND, &[], remote.start),
            Err(StartError::TooLong) => self.answer(request, serial::errors::INVALID_COMMAND_LENGTH, &[], remote.start),
        }
    }

    /// The running S or U ended: its answer.
    fn remote_done(&mut self, result: SdoResult) {
        let Some(r) = self.remote.take() else { return };
        let err = errors::of_remote(&result);
        let len = match result {
            SdoResult::Uploaded { len } => len,
            _ => 0,
        };
        let value = self.sdo_buf;
        let data = value.get(..len).unwrap_or(&[]);
        let request = if r.read {
            Request::ReadRemote { node: r.node, index: r.index, sub: r.sub }
        } else {
            Request::WriteRemote { node: r.node, index: r.index, sub: r.sub, data: host::Value::new() }
        };
        self.answer(&request, err, data, r.start);
    }

    /// The end of every input: what the dictionary, the manager and the node have to say.
    fn after_input(&mut self, now_us: u64) {
        self.now_us = self.now_us.max(now_us);
        while let Some(written) = self.node.od_mut().app.take_write() {
            self.on_written(&written, now_us);
        }
        if let Some(request) = self.node.od_mut().app.program.take_request() {
            self.program_change = Some(request);
        }
        let dropped = core::mem::take(&mut self.node.od_mut().app.writes_dropped);
        self.indications_dropped = self.indications_dropped.saturating_add(dropped);
        while let Some(event) = self.manager.take_event() {
            self.on_manager_event(&event);
        }
        self.take_node_events();
        self.apply_manager_control();
        self.show_own_status();
    }

    /// The heartbeat times of 5F01h.05/.06 go to the manager when they (or HB receive all)
    /// change: the producer time for scans to write into 1017h, the consumer time for every
    /// node's monitoring.
    fn apply_manager_control(&mut self) {
        let control = &self.node.od().device_control;
        let times = if control.manager_control.get() & HB_RECEIVE_ALL != 0 {
            (control.default_heartbeat_producer_time.get(), control.default_heartbeat_consumer_time.get())
        } else {
            (0, 0)
        };
        if times == self.heartbeat_ms {
            return;
        }
        self.heartbeat_ms = times;
        let heartbeat_ms = (times.0 != 0).then_some(times.0);
        self.manager.set_scan_config(ScanConfig { pdos: SCAN_PDOS as u8, heartbeat_ms });
        self.manager.monitor_mut().set_consumer_ms(None, times.1);
    }

    /// The NMT command `command` to the coprocessor itself, as the bus would bring it.
    fn own_nmt(&mut self, command: NmtCommand, now_us: u64) {
        if let Some(frame) = nmt_frame(command, self.node.node_id()) {
            self.node.on_frame(&frame, now_us);
        }
    }

    /// A write the device acts on or tells the host of.
    fn on_written(&mut self, w: &Written, now_us: u64) {
        if w.from_bus() {
            // The sender of an SDO download or an RPDO is not known: node-ID 0.
            self.indicate(0, w.index, w.sub, &w.data);
        }
        let [lo, hi] = [w.data.first().copied().unwrap_or(0), w.data.get(1).copied().unwrap_or(0)];
        match (w.index, w.sub) {
            (index::NMT_MASTER_MESSAGE, 1) => self.nmt_master(lo, hi),
            (index::DEVICE_CONTROL, 1) => {
                let command = if lo == 129 { NmtCommand::ResetNode } else { NmtCommand::ResetCommunication };
                self.own_nmt(command, now_us);
            }
            (index::DEVICE_CONTROL, 0x0A) => self.manager.scan(lo & 0x7F),
            _ => {}
        }
    }

    /// 5F0Ah.1: `command` to `node` (0: every node); a reset is recorded in 5F04h.
    fn nmt_master(&mut self, command: u8, node: u8) {
        let Some(nmt) = NmtCommand::from_code(command) else { return };
        if !self.manager.nmt(nmt, node) {
            return;
        }
        let code = match nmt {
            NmtCommand::ResetNode => status::RESET_APP,
            NmtCommand::ResetCommunication => status::RESET_COM,
            _ => return,
        };
        // A broadcast resets every node the manager has heard of.
        let known = |m: &Manager<SCANS, SCAN_PDOS>, n: u8| m.status(n).is_some_and(|s| s.state != Default::default());
        for n in if node == 0 { 1..=127 } else { node..=node } {
            if node != 0 || known(&self.manager, n) {
                self.record_status(n, code);
            }
        }
    }

    fn on_manager_event(&mut self, event: &ManagerEvent) {
        if let ManagerEvent::Sdo(result) = *event {
            return self.remote_done(result);
        }
        if let ManagerEvent::Scan(ScanEvent::Complete(node)) = *event {
            // The node's RPDOs may be others now: what the host wrote for them is void.
            self.rpdos.forget(node);
        }
        if let Some((node, codes)) = status::of_event(event) {
            for code in codes.into_iter().flatten() {
                self.record_status(node, code);
            }
        }
        let control = self.manager_control();
        let not_operational = |state: NodeState| matches!(state, NodeState::Stopped | NodeState::PreOperational);
        match *event {
            ManagerEvent::Scan(ScanEvent::Complete(node)) if control & KEEP_OP != 0 => {
                let operational = self.manager.status(node).is_some_and(|s| s.state == NodeState::Operational);
                if !operational {
                    self.manager.nmt(NmtCommand::Start, node);
                }
            }
            ManagerEvent::Node(MonitorEvent::StateChanged { node, to: state, .. } | MonitorEvent::HeartbeatStarted { node, state })
                if control & KEEP_OP != 0 && not_operational(state) =>
            {
                self.manager.nmt(NmtCommand::Start, node);
            }
            ManagerEvent::Node(MonitorEvent::HeartbeatLost(node)) if control & HB_RECEIVE_ALL != 0 => self.nmt_master(NmtCommand::ResetNode.code(), node),
            _ => {}
        }
    }

    /// 5F04h.`node` = `code`, and the host is told.
    fn record_status(&mut self, node: u8, code: u8) {
        if let Some(slot) = self.node.od_mut().status_of_all_nodes.items.get_mut(usize::from(node).wrapping_sub(1)) {
            *slot = code;
            let own = self.node.node_id();
            self.indicate(own, index::STATUS_OF_ALL_NODES, node, &[code]);
        }
    }

    fn take_node_events(&mut self) {
        while let Some(event) = self.node.take_event() {
            let area = match event {
                NodeEvent::ResetApplication => Some(Area::ALL),
                NodeEvent::ResetCommunication => Some(Area::COMMUNICATION),
                _ => None,
            };
            if let Some(area) = area {
                // The dictionary was reloaded: the loaded file's values again, the status
                // entries hold their defaults again (5F01h's are compared with what the
                // manager has after this input); the coprocessor starts itself again.
                self.apply_configuration(area);
                self.serial_to_program();
                self.shown = [0xFF; 3];
                self.after_boot(self.now_us);
            }
            if self.events.is_full() {
                self.events.pop_front();
            }
            let _ = self.events.push_back(event);
        }
    }

    /// 5F00h.01..03 from the node, and an indication for each that changed.
    fn show_own_status(&mut self) {
        if self.node.tx_overflows() > 0 || self.manager.tx_overflows > 0 {
            self.hardware |= HW_TX_OVERRUN;
        }
        let now = [self.node.node_id(), state_code(self.node.state()), self.hardware];
        let status = &mut self.node.od_mut().device_status;
        (status.device_status_own_node_id, status.device_status_own_nmt_state, status.device_status_own_hw_state) = (now[0], now[1], now[2]);
        for (sub, (&value, shown)) in (1..).zip(now.iter().zip(self.shown)) {
            if value != shown {
                self.indicate(now[0], index::DEVICE_STATUS, sub, &[value]);
            }
        }
        self.shown = now;
    }

    /// With 5F01h.04 bit 2: a TPDO of a scanned node, one D per mapped entry.
    fn receive_all(&mut self, frame: &CanFrame) {
        if self.manager_control() & PDO_RECEIVE_ALL == 0 || frame.rtr {
            return;
        }
        let id = u32::from(frame.id);
        let Some((node, mapping)) = self.manager.scans().iter().find_map(|s| {
            s.tpdos
                .iter()
                .find(|p| p.is_valid() && p.cob_id & 0x7FF == id)
                .map(|p| (s.node, heapless::Vec::<u32, MAX_MAPPED>::from_slice(p.mapping()).unwrap_or_default()))
        }) else {
            return;
        };
        let data = u64::from_le_bytes(frame.data);
        let mut at = 0_u32;
        for entry in mapping.iter() {
            let bits = entry & 0xFF;
            if bits == 0 || at + bits > u32::from(frame.dlc) * 8 {
                break;
            }
            let value = (data >> at) & (u64::MAX >> (64 - bits));
            let bytes = value.to_le_bytes();
            self.indicate(node, (entry >> 16) as u16, (entry >> 8) as u8, bytes.get(..bits.div_ceil(8) as usize).unwrap_or(&[]));
            at += bits;
        }
    }
}

impl<S: ParamStore, M: ConfigMemory> Device for Canopenia<S, M> {
    fn start(&mut self, now_us: u64) {
        self.now_us = now_us;
        self.node.start(now_us);
        self.serial_to_program();
        self.apply_configuration(Area::ALL);
        self.hardware = HW_INIT;
        self.shown = [0xFF; 3];
        self.after_boot(now_us);
        self.after_input(now_us);
    }

    /// Every frame goes to the node and to the manager (their COB-IDs do not overlap: the
    /// manager takes other nodes' answers, boot-ups, heartbeats and emergencies).
    fn on_frame(&mut self, frame: &CanFrame, now_us: u64) {
        self.node.on_frame(frame, now_us);
        if self.manager_runs() {
            self.manager.on_frame(frame, now_us, &mut self.sdo_buf);
        }
        self.receive_all(frame);
        self.after_input(now_us);
    }

    fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        let runs = self.manager_runs();
        let mut frame = self.node.poll(now_us).or_else(|| if runs { self.manager.poll(now_us, &mut self.sdo_buf) } else { None });
        if frame.is_none() && runs && self.manager_control() & RPDO_TRANSMIT_ALL != 0 {
            let times = self.pdo_times();
            frame = self.rpdos.check(times, now_us);
        }
        if frame.is_none()
            && let Some(request) = self.program_change.take()
        {
            self.change_program(request, now_us);
            // Its first frame (a boot-up, an emergency) now.
            frame = self.node.poll(now_us);
        }
        self.after_input(now_us);
        frame
    }

    fn on_bus_state(&mut self, bus: BusState, now_us: u64) {
        self.hardware |= match bus {
            BusState::Passive => HW_ERROR_PASSIVE,
            BusState::BusOff => HW_BUS_OFF,
            _ => 0,
        };
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

impl<S: ParamStore, M: ConfigMemory> HostPort for Canopenia<S, M> {
    fn on_host_byte(&mut self, byte: u8, now_ms: u64) {
        // The framing compares wrapping differences of a 32-bit millisecond clock.
        let command = match self.host.push(byte, now_ms as Millis) {
            None => return,
            Some(Ok(frame)) => host::command(&frame),
            Some(Err(_)) => None,
        };
        let start = self.host.start_byte();
        // The command is served at this time (an RPDO's update timer starts now).
        self.now_us = self.now_us.max(now_ms.saturating_mul(1000));
        match command {
            Some(command) if self.out.free() >= MAX_FRAME + self.reserved() => {
                self.start = start;
                self.serve(command, start);
            }
            _ => self.host_refusals = self.host_refusals.saturating_add(1),
        }
        self.after_input(now_ms.saturating_mul(1000));
    }

    fn host_output(&mut self, _now_ms: u64, out: &mut [u8]) -> usize {
        self.out.take(out)
    }
}

/// The settings of the active file in `app`'s configuration memory.
fn settings_of<M: ConfigMemory>(app: &Coprocessor<M>) -> Settings {
    app.program.active().map_or(Settings::FIRMWARE, |file| Settings::of(file.header()))
}

impl<S: ParamStore, M: ConfigMemory> Canopenia<S, M> {
    /// 1018h.4 holds the chip's serial number, and it is the activation key.
    fn serial_to_program(&mut self) {
        if let Some(serial) = self.serial_number {
            let _ = self.node.write(index::IDENTITY_OBJECT, 4, &serial.to_le_bytes(), Side::Device);
        }
        let mut serial = [0_u8; 4];
        let _ = self.node.read(index::IDENTITY_OBJECT, 4, 0, &mut serial, Side::Device);
        self.node.od_mut().app.program.serial = u32::from_le_bytes(serial);
    }
}

/// The coprocessor at `node_id` with its parameters and its configuration files in memories
/// from the runtime ("parameters", "configuration").
impl<M: ConfigMemory> Assemble<M> for Canopenia<BlockStore<M>, M> {
    fn mode_names(f: &mut dyn FnMut(&'static str)) {
        mode_names::<Od<Typed<Coprocessor<M>>>>(f);
    }

    fn assemble(mode: Option<&str>, node_id: u8, memory: &mut dyn FnMut(MemoryRequest) -> Option<M>) -> Result<Self, AssembleError> {
        assembly_mode::<Od<Typed<Coprocessor<M>>>>(mode, node_id)?;
        let size = <Od<Typed<Coprocessor<M>>> as NodeDictionary>::PERSISTENT_SIZE;
        let mut take = |name, capacity| memory(MemoryRequest { name, capacity }).ok_or(AssembleError::NoMemory(name));
        let params = take("parameters", BlockStore::<M>::capacity_for(size))?;
        let config = take("configuration", crate::config::slots::ConfigSlots::<M>::CAPACITY)?;
        Ok(Canopenia::with_configuration(node_id, BlockStore::new(params, 0), config))
    }
}
