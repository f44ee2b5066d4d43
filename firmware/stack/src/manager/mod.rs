//! A CANopen manager beside the slave engines: SDO client, NMT master, monitoring of up to
//! 127 nodes and node scanning, `no_std`, heap-free and poll-driven like the node.
//!
//! ```text
//! board ──on_frame(frame, now, buf)──▶ Manager ──poll(now, buf)──▶ frames to send
//!                                        │
//!   upload/download/nmt/scan (device code) ──▶ take_event: node changes, scans, SDO results
//! ```
//! - [`crate::sdo::client`]: the SDO client channel the manager drives;
//! - [`monitor`]: boot-ups, heartbeats and emergencies of every node, and the node table;
//! - [`scan`]: what the manager reads of a node when it appears, and the scan cache;
//! - [`nmt_frame`]: NMT master commands.
//!
//! A device that is a manager feeds every received frame to both its node and its manager
//! and sends what both poll. The manager's frames are never received by the device itself (a
//! CAN controller does not receive its own frames), so its own node is not affected by an NMT
//! broadcast it sends.
//!
//! With auto-scan on (the default), a node is scanned when it boots, and when its first
//! heartbeat comes from a node that has neither been scanned nor is queued.
//!
//! The manager has one SDO client channel, shared by the caller and the scanner. A caller's
//! transfer goes first: it starts as soon as the channel is free, before the scanner's next
//! transfer. A second caller transfer while one is queued or running gets
//! [`StartError::Busy`]. The caller's data lives in the caller's buffer (`buf` of
//! [`Manager::on_frame`] and [`Manager::poll`]): the value to download, or where an upload
//! lands; the scanner reads into 4 bytes of its own.

pub mod monitor;
pub mod scan;

use crate::frame::CanFrame;
use crate::nmt::{NMT_COB_ID, NmtCommand};
use crate::od::SdoAbort;
use crate::ring::Ring;
use crate::sdo::client::{AbortSource, SdoClient, SdoResult, StartError};
use monitor::{Monitor, MonitorEvent, NodeStatus};
use scan::{ScanConfig, ScanEvent, ScanTransfer, Scanned, Scanner};

/// The NMT master frame for `command` to `node` (0: every node).
pub fn nmt_frame(command: NmtCommand, node: u8) -> Option<CanFrame> {
    if node > 127 {
        return None;
    }
    CanFrame::data(NMT_COB_ID, &[command.code(), node])
}

/// What the manager tells its device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ManagerEvent {
    Node(MonitorEvent),
    Scan(ScanEvent),
    /// The caller's SDO transfer ended.
    Sdo(SdoResult),
}

/// A caller transfer waiting for the channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Request {
    Upload {
        node: u8,
        index: u16,
        sub: u8,
    },
    /// The value is the first `len` bytes of the caller's buffer.
    Download {
        node: u8,
        index: u16,
        sub: u8,
        len: usize,
    },
}

/// Who the transfer on the channel is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Owner {
    Nobody,
    Caller,
    Scanner,
}

const TX_QUEUE: usize = 4;
const EVENTS: usize = 16;

/// A manager caching up to `NODES` scans of `PDOS` TPDOs and RPDOs each.
#[derive(Debug)]
pub struct Manager<const NODES: usize, const PDOS: usize> {
    client: SdoClient,
    owner: Owner,
    request: Option<Request>,
    monitor: Monitor,
    scanner: Scanner<NODES, PDOS>,
    /// Scan nodes as they boot or send their first heartbeat.
    auto_scan: bool,
    scan_buf: [u8; 4],
    tx: Ring<CanFrame, TX_QUEUE>,
    events: Ring<ManagerEvent, EVENTS>,
    /// Events lost to a full queue (the oldest go first), and frames to a full transmit queue.
    pub events_dropped: u32,
    pub tx_overflows: u32,
}

impl<const NODES: usize, const PDOS: usize> Manager<NODES, PDOS> {
    const NO_FRAME: CanFrame = CanFrame { id: 0, rtr: false, dlc: 0, data: [0; 8] };

