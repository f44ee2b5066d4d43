//! The CANopen stack of generated devices on the virtual bus, driven frame by frame the way a
//! master would: NMT, SDO, PDOs, heartbeat, guarding, EMCY, store/restore.

#![allow(clippy::unwrap_used)]

use coforge_sim::devices::{DeviceKind, SimDevice, StoreAt};
use coforge_sim::vbus::VirtualBus;
use coforge_stack::frame::CanFrame;
use coforge_stack::nmt::NmtState;

const ID: u8 = 5;

fn node(device: &str) -> Box<dyn SimDevice> {
    DeviceKind::find(device).unwrap().create(None, ID, &StoreAt::Memory).unwrap()
}

/// A bus with `device` on it, its CAN side enabled (CO401GW1 waits for its host's enable).
fn started(device: &str) -> VirtualBus {
    let mut bus = VirtualBus::new(vec![node(device)]);
    if device == "co401gw1" {
        bus.nodes[0].console("enable").unwrap();
        bus.settle();
    }
    bus
}

fn bus(device: &str) -> VirtualBus {
    let mut bus = started(device);
    let boot = bus.drain();
    assert_eq!(boot, vec![CanFrame::data(0x705, &[0]).unwrap()], "boot-up message");
    bus
}

fn frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::data(id, data).unwrap()
}

fn nmt(bus: &mut VirtualBus, cs: u8) {
    bus.send(frame(0x000, &[cs, ID]));
}

/// One SDO request and the server's answer.
fn sdo(bus: &mut VirtualBus, req: [u8; 8]) -> [u8; 8] {
    bus.send(frame(0x600 + u16::from(ID), &req));
    let answers: Vec<CanFrame> = bus.drain().into_iter().filter(|f| f.id == 0x580 + u16::from(ID)).collect();
    assert_eq!(answers.len(), 1, "one SDO answer: {answers:?}");
    answers[0].data
}

fn upload(bus: &mut VirtualBus, index: u16, sub: u8) -> Result<Vec<u8>, u32> {
    let [lo, hi] = index.to_le_bytes();
    let r = sdo(bus, [0x40, lo, hi, sub, 0, 0, 0, 0]);
    match r[0] {
        0x80 => Err(u32::from_le_bytes(r[4..8].try_into().unwrap())),
        c if c & 0xE2 == 0x42 => {
            let n = if c & 1 == 1 { 4 - usize::from(c >> 2 & 3) } else { 4 };
            Ok(r[4..4 + n].to_vec())
        }
        c if c & 0xE3 == 0x41 => {
            let size = u32::from_le_bytes(r[4..8].try_into().unwrap()) as usize;
            let mut out = Vec::new();
            let mut toggle = 0;
            while out.len() < size {
                let s = sdo(bus, [0x60 | toggle, 0, 0, 0, 0, 0, 0, 0]);
                assert_eq!(s[0] & 0xE0, 0x00, "upload segment");
                assert_eq!(s[0] & 0x10, toggle, "toggle");
                let n = 7 - usize::from(s[0] >> 1 & 7);
                out.extend_from_slice(&s[1..1 + n]);
                toggle ^= 0x10;
                if s[0] & 1 == 1 {
                    break;
                }
            }
            assert_eq!(out.len(), size);
            Ok(out)
        }
        c => panic!("unexpected upload answer {c:#04X}"),
    }
}

fn download(bus: &mut VirtualBus, index: u16, sub: u8, data: &[u8]) -> Result<(), u32> {
    assert!(data.len() <= 4, "expedited only");
    let [lo, hi] = index.to_le_bytes();
    let mut req = [0x23 | (4 - data.len() as u8) << 2, lo, hi, sub, 0, 0, 0, 0];
    req[4..4 + data.len()].copy_from_slice(data);
    let r = sdo(bus, req);
    match r[0] {
        0x60 => Ok(()),
        0x80 => Err(u32::from_le_bytes(r[4..8].try_into().unwrap())),
        c => panic!("unexpected download answer {c:#04X}"),
    }
}

fn u32_of(v: &[u8]) -> u32 {
    v.iter().rev().fold(0, |acc, &b| acc << 8 | u32::from(b))
}

