//! The coforge devices the simulator runs, by name: one registry line per device, each built
//! through the device contract ([`Assemble`]) and driven through it ([`Device`]).

use crate::cr3101::{SimBoard, SimCr3101};
use crate::storage::Eeprom;
use co401gw1::Gw1;
use co401memory1::{FixedBoard, Memory1};
use coforge_stack::device::{Assemble, AssembleError, Device, MemoryRequest, NodeAccess, assembly_mode, mode_names};
use coforge_stack::emcy::EmcyDefault;
use coforge_stack::node::Node;
use coforge_stack::od::NodeDictionary;
use coforge_stack::store::{BlockStore, ParamStore};
use std::path::{Path, PathBuf};

/// Every device, by crate name.
pub const DEVICES: &[DeviceKind] = &[
    DeviceKind::of::<Memory1<Eeprom, FixedBoard>>("co401memory1"),
    DeviceKind::of::<Gw1<co401gw1::FixedBoard, BlockStore<Eeprom>>>("co401gw1"),
    DeviceKind { name: "cr3101", build: build_cr3101 },
    DeviceKind::of::<canopenia::Canopenia<BlockStore<Eeprom>, Eeprom>>("canopenia"),
];

/// Fault-injection commands typed on the simulator's console (see `coforge sim --help`).
pub trait Console {
    /// Runs `command`; what it did, or why not.
    fn console(&mut self, command: &str) -> Result<String, String> {
        Err(format!("this device takes no console commands (got `{command}`)"))
    }
}

/// A plain generated node has no board to inject faults into.
impl<D: NodeDictionary, S: ParamStore, const N: usize, const P: usize> Console for Node<D, S, N, P> {}

/// A running device, whatever its type.
pub trait SimDevice: Device + Console + Send {}

impl<T: Device + Console + Send> SimDevice for T {}

/// The spec emergency called `name` in the node's mode (fault injection by name).
pub fn emergency(node: &dyn NodeAccess, name: &str) -> Option<EmcyDefault> {
    node.emergency_named(name)
}

/// Raises the spec emergency called `name`; `false` if there is none.
pub fn raise(device: &mut dyn SimDevice, name: &str) -> bool {
    let found = emergency(device.node(), name);
    found.map(|e| device.node_mut().raise(&e)).is_some()
}

/// Ends the spec emergency called `name`; `false` if there is none.
pub fn clear(device: &mut dyn SimDevice, name: &str) -> bool {
    let found = emergency(device.node(), name);
    found.map(|e| device.node_mut().clear(&e)).is_some()
}

/// Where a simulated device keeps its non-volatile memory.
#[derive(Debug, Clone, Default)]
pub enum StoreAt {
    /// In memory: survives NMT resets, not a restart of the simulator.
    #[default]
    Memory,
    /// In files: the plain node's parameters in the file itself, any other memory in
    /// `FILE.<name>` (CO401Memory1's banks in `FILE.bank1` and `FILE.bank2`).
    File(PathBuf),
}

/// The EEPROM a device asks for, at `store`.
pub fn eeprom(store: &StoreAt, request: MemoryRequest) -> Result<Eeprom, String> {
    match store {
        StoreAt::Memory => Ok(Eeprom::new(request.capacity)),
        StoreAt::File(path) => {
            let mut name = path.clone().into_os_string();
            if request.name != "parameters" {
                name.push(format!(".{}", request.name));
            }
            let path = PathBuf::from(name);
            Eeprom::with_file(request.capacity, &path).map_err(|e| format!("{}: {e}", path.display()))
        }
    }
}