    pub const fn new(scan: ScanConfig) -> Self {
        Manager {
            client: SdoClient::new(),
            owner: Owner::Nobody,
            request: None,
            monitor: Monitor::new(),
            scanner: Scanner::new(scan),
            auto_scan: true,
            scan_buf: [0; 4],
            tx: Ring::new(Self::NO_FRAME),
            events: Ring::new(ManagerEvent::Sdo(SdoResult::Downloaded)),
            events_dropped: 0,
            tx_overflows: 0,
        }
    }

    /// Whether nodes are scanned when they boot or send their first heartbeat (default on).
    pub fn set_auto_scan(&mut self, on: bool) {
        self.auto_scan = on;
    }

    pub fn set_scan_config(&mut self, config: ScanConfig) {
        self.scanner.set_config(config);
    }

    pub fn set_sdo_timeout_us(&mut self, us: u64) {
        self.client.set_timeout_us(us);
    }

    /// Heartbeat consumer times and the node table.
    pub fn monitor_mut(&mut self) -> &mut Monitor {
        &mut self.monitor
    }

    pub fn status(&self, node: u8) -> Option<NodeStatus> {
        self.monitor.status(node)
    }

    /// The last completed scan of `node`.
    pub fn scanned(&self, node: u8) -> Option<&Scanned<PDOS>> {
        self.scanner.scanned(node)
    }

    /// Every cached scan, oldest first.
    pub fn scans(&self) -> &[Scanned<PDOS>] {
        self.scanner.cached()
    }

    /// Queues a scan of `node`.
    pub fn scan(&mut self, node: u8) {
        self.scanner.request(node);
    }

    /// Reads `index`/`sub` of `node` into the caller's buffer; the result comes as
    /// [`ManagerEvent::Sdo`].
    pub fn upload(&mut self, node: u8, index: u16, sub: u8) -> Result<(), StartError> {
        self.queue_request(node, Request::Upload { node, index, sub })
    }

    /// Writes the first `len` bytes of the caller's buffer to `index`/`sub` of `node`; the
    /// result comes as [`ManagerEvent::Sdo`].
    pub fn download(&mut self, node: u8, index: u16, sub: u8, len: usize) -> Result<(), StartError> {
        if u32::try_from(len).is_err() {
            return Err(StartError::TooLong);
        }
        self.queue_request(node, Request::Download { node, index, sub, len })
    }

    fn queue_request(&mut self, node: u8, request: Request) -> Result<(), StartError> {
        if self.request.is_some() || self.owner == Owner::Caller {
            return Err(StartError::Busy);
        }
        if !(1..=127).contains(&node) {
            return Err(StartError::NodeId);
        }
        self.request = Some(request);
        Ok(())
    }

    /// Sends an NMT command to `node` (0: every node); `false` if it could not be queued.
    pub fn nmt(&mut self, command: NmtCommand, node: u8) -> bool {
        match nmt_frame(command, node) {
            Some(frame) => self.send(frame),
            None => false,
        }
    }

    /// A received frame; `buf` is the caller's transfer data.
    pub fn on_frame(&mut self, frame: &CanFrame, now_us: u64, buf: &mut [u8]) {
        if let Some(event) = self.monitor.on_frame(frame, now_us) {
            match event {
                MonitorEvent::BootUp(node) if self.auto_scan => self.scanner.request(node),
                // A node that was on the bus before the manager: its first heartbeat is the
                // first the manager hears of it.
                MonitorEvent::HeartbeatStarted { node, .. } if self.auto_scan && !self.scanner.knows(node) => self.scanner.request(node),
                _ => {}
            }
            self.event(ManagerEvent::Node(event));
        }
        let data = if self.owner == Owner::Scanner { &mut self.scan_buf[..] } else { buf };
        if let Some(request) = self.client.on_frame(frame, now_us, data) {
            self.send(request);
        }
        self.collect_result();
    }

    /// Runs the timers, starts the next transfer, and returns the next frame to send, if any.
    /// Call until `None`.
    pub fn poll(&mut self, now_us: u64, buf: &mut [u8]) -> Option<CanFrame> {
        if let Some(frame) = self.tx.pop_front() {
            return Some(frame);
        }
        while let Some(event) = self.monitor.check(now_us) {
            self.event(ManagerEvent::Node(event));
        }
        if let Some(abort) = self.client.poll(now_us) {
            self.send(abort);
            self.collect_result();
        }
        if self.client.is_idle() {
            self.start_next(now_us, buf);
        }
        self.tx.pop_front()
    }