#[test]
fn nmt_states_and_what_they_allow() {
    let mut bus = bus("co401gw1");
    assert_eq!(bus.nodes[0].node().state(), NmtState::PreOperational);
    nmt(&mut bus, 0x01);
    assert_eq!(bus.nodes[0].node().state(), NmtState::Operational);
    nmt(&mut bus, 0x02);
    assert_eq!(bus.nodes[0].node().state(), NmtState::Stopped);
    bus.send(frame(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]));
    assert!(bus.drain().is_empty(), "no SDO in Stopped");
    nmt(&mut bus, 0x80);
    assert_eq!(bus.nodes[0].node().state(), NmtState::PreOperational);
    bus.send(frame(0x000, &[0x01, ID + 1]));
    assert_eq!(bus.nodes[0].node().state(), NmtState::PreOperational, "addressed to another node");
    bus.send(frame(0x000, &[0x01, 0]));
    assert_eq!(bus.nodes[0].node().state(), NmtState::Operational, "broadcast");
    nmt(&mut bus, 0x82);
    assert_eq!(bus.drain(), vec![frame(0x705, &[0])], "reset communication boots again");
    assert_eq!(bus.nodes[0].node().state(), NmtState::PreOperational);
}

#[test]
fn sdo_reads_writes_and_aborts() {
    let mut bus = bus("co401gw1");
    assert_eq!(u32_of(&upload(&mut bus, 0x1000, 0).unwrap()), 0x000F_0191);
    assert_eq!(upload(&mut bus, 0x1008, 0).unwrap(), b"CO401GW1".to_vec(), "segmented upload");
    assert_eq!(download(&mut bus, 0x1000, 0, &[0, 0, 0, 0]), Err(0x0601_0002), "read-only");
    assert_eq!(upload(&mut bus, 0x1234, 0), Err(0x0602_0000), "no object");
    assert_eq!(upload(&mut bus, 0x1018, 9), Err(0x0609_0011), "no sub-index");
    assert_eq!(download(&mut bus, 0x1017, 0, &[1]), Err(0x0607_0013), "too short");
    assert_eq!(download(&mut bus, 0x2180, 0, &60000_u16.to_le_bytes()), Err(0x0609_0031), "above 50000");
    download(&mut bus, 0x1017, 0, &100_u16.to_le_bytes()).unwrap();
    assert_eq!(upload(&mut bus, 0x1017, 0).unwrap(), 100_u16.to_le_bytes().to_vec());
}

#[test]
fn heartbeat_every_period() {
    let mut bus = bus("co401gw1");
    download(&mut bus, 0x1017, 0, &100_u16.to_le_bytes()).unwrap();
    bus.drain();
    bus.advance_ms(1000);
    let beats: Vec<(u64, CanFrame)> = bus.log.iter().copied().filter(|(_, f)| f.id == 0x705 && f.data[0] == 0x7F).collect();
    assert_eq!(beats.len(), 10, "{beats:?}");
    let gaps: Vec<u64> = beats.windows(2).map(|w| w[1].0 - w[0].0).collect();
    assert!(gaps.iter().all(|&g| g == 100_000), "{gaps:?}");
}

#[test]
fn node_guarding_and_life_guarding_emcy() {
    let mut bus = bus("co401gw1");
    download(&mut bus, 0x100C, 0, &100_u16.to_le_bytes()).unwrap();
    download(&mut bus, 0x100D, 0, &[3]).unwrap();
    nmt(&mut bus, 0x01);
    bus.drain();
    let rtr = CanFrame::remote(0x705, 1).unwrap();
    bus.send(rtr);
    assert_eq!(bus.drain(), vec![frame(0x705, &[0x05])]);
    bus.send(rtr);
    assert_eq!(bus.drain(), vec![frame(0x705, &[0x85])], "toggle bit");
    bus.advance_ms(301);
    let emcy: Vec<CanFrame> = bus.drain().into_iter().filter(|f| f.id == 0x85).collect();
    assert_eq!(emcy, vec![frame(0x85, &[0x30, 0x81, 0x01, 0, 0, 0, 0, 0x30])], "life guarding error from the spec");
    assert_eq!(bus.nodes[0].node().state(), NmtState::PreOperational, "1029 sub 1 = 0: operational -> pre-operational");
    assert_eq!(upload(&mut bus, 0x1001, 0).unwrap(), vec![0x01]);
    bus.send(rtr);
    let after: Vec<CanFrame> = bus.drain();
    assert!(after.contains(&frame(0x85, &[0, 0, 0, 0, 0, 0, 0, 0])), "error reset: {after:?}");
    assert_eq!(upload(&mut bus, 0x1001, 0).unwrap(), vec![0x00]);
}