/// Builds a device: its name, mode name, node-ID, where its non-volatile memory lives, the
/// card image in its slot (CR3101).
type Build = fn(&'static str, Option<&str>, u8, &StoreAt, Option<&Path>) -> Result<Box<dyn SimDevice>, String>;

/// A device the simulator can run.
#[derive(Debug, Clone, Copy)]
pub struct DeviceKind {
    pub name: &'static str,
    build: Build,
}

impl DeviceKind {
    /// Device type `T` under `name`.
    pub const fn of<T: Assemble<Eeprom> + Console + Send + 'static>(name: &'static str) -> DeviceKind {
        DeviceKind { name, build: build::<T> }
    }

    pub fn find(name: &str) -> Result<DeviceKind, String> {
        DEVICES.iter().find(|d| d.name == name).copied().ok_or_else(|| {
            let known: Vec<&str> = DEVICES.iter().map(|d| d.name).collect();
            format!("unknown device `{name}`; known devices: {}", known.join(", "))
        })
    }

    /// A device of this kind, not started yet.
    pub fn create(&self, mode: Option<&str>, node_id: u8, store: &StoreAt) -> Result<Box<dyn SimDevice>, String> {
        (self.build)(self.name, mode, node_id, store, None)
    }

    /// A device of this kind with the card image `card` in its slot (CR3101; made and
    /// formatted if there is no such file).
    pub fn create_with_card(&self, mode: Option<&str>, node_id: u8, store: &StoreAt, card: &Path) -> Result<Box<dyn SimDevice>, String> {
        (self.build)(self.name, mode, node_id, store, Some(card))
    }
}

/// Checked first, so that no file is created for a device that cannot run. 0 goes on to the
/// device: CO401GW1 takes it as ID pins all high (the host sets 100Bh); the others refuse it
/// before they ask for memory.
fn check_node_id(node_id: u8) -> Result<(), String> {
    if node_id > 127 { Err(format!("node-ID {node_id} is outside 1..=127")) } else { Ok(()) }
}

/// CR3101: its mode comes from 20F5h and its node-ID from 20F0h/20F1h at power-on;
/// `node_id` is the pair's factory setting, and `mode` is written into 20F5h before that.
fn build_cr3101(name: &'static str, mode: Option<&str>, node_id: u8, store: &StoreAt, card: Option<&Path>) -> Result<Box<dyn SimDevice>, String> {
    check_node_id(node_id)?;
    if node_id == 0 {
        return Err(format!("node-ID {node_id} is outside 1..=127"));
    }
    type Dictionary = cr3101::Od<cr3101::app::Typed<cr3101::logger::Logger<crate::cr3101::SimCard>>>;
    let given = mode;
    let mode = assembly_mode::<Dictionary>(mode, node_id).map_err(|_| {
        let mut known = Vec::new();
        mode_names::<Dictionary>(&mut |m| known.push(m));
        format!("{name} has no mode `{}`; its modes are: {}", given.unwrap_or_default(), known.join(", "))
    })?;
    let size = <Dictionary as NodeDictionary>::PERSISTENT_SIZE;
    // Saved at every write (automatic save): a ring of slots spreads the wear.
    let request = MemoryRequest { name: "parameters", capacity: BlockStore::<Eeprom>::capacity_for_slots(size, coforge_stack::store::MAX_SLOTS) };
    let storage = eeprom(store, request)?;
    let board = SimBoard::new(card.map(Path::to_path_buf)).map_err(|e| format!("{name}: card image: {e}"))?;
    let mut device = SimCr3101::new(board, BlockStore::new(storage, 0), node_id);
    if given.is_some() {
        device.set_pdo_mode(mode);
    }
    Ok(Box::new(device))
}

fn build<T: Assemble<Eeprom> + Console + Send + 'static>(
    name: &'static str,
    mode: Option<&str>,
    node_id: u8,
    store: &StoreAt,
    card: Option<&Path>,
) -> Result<Box<dyn SimDevice>, String> {
    let bad_node_id = || format!("node-ID {node_id} is outside 1..=127");
    check_node_id(node_id)?;
    if card.is_some() {
        return Err(format!("{name} has no card slot (--card is for cr3101)"));
    }
    let mut file_error = None;
    let mut memory = |request| eeprom(store, request).map_err(|e| file_error = Some(e)).ok();
    match T::assemble(mode, node_id, &mut memory) {
        Ok(device) => Ok(Box::new(device)),
        Err(AssembleError::UnknownMode) => {
            let mut known = Vec::new();
            T::mode_names(&mut |m| known.push(m));
            Err(format!("{name} has no mode `{}`; its modes are: {}", mode.unwrap_or_default(), known.join(", ")))
        }
        Err(AssembleError::NodeId) => Err(bad_node_id()),
        Err(AssembleError::NoMemory(what)) => Err(file_error.unwrap_or_else(|| format!("{name}: no {what} memory"))),
        Err(AssembleError::Config(why)) => Err(format!("{name}: {why}")),
    }
}
