#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! CANopenIA's configuration loading (manual section 4.2) on the virtual bus, with a CANopen
//! master's SDO client: the activation sequence, a binary EDS downloaded into 1F50h.2 of node
//! 70h, the application started with it; corrupt files and files the dictionary cannot hold
//! refused with nothing changed; a download cut by a power loss leaves the previous file.

use coforge_sim::devices::{DeviceKind, StoreAt};
use coforge_sim::vbus::VirtualBus;
use coforge_stack::frame::CanFrame;

const FIRMWARE_ID: u8 = 2;
const BOOTLOADER: u8 = 0x70;
const VENDOR_401: &[u8] = include_bytes!("../../../tests/vendor-data/canopenia/CiA401_IO_Node3.bin");
const VENDOR_402: &[u8] = include_bytes!("../../../tests/vendor-data/canopenia/CiA402_Stepper_Node8.bin");

/// Our own spec exported as a binary EDS for `node_id`, with the CANopen manager and autostart.
fn own_file(node_id: u8) -> Vec<u8> {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../spec/canopenia.yaml")).unwrap();
    let device = coforge_spec::load_str("canopenia.yaml", &text).device().unwrap().clone();
    let func = coforge_beds::layout::func::MANAGER | coforge_beds::layout::func::AUTOSTART;
    let settings = coforge_spec::beds::Settings { node_id, bitrate_kbit: 250, func, ident: "coforge test".into() };
    coforge_spec::beds::export(&device, None, settings).unwrap()
}

struct Bench {
    bus: VirtualBus,
    store: StoreAt,
    /// Every frame on the bus not taken by [`Bench::frames`] yet.
    seen: Vec<CanFrame>,
    /// Holds the memory files; removed when the bench is dropped.
    _dir: tempfile::TempDir,
}

impl Bench {
    /// The coprocessor (runtime node-ID 2) with its memories in files under a fresh directory.
    fn new(name: &str) -> Self {
        let dir = tempfile::Builder::new().prefix(&format!("coforge-ia-config-{name}-")).tempdir().unwrap();
        let store = StoreAt::File(dir.path().join("ia"));
        let mut bench = Bench { bus: VirtualBus::new(Vec::new()), store, seen: Vec::new(), _dir: dir };
        bench.power_on();
        bench
    }

    /// A coprocessor running coforge's own file for `node_id`.
    fn with_own_file(name: &str, node_id: u8) -> Self {
        let mut b = Bench::new(name);
        b.enter_bootloader(FIRMWARE_ID);
        b.download(BOOTLOADER, &own_file(node_id), None).unwrap();
        b.start_application(node_id);
        b
    }

    /// Power-on from what the memory files hold (a power cut is: drop the device, power on).
    fn power_on(&mut self) {
        let ia = DeviceKind::find("canopenia").unwrap().create(None, FIRMWARE_ID, &self.store).unwrap();
        self.bus = VirtualBus::new(vec![ia]);
        self.seen.clear();
        self.bus.settle();
    }

    /// The frames since the last call.
    fn frames(&mut self) -> Vec<CanFrame> {
        self.bus.settle();
        self.seen.extend(self.bus.drain());
        std::mem::take(&mut self.seen)
    }

    /// One SDO request to `node`, its answer.
    fn sdo(&mut self, node: u8, request: [u8; 8]) -> [u8; 8] {
        self.bus.settle();
        self.seen.extend(self.bus.drain());
        self.bus.send(CanFrame::data(0x600 + u16::from(node), &request).unwrap());
        self.bus.settle();
        let new = self.bus.drain();
        let answers: Vec<[u8; 8]> = new.iter().filter(|f| f.id == 0x580 + u16::from(node)).map(|f| f.data).collect();
        self.seen.extend(new);
        assert_eq!(answers.len(), 1, "one answer from node {node:#x}: {answers:x?}");
        answers[0]
    }

    fn read_u32(&mut self, node: u8, index: u16, sub: u8) -> Result<u32, u32> {
        let [i0, i1] = index.to_le_bytes();
        let a = self.sdo(node, [0x40, i0, i1, sub, 0, 0, 0, 0]);
        let value = u32::from_le_bytes([a[4], a[5], a[6], a[7]]);
        if a[0] == 0x80 { Err(value) } else { Ok(value) }
    }