#[test]
fn tpdo_remapping_and_transmission_types() {
    let mut bus = bus("co401gw1");
    // Remap TPDO1 (1800h/1A00h) to 6000h.1 + 6000h.2, synchronous every 2nd SYNC.
    let cob = u32_of(&upload(&mut bus, 0x1800, 1).unwrap());
    assert_eq!(cob & 0x7FF, 0x185);
    assert_eq!(download(&mut bus, 0x1A00, 0, &[0]), Err(0x0800_0022), "mapping while the PDO is valid");
    download(&mut bus, 0x1800, 1, &(cob | 0x8000_0000).to_le_bytes()).unwrap();
    download(&mut bus, 0x1A00, 0, &[0]).unwrap();
    download(&mut bus, 0x1A00, 1, &0x6000_0108_u32.to_le_bytes()).unwrap();
    download(&mut bus, 0x1A00, 2, &0x6000_0208_u32.to_le_bytes()).unwrap();
    assert_eq!(download(&mut bus, 0x1A00, 3, &0x1000_0020_u32.to_le_bytes()), Err(0x0604_0041), "1000h is not mappable");
    download(&mut bus, 0x1A00, 0, &[2]).unwrap();
    download(&mut bus, 0x1800, 2, &[2]).unwrap();
    download(&mut bus, 0x1800, 1, &cob.to_le_bytes()).unwrap();
    nmt(&mut bus, 0x01);
    bus.drain();
    // 6000h.2: 6000h.1 is the chip's IN0..IN7 (hardware inputs enabled).
    bus.nodes[0].node_mut().write(0x6000, 2, &[0xAB], coforge_stack::od::Side::Device).unwrap();
    let sync = frame(0x080, &[]);
    bus.send(sync);
    assert!(bus.drain().is_empty(), "first SYNC of two");
    bus.send(sync);
    assert_eq!(bus.drain(), vec![frame(0x185, &[0x00, 0xAB])]);
}

#[test]
fn expedited_download_without_size_takes_the_entry_size() {
    let mut bus = bus("co401gw1");
    // 0x22: expedited, size not indicated; 1017h is UNSIGNED16, so 2 of the 4 bytes count.
    assert_eq!(sdo(&mut bus, [0x22, 0x17, 0x10, 0, 0x34, 0x12, 0, 0])[0], 0x60);
    assert_eq!(upload(&mut bus, 0x1017, 0).unwrap(), vec![0x34, 0x12]);
    // An explicit size of 4 is still checked against the 2-byte entry.
    assert_eq!(sdo(&mut bus, [0x23, 0x17, 0x10, 0, 0x34, 0x12, 0, 0])[0], 0x80, "size 4 given for a 2-byte entry");
}

#[test]
fn stored_parameters_survive_reset_and_restore_brings_defaults_back() {
    let mut bus = bus("co401gw1");
    download(&mut bus, 0x100C, 0, &500_u16.to_le_bytes()).unwrap();
    assert_eq!(download(&mut bus, 0x1010, 1, b"SAVE"), Err(0x0800_0020), "wrong signature");
    download(&mut bus, 0x1010, 1, b"save").unwrap();
    download(&mut bus, 0x100C, 0, &700_u16.to_le_bytes()).unwrap();
    nmt(&mut bus, 0x81);
    bus.drain();
    assert_eq!(upload(&mut bus, 0x100C, 0).unwrap(), 500_u16.to_le_bytes().to_vec(), "the stored value, not the last one");
    download(&mut bus, 0x1011, 1, b"load").unwrap();
    assert_eq!(upload(&mut bus, 0x100C, 0).unwrap(), 500_u16.to_le_bytes().to_vec(), "restore takes effect at the next reset");
    nmt(&mut bus, 0x81);
    bus.drain();
    assert_eq!(upload(&mut bus, 0x100C, 0).unwrap(), vec![0, 0], "spec default");
}