    /// The caller's queued transfer first, else the scanner's next.
    fn start_next(&mut self, now_us: u64, buf: &[u8]) {
        let (owner, started) = if let Some(request) = self.request.take() {
            let started = match request {
                Request::Upload { node, index, sub } => self.client.upload(node, index, sub, now_us),
                Request::Download { node, index, sub, len } => self.client.download(node, index, sub, buf.get(..len).unwrap_or(buf), now_us),
            };
            (Owner::Caller, started)
        } else {
            if let Some(event) = self.scanner.start_next() {
                self.event(ManagerEvent::Scan(event));
            }
            let started = match self.scanner.transfer() {
                Some(ScanTransfer::Read { node, index, sub }) => self.client.upload(node, index, sub, now_us),
                Some(ScanTransfer::Write { node, index, sub, data }) => self.client.download(node, index, sub, &data, now_us),
                None => return,
            };
            (Owner::Scanner, started)
        };
        match started {
            Ok(frame) => {
                self.owner = owner;
                self.send(frame);
            }
            // The channel was idle and the request checked when queued: not reached, but a
            // caller is never left waiting.
            Err(_) if owner == Owner::Caller => self.event(ManagerEvent::Sdo(SdoResult::Aborted { code: SdoAbort::General.code(), by: AbortSource::Client })),
            Err(_) => {}
        }
    }

    fn collect_result(&mut self) {
        let Some(result) = self.client.take_result() else { return };
        match core::mem::replace(&mut self.owner, Owner::Nobody) {
            Owner::Caller => self.event(ManagerEvent::Sdo(result)),
            Owner::Scanner => {
                if let Some(event) = self.scanner.on_result(&result, &self.scan_buf) {
                    self.event(ManagerEvent::Scan(event));
                }
            }
            Owner::Nobody => {}
        }
    }

    /// The next event for the device code.
    pub fn take_event(&mut self) -> Option<ManagerEvent> {
        self.events.pop_front()
    }

    fn event(&mut self, event: ManagerEvent) {
        if self.events.push_back_evicting(event) {
            self.events_dropped = self.events_dropped.saturating_add(1);
        }
    }

    fn send(&mut self, frame: CanFrame) -> bool {
        let queued = self.tx.push_back(frame).is_ok();
        if !queued {
            self.tx_overflows = self.tx_overflows.saturating_add(1);
        }
        queued
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nmt_master_frames() {
        assert_eq!(nmt_frame(NmtCommand::Start, 0), CanFrame::data(0, &[0x01, 0x00]));
        assert_eq!(nmt_frame(NmtCommand::ResetCommunication, 127), CanFrame::data(0, &[0x82, 0x7F]));
        assert_eq!(nmt_frame(NmtCommand::Stop, 128), None);
        let mut m = Manager::<1, 1>::new(ScanConfig::default());
        assert!(m.nmt(NmtCommand::EnterPreOperational, 5));
        assert!(!m.nmt(NmtCommand::Start, 200));
        let mut buf = [0; 4];
        assert_eq!(m.poll(0, &mut buf), CanFrame::data(0, &[0x80, 0x05]));
        assert_eq!(m.poll(0, &mut buf), None, "one frame, nothing else happens");
        assert_eq!(m.take_event(), None);
    }

    /// The RAM figures the README quotes, on a 64-bit host (a Cortex-M build is smaller only
    /// where `usize` fields are: the record cache's length).
    #[test]
    fn ram_of_the_manager_state() {
        extern crate std;
        std::println!(
            "monitor of 127 nodes: {} B; scan record with 4 PDOs each way: {} B; manager with 31 cached scans: {} B; SDO client channel: {} B",
            core::mem::size_of::<Monitor>(),
            core::mem::size_of::<Scanned<4>>(),
            core::mem::size_of::<Manager<31, 4>>(),
            core::mem::size_of::<SdoClient>()
        );
        assert_eq!(core::mem::size_of::<Monitor>(), 127 * 8 + 8, "8 bytes a node");
        // Besides the cache of records, the manager's state stays under 2 KiB.
        let cache = 31 * core::mem::size_of::<Scanned<4>>();
        assert!(core::mem::size_of::<Manager<31, 4>>() < cache + 2048);
    }
}