    /// An expedited download; `Err(abort code)` if refused.
    fn write(&mut self, node: u8, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
        let [i0, i1] = index.to_le_bytes();
        let mut r = [0x23 | ((4 - data.len() as u8) << 2), i0, i1, sub, 0, 0, 0, 0];
        r[4..4 + data.len()].copy_from_slice(data);
        let a = self.sdo(node, r);
        if a[0] == 0x80 { Err(u32::from_le_bytes([a[4], a[5], a[6], a[7]])) } else { Ok(()) }
    }

    /// A segmented download of `file` into 1F50h.2 of `node`, stopped after `segments`
    /// segments if given; `Err(abort code)` if refused.
    fn download(&mut self, node: u8, file: &[u8], segments: Option<usize>) -> Result<(), u32> {
        let [s0, s1, s2, s3] = (file.len() as u32).to_le_bytes();
        let a = self.sdo(node, [0x21, 0x50, 0x1F, 2, s0, s1, s2, s3]);
        if a[0] == 0x80 {
            return Err(u32::from_le_bytes([a[4], a[5], a[6], a[7]]));
        }
        let chunks: Vec<&[u8]> = file.chunks(7).collect();
        for (i, chunk) in chunks.iter().enumerate().take(segments.unwrap_or(usize::MAX)) {
            let mut f = [0; 8];
            f[0] = ((i as u8 & 1) << 4) | ((7 - chunk.len() as u8) << 1) | u8::from(i + 1 == chunks.len());
            f[1..1 + chunk.len()].copy_from_slice(chunk);
            let a = self.sdo(node, f);
            if a[0] == 0x80 {
                return Err(u32::from_le_bytes([a[4], a[5], a[6], a[7]]));
            }
            assert_eq!(a[0], 0x20 | ((i as u8 & 1) << 4));
        }
        Ok(())
    }

    /// Steps 2..5 of section 4.2: pre-operational, the serial number as key, then 0 to
    /// 1F51h.1; the device boots as node 70h.
    fn enter_bootloader(&mut self, node: u8) {
        self.bus.send(CanFrame::data(0, &[0x80, node]).unwrap());
        self.frames();
        let serial = self.read_u32(node, 0x1018, 4).unwrap();
        self.write(node, 0x1F50, 1, &serial.to_le_bytes()).unwrap();
        self.write(node, 0x1F51, 1, &[0]).unwrap();
        let frames = self.frames();
        assert!(frames.iter().any(|f| f.id == 0x770 && f.payload() == [0]), "boot-up of node 70h: {frames:x?}");
    }

    /// 1 to 1F51h.1: the error-reset emergency from node 70h, then the application's boot-up.
    fn start_application(&mut self, expected_node: u8) -> Vec<CanFrame> {
        self.write(BOOTLOADER, 0x1F51, 1, &[1]).unwrap();
        let frames = self.frames();
        assert!(frames.iter().any(|f| f.id == 0xF0 && f.payload() == [0; 8]), "error reset from 70h: {frames:x?}");
        let boot = 0x700 + u16::from(expected_node);
        assert!(frames.iter().any(|f| f.id == boot && f.payload() == [0]), "boot-up of node {expected_node}: {frames:x?}");
        frames
    }
}