#[test]
fn a_save_after_a_restore_keeps_the_store_erased_until_the_next_reset() {
    // CO401GW1 1010h: "If the save command is done after a restore procedure, a previously
    // saved dictionary is deleted, so the chip will start with default data."
    let mut bus = bus("co401gw1");
    download(&mut bus, 0x100C, 0, &500_u16.to_le_bytes()).unwrap();
    download(&mut bus, 0x1010, 1, b"save").unwrap();
    download(&mut bus, 0x1011, 1, b"load").unwrap();
    download(&mut bus, 0x100C, 0, &600_u16.to_le_bytes()).unwrap();
    download(&mut bus, 0x1010, 1, b"save").unwrap();
    nmt(&mut bus, 0x81);
    bus.drain();
    assert_eq!(upload(&mut bus, 0x100C, 0).unwrap(), vec![0, 0], "neither 500 nor 600 was kept: defaults");
    // After that reset the dictionary shows the defaults again, and saving works as before.
    download(&mut bus, 0x100C, 0, &700_u16.to_le_bytes()).unwrap();
    download(&mut bus, 0x1010, 1, b"save").unwrap();
    nmt(&mut bus, 0x81);
    bus.drain();
    assert_eq!(upload(&mut bus, 0x100C, 0).unwrap(), 700_u16.to_le_bytes().to_vec(), "saved after the reset");
    // A reset of communication does not end a pending restore: the application entries
    // (2180h) still show the values the restore discarded.
    download(&mut bus, 0x2180, 0, &1234_u16.to_le_bytes()).unwrap();
    download(&mut bus, 0x1010, 1, b"save").unwrap();
    download(&mut bus, 0x1011, 1, b"load").unwrap();
    nmt(&mut bus, 0x82);
    bus.drain();
    assert_eq!(upload(&mut bus, 0x2180, 0).unwrap(), 1234_u16.to_le_bytes().to_vec(), "not reloaded by reset communication");
    download(&mut bus, 0x1010, 1, b"save").unwrap();
    nmt(&mut bus, 0x81);
    bus.drain();
    assert_eq!(upload(&mut bus, 0x2180, 0).unwrap(), 1000_u16.to_le_bytes().to_vec(), "2180h default, not the discarded 1234");
}

fn emcy_frames(bus: &mut VirtualBus) -> Vec<[u8; 8]> {
    bus.drain().into_iter().filter(|f| f.id == 0x80 + u16::from(ID)).map(|f| f.data).collect()
}

#[test]
fn sync_cycle_monitoring_from_1006() {
    let mut bus = bus("cr3101");
    download(&mut bus, 0x1006, 0, &100_000_u32.to_le_bytes()).unwrap();
    bus.drain();
    bus.advance_ms(500);
    assert!(emcy_frames(&mut bus).is_empty(), "monitoring starts with the first SYNC");
    bus.send(frame(0x080, &[]));
    bus.advance_ms(150);
    assert!(emcy_frames(&mut bus).is_empty(), "within 1.5 cycles");
    bus.advance_ms(1);
    assert_eq!(emcy_frames(&mut bus), vec![[0x00, 0x81, 0x11, 0, 0, 0, 0, 0]], "SYNC timeout");
    bus.advance_ms(500);
    assert!(emcy_frames(&mut bus).is_empty(), "reported once");
    bus.send(frame(0x080, &[]));
    assert_eq!(emcy_frames(&mut bus), vec![[0, 0, 0, 0, 0, 0, 0, 0]], "the next SYNC resets the error");
}

/// CO401GW1's dictionary as a plain node with CiA 301 4.2 RPDO deadline monitoring switched on
/// and its CiA 301 emergency (the chip has neither: errata GW1-13, GW1-59), to check the
/// stack's monitor.
fn gw1_with_rpdo_deadlines() -> Box<dyn SimDevice> {
    use coforge_sim::app::RamApp;
    use coforge_stack::store::NoStore;
    let config = coforge_stack::node::NodeConfig { rpdo_deadlines: true, listed_emergencies_only: false, ..co401gw1::node_config(ID) };
    let od = co401gw1::Od::new(co401gw1::Mode::ALL[0], ID, RamApp::default());
    let node: co401gw1::Node<RamApp, NoStore> = coforge_stack::node::Node::new(od, NoStore, config);
    Box::new(node)
}

