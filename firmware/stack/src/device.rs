//! The device contract: what every runtime drives (a board's main loop, the simulator, the
//! size probe, the tests) and every device implements, from a plain generated node to a
//! module with behaviour of its own.
//!
//! ```text
//! runtime ──start / on_frame / on_bus_state──▶ Device ──poll──▶ frames to send
//!    │                                           │
//!    └──on_host_byte(byte, t)──▶ HostPort ──host_output(t)──▶ bytes to the host, at any time
//! ```
//! Times are microseconds from an arbitrary epoch, except on the serial host port, whose
//! framings time gaps and pauses in milliseconds (so a byte costs no 64-bit division); a
//! device never reads a clock itself. The serial host port is byte-oriented both ways: a device answers late, or unasked (a
//! boot-up frame every 250 ms, an indication), so output is polled, not returned per byte.

use crate::emcy::EmcyDefault;
use crate::frame::CanFrame;
use crate::leds::Leds;
use crate::nmt::NmtState;
use crate::node::{BusState, Node, NodeEvent};
use crate::od::{NodeDictionary, ReadLen, SdoAbort, Side, mode_named};
use crate::store::ParamStore;

/// A CANopen device as its runtime sees it.
pub trait Device {
    /// Power-on.
    fn start(&mut self, now_us: u64);

    /// A frame received from the bus.
    fn on_frame(&mut self, frame: &CanFrame, now_us: u64);

    /// Runs the timers; the next frame to send, if any. Call until `None`.
    fn poll(&mut self, now_us: u64) -> Option<CanFrame>;

    /// The CAN controller changed its error state.
    fn on_bus_state(&mut self, bus: BusState, now_us: u64);

    /// The next event for the runtime (resets, state changes, a controller restart).
    fn take_event(&mut self) -> Option<NodeEvent>;

    /// CiA 303-3 indicator states.
    fn leds(&self) -> Leds;

    /// The CANopen node underneath: state, dictionary, emergencies.
    fn node(&self) -> &dyn NodeAccess;

    fn node_mut(&mut self) -> &mut dyn NodeAccess;

    /// The serial host interface, for a device that has one.
    fn host_port(&mut self) -> Option<&mut dyn HostPort> {
        None
    }
}

/// A device's serial host interface, as a byte stream each way.
pub trait HostPort {
    /// A byte from the host, received at `now_ms` (framings resynchronise on pauses).
    fn on_host_byte(&mut self, byte: u8, now_ms: u64);

    /// Copies bytes waiting for the host at `now_ms` into `out` and returns how many: answers,
    /// late answers and unsolicited frames alike. 0 when nothing waits.
    fn host_output(&mut self, now_ms: u64, out: &mut [u8]) -> usize;
}

/// The node underneath a device, for runtimes and host tools (object-safe, so a runtime can
/// hold any device).
pub trait NodeAccess {
    fn state(&self) -> NmtState;

    fn node_id(&self) -> u8;

    /// Whether the CAN side runs (see [`Node::enable_can`]).
    fn can_enabled(&self) -> bool;

    /// The spec name of the dictionary's mode.
    fn mode_name(&self) -> &'static str;

    /// A read on behalf of `side`.
    fn read(&mut self, index: u16, sub: u8, offset: usize, buf: &mut [u8], side: Side) -> Result<ReadLen, SdoAbort>;

    /// A write on behalf of `side`, with the side effects of an SDO download.
    fn write(&mut self, index: u16, sub: u8, data: &[u8], side: Side) -> Result<(), SdoAbort>;

    /// The spec's emergencies in the dictionary's mode.
    fn emergencies(&self) -> &'static [EmcyDefault];

    /// The spec emergency called `name` in the dictionary's mode (host tools).
    fn emergency_named(&self, name: &str) -> Option<EmcyDefault>;

    fn raise(&mut self, e: &EmcyDefault);

    fn clear(&mut self, e: &EmcyDefault);

    fn is_active(&self, e: &EmcyDefault) -> bool;

    /// An application event for TPDO `number` (1-based).
    fn trigger_tpdo(&mut self, number: u16);

    /// Frames the node could not queue.
    fn tx_overflows(&self) -> u32;
}

/// A non-volatile memory a device asks its runtime for when it is assembled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MemoryRequest {
    /// What it holds ("parameters", "bank1", ...): a runtime names files after it.
    pub name: &'static str,
    /// Bytes.
    pub capacity: usize,
}

