//! The four coforge devices as simulator nodes, chosen by name at run time.

use crate::app::RamApp;
use crate::storage::MemStorage;
use coforge_stack::emcy::EmcyDefault;
use coforge_stack::frame::CanFrame;
use coforge_stack::node::{BusState, Node, NodeEvent};
use coforge_stack::od::{AppObjects, NodeDictionary, ReadLen, SdoAbort, Side};
use coforge_stack::store::{BlockStore, ParamStore};
use std::path::PathBuf;

/// A running device, whatever its dictionary type.
pub trait SimNode: Send {
    fn start(&mut self, now_us: u64);
    fn on_frame(&mut self, frame: &CanFrame, now_us: u64);
    fn poll(&mut self, now_us: u64) -> Option<CanFrame>;
    fn state(&self) -> coforge_stack::nmt::NmtState;
    fn node_id(&self) -> u8;
    /// A read or write as the device itself (no access rules; lengths and limits apply).
    fn read(&mut self, index: u16, sub: u8, buf: &mut [u8]) -> Result<ReadLen, SdoAbort>;
    fn write(&mut self, index: u16, sub: u8, data: &[u8], side: Side) -> Result<(), SdoAbort>;
    /// The spec emergency called `name` (fault injection); `false` if there is none.
    fn raise(&mut self, name: &str) -> bool;
    fn clear(&mut self, name: &str) -> bool;
    fn on_bus_state(&mut self, bus: BusState, now_us: u64);
    fn take_event(&mut self) -> Option<NodeEvent>;
    fn trigger_tpdo(&mut self, number: u16);
    /// CiA 303-3 indicator states.
    fn leds(&self) -> coforge_stack::leds::Leds;
    /// Whether the device has a serial host interface.
    fn has_serial(&self) -> bool {
        false
    }
    /// One byte from the serial host, received at `now_ms`; the answer, if this byte
    /// completes a command, goes to `out` and its length is returned.
    fn serial_byte(&mut self, _byte: u8, _now_ms: u32, _out: &mut [u8]) -> usize {
        0
    }
    /// A fault-injection command from the simulator's console (see `coforge sim --help`).
    fn control(&mut self, command: &str) -> Result<String, String> {
        Err(format!("this device takes no console commands (got `{command}`)"))
    }
}

/// A generated dictionary's emergencies by spec name (the device's `emcy::by_name` in the
/// dictionary's mode): the names live on the host only.
pub trait EmcyByName {
    fn emcy_by_name(&self, name: &str) -> Option<EmcyDefault>;
}

macro_rules! emcy_by_name {
    ($($krate:ident),*) => {
        $(impl<A: AppObjects> EmcyByName for $krate::Od<A> {
            fn emcy_by_name(&self, name: &str) -> Option<EmcyDefault> {
                $krate::emcy::by_name(self.mode(), name)
            }
        })*
    };
}

emcy_by_name!(co401memory1, co401gw1, cr3101, canopenia);

impl<D, S, const N: usize, const P: usize> SimNode for Node<D, S, N, P>
where
    D: NodeDictionary + EmcyByName + Send,
    S: ParamStore + Send,
{
    fn start(&mut self, now_us: u64) {
        Node::start(self, now_us);
    }
    fn on_frame(&mut self, frame: &CanFrame, now_us: u64) {
        Node::on_frame(self, frame, now_us);
    }
    fn poll(&mut self, now_us: u64) -> Option<CanFrame> {
        Node::poll(self, now_us)
    }
    fn state(&self) -> coforge_stack::nmt::NmtState {
        Node::state(self)
    }
    fn node_id(&self) -> u8 {
        Node::node_id(self)
    }
    fn read(&mut self, index: u16, sub: u8, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        Node::read(self, index, sub, 0, buf, Side::Device)
    }
    fn write(&mut self, index: u16, sub: u8, data: &[u8], side: Side) -> Result<(), SdoAbort> {
        Node::write(self, index, sub, data, side)
    }
    fn raise(&mut self, name: &str) -> bool {
        let found = self.od().emcy_by_name(name);
        found.map(|e| Node::raise(self, &e)).is_some()
    }
    fn clear(&mut self, name: &str) -> bool {
        let found = self.od().emcy_by_name(name);
        found.map(|e| Node::clear(self, &e)).is_some()
    }
    fn on_bus_state(&mut self, bus: BusState, now_us: u64) {
        Node::on_bus_state(self, bus, now_us);
    }
    fn take_event(&mut self) -> Option<NodeEvent> {
        Node::take_event(self)
    }
    fn trigger_tpdo(&mut self, number: u16) {
        Node::trigger_tpdo(self, number);
    }
    fn leds(&self) -> coforge_stack::leds::Leds {
        Node::leds(self)
    }
}

