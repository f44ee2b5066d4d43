//! A node before its CAN side is enabled (CO401GW1: the host enables it with a serial command
//! after configuring it): silent on the bus, host rules "before the CAN interface is enabled"
//! apply, what the host wrote survives the enable, and the mode is chosen at that moment.

use co401gw1::{Mode, Node, index};
use coforge_stack::device::{Device, NodeAccess};
use coforge_stack::frame::CanFrame;
use coforge_stack::node::read_u32;
use coforge_stack::od::{NoAppObjects, SdoAbort, Side};
use coforge_stack::store::NoStore;

fn node(mode: Mode) -> Node<NoAppObjects, NoStore> {
    Node::of_dictionary(mode, 5, NoAppObjects, NoStore)
}

fn drain(n: &mut Node<NoAppObjects, NoStore>, now: u64) -> Vec<CanFrame> {
    std::iter::from_fn(|| n.poll(now)).collect()
}

#[test]
fn before_enable_the_node_is_silent_and_the_host_configures_it() {
    let mut n = node(Mode::Digital);
    n.power_on(0);
    assert!(!n.can_enabled());
    // Nothing is sent, and an SDO request gets no answer.
    n.on_frame(&CanFrame::data(0x605, &[0x40, 0x00, 0x10, 0, 0, 0, 0, 0]).unwrap(), 1_000);
    assert!(drain(&mut n, 2_000_000).is_empty());
    // 100Bh and 1018h.4 are host-writable only now.
    assert_eq!(n.write(index::NODE_ID, 0, &[9], Side::Host), Ok(()));
    assert_eq!(n.write(index::IDENTITY_OBJECT, 4, &0x1234_u32.to_le_bytes(), Side::Host), Ok(()));
    n.enable_can(Mode::DigitalAlt, 3_000_000);
    assert!(n.can_enabled());
    assert_eq!(NodeAccess::mode_name(&n), "digital_alt");
    // Boot-up at once, in the mode chosen at enable.
    assert_eq!(drain(&mut n, 3_000_000).first().map(|f| (f.id, f.payload().to_vec())), Some((0x705, vec![0])));
    assert_eq!(read_u32(n.od_mut(), 0x1404, 1), Some(0x305), "RPDO5 at the digital_alt default");
    // What the host wrote before is kept; now the same writes are refused.
    assert_eq!(read_u32(n.od_mut(), index::NODE_ID, 0), Some(9));
    assert_eq!(read_u32(n.od_mut(), index::IDENTITY_OBJECT, 4), Some(0x1234));
    assert_eq!(n.write(index::NODE_ID, 0, &[10], Side::Host), Err(SdoAbort::DataTransferState));
    assert_eq!(n.write(index::IDENTITY_OBJECT, 4, &[0; 4], Side::Host), Err(SdoAbort::DataTransferState));
    // A second enable changes nothing.
    n.enable_can(Mode::Digital, 4_000_000);
    assert_eq!(NodeAccess::mode_name(&n), "digital_alt");
}

#[test]
fn start_is_power_on_and_enable_in_the_dictionarys_mode() {
    let mut n = node(Mode::Mixed);
    Device::start(&mut n, 0);
    assert!(n.can_enabled());
    assert_eq!(drain(&mut n, 0).first().map(|f| f.id), Some(0x705));
    assert_eq!(n.write(index::NODE_ID, 0, &[9], Side::Host), Err(SdoAbort::DataTransferState));
    // Before power-on, enable does nothing.
    let mut cold = node(Mode::Mixed);
    cold.enable_can(Mode::Mixed, 0);
    assert!(!cold.can_enabled());
    assert!(drain(&mut cold, 0).is_empty());
}
