//! What a generated node tells its device code (`Node::take_event`): CO401GW1's node reports
//! every NMT command addressed to it and every emergency it queues, with the frame's bytes.

use coforge_stack::frame::CanFrame;
use coforge_stack::nmt::NmtState;
use coforge_stack::node::{BusState, NodeEvent};
use coforge_stack::od::NoAppObjects;
use coforge_stack::store::NoStore;

const ID: u8 = 5;

type Gw1 = co401gw1::Node<NoAppObjects, NoStore>;

fn events(n: &mut Gw1) -> Vec<NodeEvent> {
    std::iter::from_fn(|| n.take_event()).collect()
}

fn drain(n: &mut Gw1, now: u64) -> Vec<CanFrame> {
    std::iter::from_fn(|| n.poll(now)).collect()
}

#[test]
fn nmt_commands_and_emergencies_reach_the_device_code() {
    let mut n: Gw1 = Gw1::of_dictionary(co401gw1::Mode::ALL[0], ID, NoAppObjects, NoStore);
    n.start(0);
    drain(&mut n, 0);
    events(&mut n);
    n.on_frame(&CanFrame::data(0x000, &[0x01, 0]).unwrap(), 1_000);
    n.on_frame(&CanFrame::data(0x000, &[0x02, ID + 1]).unwrap(), 1_000);
    n.on_frame(&CanFrame::data(0x000, &[0x80, ID]).unwrap(), 1_000);
    assert_eq!(
        events(&mut n),
        [
            NodeEvent::NmtReceived(0x01),
            NodeEvent::StateChanged(NmtState::Operational),
            NodeEvent::NmtReceived(0x80),
            NodeEvent::StateChanged(NmtState::PreOperational),
        ],
        "start all, (stop for node 6), enter pre-operational"
    );
    // The spec's CAN warning, then the error reset when the controller is active again.
    n.on_bus_state(BusState::Warning, 2_000);
    n.on_bus_state(BusState::Active, 3_000);
    let sent: Vec<[u8; 8]> = drain(&mut n, 3_000).iter().filter(|f| f.id == 0x80 + u16::from(ID)).map(|f| f.data).collect();
    assert_eq!(sent, [[0x00, 0x81, 0x01, 0, 0, 0, 0, 0x40], [0; 8]]);
    let reported: Vec<NodeEvent> = sent.iter().map(|&data| NodeEvent::EmergencySent(data)).collect();
    assert_eq!(events(&mut n), reported);
}