/// Where a simulated device keeps its parameters.
#[derive(Debug, Clone, Default)]
pub enum StoreAt {
    /// In memory: survives NMT resets, not a restart of the simulator.
    #[default]
    Memory,
    /// In a file.
    File(PathBuf),
}

/// Builds a node of one device: mode name, node-ID, where its non-volatile memory lives.
type Build = fn(Option<&str>, u8, &StoreAt) -> Result<Box<dyn SimNode>, String>;

/// A device the simulator can run.
#[derive(Debug, Clone, Copy)]
pub struct DeviceKind {
    pub name: &'static str,
    build: Build,
}

/// An EEPROM of `capacity` bytes at `store`; `suffix` tells several apart in one file name.
pub fn eeprom(store: &StoreAt, capacity: usize, suffix: &str) -> Result<MemStorage, String> {
    match store {
        StoreAt::Memory => Ok(MemStorage::new(capacity)),
        StoreAt::File(path) => {
            let mut name = path.clone().into_os_string();
            name.push(suffix);
            let path = PathBuf::from(name);
            MemStorage::with_file(capacity, &path).map_err(|e| format!("{}: {e}", path.display()))
        }
    }
}

macro_rules! device_kind {
    ($krate:ident) => {
        DeviceKind {
            name: stringify!($krate),
            build: |mode, node_id, store| {
                let mode = match mode {
                    None => $krate::Mode::ALL[0],
                    Some(name) => $krate::Mode::ALL.into_iter().find(|m| m.name() == name).ok_or_else(|| {
                        let known: Vec<&str> = $krate::Mode::ALL.iter().map(|m| m.name()).collect();
                        format!("{} has no mode `{name}`; its modes are: {}", stringify!($krate), known.join(", "))
                    })?,
                };
                let size = <$krate::Od<RamApp> as NodeDictionary>::PERSISTENT_SIZE;
                let storage = eeprom(store, BlockStore::<MemStorage>::capacity_for(size), "")?;
                let od = $krate::Od::new(mode, node_id, RamApp::default());
                let node: $krate::Node<RamApp, BlockStore<MemStorage>> = Node::new(od, BlockStore::new(storage, 0), $krate::node_config(node_id));
                Ok(Box::new(node))
            },
        }
    };
}

/// Every device, by crate name.
pub const DEVICES: [DeviceKind; 4] =
    [DeviceKind { name: "co401memory1", build: crate::memory1::build }, device_kind!(co401gw1), device_kind!(cr3101), device_kind!(canopenia)];

impl DeviceKind {
    pub fn find(name: &str) -> Result<DeviceKind, String> {
        DEVICES.into_iter().find(|d| d.name == name).ok_or_else(|| {
            let known: Vec<&str> = DEVICES.iter().map(|d| d.name).collect();
            format!("unknown device `{name}`; known devices: {}", known.join(", "))
        })
    }

    /// A node of this device, not started yet.
    pub fn create(&self, mode: Option<&str>, node_id: u8, store: &StoreAt) -> Result<Box<dyn SimNode>, String> {
        if !(1..=127).contains(&node_id) {
            return Err(format!("node-ID {node_id} is outside 1..=127"));
        }
        (self.build)(mode, node_id, store)
    }
}