#[test]
fn rpdo_deadline_monitoring_from_its_event_timer() {
    let mut bus = VirtualBus::new(vec![gw1_with_rpdo_deadlines()]);
    bus.drain();
    download(&mut bus, 0x1400, 5, &50_u16.to_le_bytes()).unwrap();
    nmt(&mut bus, 0x01);
    bus.drain();
    bus.advance_ms(200);
    assert!(emcy_frames(&mut bus).is_empty(), "monitoring starts with the first RPDO");
    bus.send(frame(0x205, &[0; 8]));
    bus.advance_ms(50);
    assert!(emcy_frames(&mut bus).is_empty());
    bus.advance_ms(1);
    assert_eq!(emcy_frames(&mut bus), vec![[0x50, 0x82, 0x11, 0, 0, 0, 0, 0]], "RPDO timeout 8250h");
    bus.send(frame(0x205, &[0; 8]));
    assert_eq!(emcy_frames(&mut bus), vec![[0, 0, 0, 0, 0, 0, 0, 0]], "the next RPDO resets the error");
}

#[test]
fn ds301_4_0_devices_do_not_monitor_rpdo_deadlines() {
    for device in ["co401gw1", "co401memory1"] {
        let mut bus = started(device);
        bus.drain();
        download(&mut bus, 0x1400, 5, &50_u16.to_le_bytes()).unwrap();
        nmt(&mut bus, 0x01);
        bus.send(frame(0x205, &[0x91, 0x91, 0, 0, 0, 0, 0, 0][..if device == "co401gw1" { 8 } else { 2 }]));
        bus.drain();
        bus.advance_ms(500);
        let late = emcy_frames(&mut bus);
        assert!(!late.iter().any(|f| f[..2] == [0x50, 0x82]), "{device}: no 8250h (errata GW1-13, MEM-27): {late:02x?}");
    }
}

#[test]
fn boot_up_message_can_be_switched_off_by_2110() {
    let mut bus = bus("co401gw1");
    download(&mut bus, 0x2110, 0, &[0]).unwrap();
    nmt(&mut bus, 0x82);
    assert!(bus.drain().is_empty(), "no boot-up with 2110h = 0");
    assert_eq!(bus.nodes[0].node().state(), NmtState::PreOperational);
    download(&mut bus, 0x2110, 0, &[1]).unwrap();
    nmt(&mut bus, 0x82);
    assert_eq!(bus.drain(), vec![frame(0x705, &[0])]);
}

#[test]
fn bus_off_restart_and_return_emergency() {
    use coforge_stack::leds::LedState;
    use coforge_stack::node::{BusState, NodeEvent};
    let mut bus = bus("co401gw1");
    download(&mut bus, 0x1017, 0, &100_u16.to_le_bytes()).unwrap();
    nmt(&mut bus, 0x01);
    bus.drain();
    while bus.nodes[0].take_event().is_some() {}
    let now = bus.now_us();
    bus.nodes[0].on_bus_state(BusState::BusOff, now);
    assert_eq!(bus.nodes[0].node().state(), NmtState::PreOperational, "1029h sub 1 = 0: a communication error leaves Operational");
    assert_eq!(bus.nodes[0].leds().error, LedState::On, "CiA 303-3: bus-off lights the error LED");
    bus.advance_ms(999);
    assert!(bus.drain().is_empty(), "nothing is sent while bus-off");
    assert_eq!(bus.nodes[0].take_event(), Some(NodeEvent::StateChanged(NmtState::PreOperational)));
    assert_eq!(bus.nodes[0].take_event(), None, "restart only after 2180h = 1000 ms");
    bus.advance_ms(1);
    assert_eq!(bus.nodes[0].take_event(), Some(NodeEvent::RestartController));
    let now = bus.now_us();
    bus.nodes[0].on_bus_state(BusState::Active, now);
    bus.advance_ms(1);
    let emcy = emcy_frames(&mut bus);
    assert_eq!(emcy[0], [0x40, 0x81, 0x01, 0, 0, 0, 0, 0xC0], "the datasheet's return-from-bus-off frame: {emcy:02X?}");
    assert_eq!(emcy[1], [0, 0, 0, 0, 0, 0, 0, 0], "then error reset");
    assert_eq!(bus.nodes[0].leds().error, LedState::Off);
    assert_eq!(bus.nodes[0].leds().run, LedState::Blinking, "pre-operational");
    let now = bus.now_us();
    bus.nodes[0].on_bus_state(BusState::Warning, now);
    bus.advance_ms(1);
    assert_eq!(emcy_frames(&mut bus), vec![[0x00, 0x81, 0x01, 0, 0, 0, 0, 0x40]], "spec can_warning emergency");
    assert_eq!(bus.nodes[0].leds().error, LedState::SingleFlash);
}