/// Why a device could not be assembled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AssembleError {
    /// The device has no mode of that name.
    UnknownMode,
    /// The node-ID is outside 1..=127.
    NodeId,
    /// The runtime could not provide this memory.
    NoMemory(&'static str),
    /// The device refused its configuration (reserved pin settings, ...).
    Config(&'static str),
}

/// How a runtime builds a device: the mode and node-ID it chooses (a simulated board's pins)
/// and the non-volatile memories of type `M` it provides.
pub trait Assemble<M>: Device + Sized {
    /// Calls `f` with each mode's spec name, the default first.
    fn mode_names(f: &mut dyn FnMut(&'static str));

    /// The device in mode `mode` (`None`: the default) at `node_id`, not started yet, with the
    /// memories `memory` gives it.
    fn assemble(mode: Option<&str>, node_id: u8, memory: &mut dyn FnMut(MemoryRequest) -> Option<M>) -> Result<Self, AssembleError>;
}

impl<D: NodeDictionary, S: ParamStore, const N: usize, const P: usize> Node<D, S, N, P> {
    /// A node of dictionary `D` in `mode` at `node_id`, with the spec's node settings.
    pub fn of_dictionary(mode: D::Mode, node_id: u8, app: D::App, store: S) -> Self {
        Node::new(D::new(mode, node_id, app), store, D::node_config(node_id))
    }
}

impl<D: NodeDictionary, S: ParamStore, const N: usize, const P: usize> Device for Node<D, S, N, P> {
    fn start(&mut self, now_us: u64) {
        Node::start(self, now_us);
    }
    fn on_frame(&mut self, frame: &CanFrame, now_us: u64) {
        Node::on_frame(self, frame, now_us);
    }
    fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        Node::poll(self, now_us)
    }
    fn on_bus_state(&mut self, bus: BusState, now_us: u64) {
        Node::on_bus_state(self, bus, now_us);
    }
    fn take_event(&mut self) -> Option<NodeEvent> {
        Node::take_event(self)
    }
    fn leds(&self) -> Leds {
        Node::leds(self)
    }
    fn node(&self) -> &dyn NodeAccess {
        self
    }
    fn node_mut(&mut self) -> &mut dyn NodeAccess {
        self
    }
}

impl<D: NodeDictionary, S: ParamStore, const N: usize, const P: usize> NodeAccess for Node<D, S, N, P> {
    fn state(&self) -> NmtState {
        Node::state(self)
    }
    fn node_id(&self) -> u8 {
        Node::node_id(self)
    }
    fn can_enabled(&self) -> bool {
        Node::can_enabled(self)
    }
    fn mode_name(&self) -> &'static str {
        D::mode_name(self.od().mode())
    }
    fn read(&mut self, index: u16, sub: u8, offset: usize, buf: &mut [u8], side: Side) -> Result<ReadLen, SdoAbort> {
        Node::read(self, index, sub, offset, buf, side)
    }
    fn write(&mut self, index: u16, sub: u8, data: &[u8], side: Side) -> Result<(), SdoAbort> {
        Node::write(self, index, sub, data, side)
    }
    fn emergencies(&self) -> &'static [EmcyDefault] {
        self.od().emergencies()
    }
    fn emergency_named(&self, name: &str) -> Option<EmcyDefault> {
        self.od().emergency_named(name)
    }
    fn raise(&mut self, e: &EmcyDefault) {
        Node::raise(self, e);
    }
    fn clear(&mut self, e: &EmcyDefault) {
        Node::clear(self, e);
    }
    fn is_active(&self, e: &EmcyDefault) -> bool {
        Node::is_active(self, e)
    }
    fn trigger_tpdo(&mut self, number: u16) {
        Node::trigger_tpdo(self, number);
    }
    fn tx_overflows(&self) -> u32 {
        Node::tx_overflows(self)
    }
}

/// What every device checks first when it is assembled: the mode a runtime names exists in
/// dictionary `D`, and the node-ID is one CANopen allows.
pub fn assembly_mode<D: NodeDictionary>(mode: Option<&str>, node_id: u8) -> Result<D::Mode, AssembleError> {
    let mode = mode_named::<D>(mode).map_err(|_| AssembleError::UnknownMode)?;
    if !(1..=127).contains(&node_id) {
        return Err(AssembleError::NodeId);
    }
    Ok(mode)
}

/// Calls `f` with the spec name of each mode of dictionary `D` (`Assemble::mode_names`).
pub fn mode_names<D: NodeDictionary>(f: &mut dyn FnMut(&'static str)) {
    D::MODES.iter().for_each(|&m| f(D::mode_name(m)));
}

/// A plain generated node keeps its parameters (1010h/1011h) in a block store on the one
/// memory it asks for.
impl<D, M, const N: usize, const P: usize> Assemble<M> for Node<D, crate::store::BlockStore<M>, N, P>
where
    D: NodeDictionary,
    D::App: Default,
    M: embedded_storage::Storage,
{
    fn mode_names(f: &mut dyn FnMut(&'static str)) {
        mode_names::<D>(f);
    }

    fn assemble(mode: Option<&str>, node_id: u8, memory: &mut dyn FnMut(MemoryRequest) -> Option<M>) -> Result<Self, AssembleError> {
        let mode = assembly_mode::<D>(mode, node_id)?;
        let request = MemoryRequest { name: "parameters", capacity: crate::store::BlockStore::<M>::capacity_for(D::PERSISTENT_SIZE) };
        let storage = memory(request).ok_or(AssembleError::NoMemory(request.name))?;
        Ok(Node::of_dictionary(mode, node_id, D::App::default(), crate::store::BlockStore::new(storage, 0)))
    }
}
