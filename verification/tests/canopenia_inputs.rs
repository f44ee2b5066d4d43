//! CANopenIA under arbitrary input on both of its inputs, with proptest: host bytes at random
//! times (whole frames of the protocol, with any start byte, mixed with garbage) and CAN
//! frames (its own identifiers and its manager's weighted up). The invariants are
//! `coforge_verification::canopenia::check` (cargo fuzz checks the same on raw bytes).

use coforge_verification::canopenia::{Input, NODE, check, decode};
use proptest::prelude::*;

/// A valid command frame (W, R, S, U to the coprocessor or node 3) in any start-byte form,
/// as host bytes, or a run of garbage.
fn host_bytes() -> impl Strategy<Value = Vec<Input>> {
    let start = prop::sample::select(vec![0x11_u8, 0x01, 0x21, 0x31, 0x12]);
    let letter = prop::sample::select(vec![b'W', b'R', b'S', b'U', b'D', b'X']);
    let index = prop::sample::select(vec![0x1000_u16, 0x1017, 0x1018, 0x5F00, 0x5F01, 0x5F0A, 0x6000, 0x6200, 0x1F51, 0x2345]);
    let frame = (start, letter, index, 0..6_u8, prop::collection::vec(any::<u8>(), 0..8)).prop_map(|(start, letter, index, sub, data)| {
        let mut payload = vec![letter];
        if matches!(letter, b'S' | b'U') {
            payload.push(if sub % 2 == 0 { NODE as u8 } else { 3 });
        }
        payload.extend(index.to_le_bytes());
        payload.push(sub);
        payload.extend(data);
        let mut frame = vec![start];
        let length = (payload.len() as u16).to_le_bytes();
        frame.extend(if start & 0x20 != 0 { &length[..] } else { &length[..1] });
        frame.extend(&payload);
        if start & 0x10 != 0 {
            let crc = coforge_link::crc::CCITT.checksum(&frame[1..]);
            frame.extend(crc.to_le_bytes());
        }
        frame
    });
    let bytes = prop_oneof![4 => frame, 1 => prop::collection::vec(any::<u8>(), 1..20)];
    (bytes, prop_oneof![3 => Just(0_u32), 1 => 0..70_u32])
        .prop_map(|(bytes, gap)| bytes.into_iter().enumerate().map(|(i, byte)| Input::Host { byte, gap_ms: if i == 0 { gap } else { 0 } }).collect())
}

fn can() -> impl Strategy<Value = Vec<Input>> {
    let id = prop_oneof![Just(0x000), Just(0x600 + NODE), Just(0x200 + NODE), Just(0x583), Just(0x703), Just(0x183), Just(0x083), 0..0x800_u16];
    (id, any::<bool>(), any::<[u8; 8]>(), 0..=8_u8).prop_map(|(id, rtr, data, len)| vec![Input::Can { id, rtr: rtr && id != 0x583, data, len }])
}

fn inputs() -> impl Strategy<Value = Vec<Input>> {
    let time = (0..1600_u32).prop_map(|ms| vec![Input::Time { ms }]);
    prop::collection::vec(prop_oneof![5 => host_bytes(), 4 => can(), 1 => time], 1..60).prop_map(|runs| runs.into_iter().flatten().collect())
}

fn host(bytes: &[u8]) -> Vec<Input> {
    bytes.iter().map(|&byte| Input::Host { byte, gap_ms: 0 }).collect()
}

/// The checker reads what the coprocessor says: a read of 6000h.1 (the manual's frame) and
/// the indication of a bus write are two frames; a frame the host cannot read would fail it.
#[test]
fn the_checker_reads_answers_and_indications() {
    let mut inputs = host(&[0x11, 0x04, 0x52, 0x00, 0x10, 0x00, 0x26, 0x12]);
    inputs.push(Input::Can { id: 0x600 + NODE, rtr: false, data: [0x2F, 0x00, 0x62, 0x01, 0x05, 0, 0, 0], len: 8 });
    // At start the coprocessor indicates its own node-ID, state and hardware state.
    assert_eq!(check(false, true, inputs.clone()), 3 + 2);
    assert_eq!(check(false, false, inputs), 3 + 1, "without frames: the R answer only");
    // Raw bytes (cargo fuzz): AUTORUN and frames on, 0 ms pass, a heartbeat of node 3.
    let (autorun, with_can, raw) = decode(&[0b101, 0x07, 0x05, 0x17, 0x03, 0x05]).unwrap();
    assert_eq!((autorun, with_can), (true, true));
    assert_eq!(raw.collect::<Vec<_>>(), [Input::Time { ms: 0 }, Input::Can { id: 0x703, rtr: false, data: [0x05, 0, 0, 0, 0, 0, 0, 0], len: 1 }]);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn host_bytes_write_only_what_the_rules_allow(autorun in any::<bool>(), inputs in inputs()) {
        check(autorun, false, inputs);
    }

    #[test]
    fn host_and_bus_together_never_write_what_neither_may(autorun in any::<bool>(), inputs in inputs()) {
        check(autorun, true, inputs);
    }
}