#[test]
fn the_activation_sequence_needs_the_serial_number_and_pre_operational() {
    let mut b = Bench::new("key");
    // Without the key, stopping the program is refused (device state).
    assert_eq!(b.write(FIRMWARE_ID, 0x1F51, 1, &[0]), Err(0x0800_0022));
    // A wrong key is refused as a value.
    let serial = b.read_u32(FIRMWARE_ID, 0x1018, 4).unwrap();
    assert_eq!(b.write(FIRMWARE_ID, 0x1F50, 1, &serial.wrapping_add(1).to_le_bytes()), Err(0x0609_0030));
    assert_eq!(b.write(FIRMWARE_ID, 0x1F51, 1, &[0]), Err(0x0800_0022));
    // Program data outside bootloader mode.
    assert_eq!(b.download(FIRMWARE_ID, &own_file(5), None), Err(0x0800_0022));
    // Operational: the writes of the sequence are refused (erratum COIA-37).
    b.bus.send(CanFrame::data(0, &[1, FIRMWARE_ID]).unwrap());
    b.frames();
    assert_eq!(b.write(FIRMWARE_ID, 0x1F50, 1, &serial.to_le_bytes()), Err(0x0800_0022));
    b.enter_bootloader(FIRMWARE_ID);
    assert_eq!(b.read_u32(BOOTLOADER, 0x1F51, 1), Ok(0), "stopped in bootloader mode");
    // Nothing loaded: starting again gives the firmware's own node-ID.
    b.start_application(FIRMWARE_ID);
    assert_eq!(b.read_u32(FIRMWARE_ID, 0x1F51, 1), Ok(1));
}

#[test]
fn a_file_from_coforge_beds_is_loaded_and_runs() {
    let mut b = Bench::new("own");
    b.enter_bootloader(FIRMWARE_ID);
    b.download(BOOTLOADER, &own_file(5), None).unwrap();
    b.start_application(5);
    // The file's autostart: operational at once (5F00h.02), its PDOs at node 5.
    assert_eq!(b.read_u32(5, 0x5F00, 2).map(|v| v & 0xFF), Ok(0x05));
    assert_eq!(b.read_u32(5, 0x1800, 1), Ok(0x185));
    assert_eq!(b.read_u32(5, 0x5F00, 1).map(|v| v & 0xFF), Ok(5));
    // A power-on keeps it.
    b.power_on();
    assert_eq!(b.read_u32(5, 0x1000, 0), Ok(0x000F_0191));
}

#[test]
fn corrupt_files_are_refused_and_change_nothing() {
    let mut b = Bench::with_own_file("corrupt", 5);
    b.enter_bootloader(5);
    let good = own_file(6);
    // A flipped bit (CRC), a cut file, a file longer than a slot.
    let mut flipped = good.clone();
    flipped[300] ^= 0x01;
    assert_eq!(b.download(BOOTLOADER, &flipped, None), Err(0x0800_0023));
    assert_eq!(b.download(BOOTLOADER, &good[..good.len() - 10], None), Err(0x0800_0023));
    assert_eq!(b.download(BOOTLOADER, &vec![0; 9000], None), Err(0x0607_0012));
    // A CiA 402 file needs objects this dictionary lacks.
    assert_eq!(b.download(BOOTLOADER, VENDOR_402, None), Err(0x0602_0000));
    // The previous file is still the one that runs.
    b.start_application(5);
}

#[test]
fn a_power_cut_during_the_download_leaves_the_previous_file() {
    let mut b = Bench::with_own_file("cut", 5);
    b.enter_bootloader(5);
    b.download(BOOTLOADER, &own_file(6), Some(100)).unwrap();
    b.power_on();
    let frames = b.frames();
    assert_eq!(b.read_u32(5, 0x1000, 0), Ok(0x000F_0191), "node 5 again after the cut: {frames:x?}");
    // And a download after it works.
    b.enter_bootloader(5);
    b.download(BOOTLOADER, &own_file(6), None).unwrap();
    b.start_application(6);
}

#[test]
fn the_vendor_cia401_file_is_loaded_and_runs() {
    let mut b = Bench::new("vendor");
    b.enter_bootloader(FIRMWARE_ID);
    b.download(BOOTLOADER, VENDOR_401, None).unwrap();
    b.start_application(3);
    // Its PDOs (TPDO2 maps the analog inputs, COB-IDs with the no-RTR bit) and defaults.
    assert_eq!(b.read_u32(3, 0x1801, 1), Ok(0x4000_0283));
    assert_eq!(b.read_u32(3, 0x1A01, 1), Ok(0x6401_0110));
    assert_eq!(b.read_u32(3, 0x1801, 3).map(|v| v & 0xFFFF), Ok(2000));
    assert_eq!(b.read_u32(3, 0x6000, 1).map(|v| v & 0xFF), Ok(0x12));
}
