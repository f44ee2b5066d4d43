//! The spec's `node:` settings through a generated node: CO401GW1's dictionary, emergencies
//! and PDOs, with each setting switched on and off explicitly (whatever its spec chooses), so
//! the difference is the setting's alone.

use coforge_stack::frame::CanFrame;
use coforge_stack::node::{BusState, NodeConfig};
use coforge_stack::od::NoAppObjects;
use coforge_stack::store::NoStore;

const ID: u8 = 5;

type Gw1 = co401gw1::Node<NoAppObjects, NoStore>;

/// A started CO401GW1 node in its first mode with `cfg`, its boot-up taken.
fn gw1(cfg: impl FnOnce(NodeConfig) -> NodeConfig) -> Gw1 {
    let od = co401gw1::Od::new(co401gw1::Mode::ALL[0], ID, NoAppObjects);
    let mut n: Gw1 = coforge_stack::node::Node::new(od, NoStore, cfg(co401gw1::node_config(ID)));
    n.start(0);
    drain(&mut n, 0);
    n
}

fn drain(n: &mut Gw1, now: u64) -> Vec<CanFrame> {
    std::iter::from_fn(|| n.poll(now)).collect()
}

fn emergencies(frames: &[CanFrame]) -> Vec<[u8; 8]> {
    frames.iter().filter(|f| f.id == 0x80 + u16::from(ID)).map(|f| f.data).collect()
}

/// Operational, CAN passive (the spec lists no emergency for it), a too short RPDO1 (none
/// either), then a CAN warning (listed: "can_error_warning"): the emergencies sent.
fn unlisted_then_listed(listed_only: bool) -> Vec<[u8; 8]> {
    let mut n = gw1(|c| NodeConfig { listed_emergencies_only: listed_only, ..c });
    n.on_frame(&CanFrame::data(0x000, &[0x01, ID]).unwrap(), 0);
    n.on_bus_state(BusState::Passive, 1_000);
    n.on_frame(&CanFrame::data(0x200 + u16::from(ID), &[0x00]).unwrap(), 2_000);
    n.on_bus_state(BusState::Active, 3_000);
    n.on_bus_state(BusState::Warning, 4_000);
    emergencies(&drain(&mut n, 4_000))
}

#[test]
fn listed_emergencies_only_leaves_out_the_cia_301_defaults() {
    let all = unlisted_then_listed(false);
    assert!(all.contains(&[0x20, 0x81, 0x11, 0, 0, 0, 0, 0]), "CAN passive 8120h by default: {all:02X?}");
    assert!(all.contains(&[0x10, 0x82, 0x11, 0, 0, 0, 0, 0]), "RPDO length 8210h by default: {all:02X?}");
    assert_eq!(all.last(), Some(&[0x00, 0x81, 0x11, 0, 0, 0, 0, 0x40]), "the warning, with the RPDO length error's communication bit still set");
    assert_eq!(unlisted_then_listed(true), [[0x00, 0x81, 0x01, 0, 0, 0, 0, 0x40]], "only the spec's own emergency, and no bit of an unlisted one");
}

/// Operational at `now`; the TPDO1 payloads (digital input bytes 6000h.1..8) sent after a
/// device write of input byte 0, and after the device's own trigger of 6000h.1.
fn tpdo1_after_write_and_trigger(on_write: bool) -> (Vec<Vec<u8>>, Vec<Vec<u8>>) {
    let mut n = gw1(|c| NodeConfig { tpdo_on_write: on_write, ..c });
    n.on_frame(&CanFrame::data(0x000, &[0x01, ID]).unwrap(), 1_000);
    drain(&mut n, 1_000);
    let tpdo1 = |frames: Vec<CanFrame>| -> Vec<Vec<u8>> { frames.iter().filter(|f| f.id == 0x180 + u16::from(ID)).map(|f| f.payload().to_vec()).collect() };
    assert_eq!(n.write(0x6000, 1, &[0xA5], coforge_stack::od::Side::Device), Ok(()));
    let after_write = tpdo1(drain(&mut n, 2_000));
    n.trigger_mapped(0x6000, 1);
    let after_trigger = tpdo1(drain(&mut n, 3_000));
    (after_write, after_trigger)
}

#[test]
fn tpdo_on_write_off_leaves_the_tpdos_to_the_device() {
    let inputs = vec![0xA5, 0, 0, 0, 0, 0, 0, 0];
    assert_eq!(tpdo1_after_write_and_trigger(true), (vec![inputs.clone()], vec![inputs.clone()]), "CiA 301: the write triggers TPDO1");
    assert_eq!(tpdo1_after_write_and_trigger(false), (vec![], vec![inputs]), "only Node::trigger_mapped sends it");
}
