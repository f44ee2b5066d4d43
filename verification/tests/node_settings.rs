//! The spec's `node:` settings through a generated node: CO401GW1's dictionary, emergencies
//! and PDOs, with each setting switched on and off explicitly (whatever its spec chooses), so
//! the difference is the setting's alone.

use co401gw1::IoImage;
use co401gw1::app::Typed;
use coforge_stack::frame::CanFrame;
use coforge_stack::node::{BusState, NodeConfig, read_u32};
use coforge_stack::od::{SdoAbort, Side};
use coforge_stack::store::NoStore;

const ID: u8 = 5;

/// The chip's dictionary over its own process image (6000h..6320h are app-backed).
type Gw1 = co401gw1::Node<Typed<IoImage>, NoStore>;

/// A started CO401GW1 node in its first mode with `cfg`, its boot-up taken.
fn gw1(cfg: impl FnOnce(NodeConfig) -> NodeConfig) -> Gw1 {
    let od = co401gw1::Od::new(co401gw1::Mode::ALL[0], ID, Typed(IoImage::default()));
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
    assert_eq!(n.write(0x6000, 1, &[0xA5], Side::Device), Ok(()));
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

/// An expedited SDO download from the bus: `Err` with the abort code if refused.
fn download(n: &mut Gw1, index: u16, sub: u8, value: &[u8]) -> Result<(), u32> {
    let [lo, hi] = index.to_le_bytes();
    let mut request = [0x23 | ((4 - value.len() as u8) << 2), lo, hi, sub, 0, 0, 0, 0];
    request[4..4 + value.len()].copy_from_slice(value);
    n.on_frame(&CanFrame::data(0x600 + u16::from(ID), &request).unwrap(), 0);
    let answer = drain(n, 0).into_iter().find(|f| f.id == 0x580 + u16::from(ID)).expect("an SDO answer");
    match answer.data[0] {
        0x60 => Ok(()),
        0x80 => Err(u32::from_le_bytes(answer.data[4..8].try_into().unwrap())),
        other => panic!("SDO answer {other:02X}"),
    }
}

/// The remapping procedure for TPDO1 over SDO, with 2102h "Remapping Enabled Info" set to
/// `enabled` by the host first: the first refused step's abort code, if any.
fn remap_tpdo1(remapping_object: Option<u16>, enabled: u8) -> Result<(), u32> {
    let mut n = gw1(|c| NodeConfig { remapping_object, ..c });
    assert_eq!(n.write(0x2102, 0, &[enabled], Side::Host), Ok(()));
    download(&mut n, 0x1800, 1, &(0x8000_0180_u32 + u32::from(ID)).to_le_bytes())?;
    download(&mut n, 0x1A00, 0, &[0])?;
    download(&mut n, 0x1A00, 1, &0x6000_0108_u32.to_le_bytes())?;
    download(&mut n, 0x1A00, 0, &[1])?;
    download(&mut n, 0x1800, 1, &(0x180_u32 + u32::from(ID)).to_le_bytes())
}

#[test]
fn the_remapping_object_at_0_refuses_every_mapping_write() {
    assert_eq!(remap_tpdo1(Some(0x2102), 0), Err(0x0800_0021), "local control: remapping disabled");
    assert_eq!(remap_tpdo1(Some(0x2102), 1), Ok(()));
    assert_eq!(remap_tpdo1(Some(0x2102), 255), Ok(()));
    assert_eq!(remap_tpdo1(None, 0), Ok(()), "without the setting 2102h means nothing to the stack");
    // The device and the host are refused as well, and nothing changes.
    let mut n = gw1(|c| NodeConfig { remapping_object: Some(0x2102), ..c });
    assert_eq!(n.write(0x2102, 0, &[0], Side::Host), Ok(()));
    let before = read_u32(n.od_mut(), 0x1600, 1);
    for side in [Side::Host, Side::Device] {
        assert_eq!(n.write(0x1600, 1, &0x6200_0208_u32.to_le_bytes(), side), Err(SdoAbort::DataTransferLocal), "{side:?}");
        assert_eq!(n.write(0x1A00, 0, &[0], side), Err(SdoAbort::DataTransferLocal), "{side:?}");
    }
    assert_eq!(read_u32(n.od_mut(), 0x1600, 1), before);
    assert_eq!(read_u32(n.od_mut(), 0x1A00, 0), Some(8));
}