#[test]
fn timers_near_the_end_of_the_clock_do_not_overflow() {
    use coforge_stack::od::Side;
    let mut n = node("co401gw1");
    let t = u64::MAX - 1_000;
    n.start(t);
    n.console("enable").unwrap();
    n.node_mut().write(0x1017, 0, &100_u16.to_le_bytes(), Side::Bus).unwrap();
    n.node_mut().write(0x1800, 5, &10_u16.to_le_bytes(), Side::Bus).unwrap();
    n.node_mut().write(0x1400, 5, &10_u16.to_le_bytes(), Side::Bus).unwrap();
    n.on_frame(&frame(0x000, &[0x01, ID]), t);
    n.on_frame(&frame(0x205, &[0; 8]), t);
    n.node_mut().trigger_tpdo(1);
    let mut sent = 0;
    // Deadlines saturate at u64::MAX (584 000 years of microseconds) instead of overflowing.
    for now in [t, t + 500] {
        while n.poll(now).is_some() {
            sent += 1;
        }
    }
    assert!(sent >= 2, "boot-up and the TPDO go out ({sent})");
    assert_eq!(n.node().state(), NmtState::Operational);
}

#[test]
fn the_registry_names_devices_modes_and_spec_emergencies() {
    let create = |device: &str, mode: Option<&str>, id: u8| DeviceKind::find(device).and_then(|k| k.create(mode, id, &StoreAt::Memory)).err();
    assert_eq!(create("co401gw2", None, ID).unwrap(), "unknown device `co401gw2`; known devices: co401memory1, co401gw1, cr3101, canopenia");
    assert_eq!(create("co401gw1", Some("analog"), ID).unwrap(), "co401gw1 has no mode `analog`; its modes are: mixed, digital, digital_alt");
    assert_eq!(create("co401memory1", Some("mixed"), ID).unwrap(), "co401memory1 has no mode `mixed`; its modes are: default");
    assert_eq!(create("cr3101", None, 0).unwrap(), "node-ID 0 is outside 1..=127");
    assert_eq!(create("co401memory1", None, 0).unwrap(), "node-ID 0 is outside 1..=127");
    assert_eq!(create("cr3101", None, 128).unwrap(), "node-ID 128 is outside 1..=127");
    // CO401GW1's ID pins all high: the host programs the node-ID (100Bh) before enable.
    assert_eq!(create("co401gw1", None, 0), None);
    assert_eq!(create("co401gw1", Some("digital"), ID), None);

    let mut bus = bus("co401gw1");
    assert!(coforge_sim::devices::raise(&mut *bus.nodes[0], "application_emergency_0"));
    bus.advance_ms(1);
    assert_eq!(emcy_frames(&mut bus), vec![[0x10, 0x23, 0x01, 0, 0x01, 0, 0, 0]], "the spec's frame");
    assert!(coforge_sim::devices::clear(&mut *bus.nodes[0], "application_emergency_0"));
    bus.advance_ms(1);
    assert_eq!(emcy_frames(&mut bus), vec![[0; 8]], "error reset");
    assert!(!coforge_sim::devices::raise(&mut *bus.nodes[0], "no_such_emergency"));
}
