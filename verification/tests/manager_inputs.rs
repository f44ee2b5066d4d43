//! coforge-stack's manager under arbitrary traffic and caller requests, with proptest: frames
//! on the caller's server, heartbeat, emergency, NMT and other identifiers, uploads and
//! downloads, scans and time. The invariants are `coforge_verification::manager::check`
//! (cargo fuzz checks the same on raw bytes).

use coforge_verification::manager::{Input, SERVER, check, decode};
use proptest::prelude::*;

fn input() -> impl Strategy<Value = Input> {
    let server = 0x580 + u16::from(SERVER);
    let id = prop_oneof![4 => Just(server), 1 => 0x700..0x780_u16, 1 => 0x080..0x100_u16, 1 => 0x580..0x600_u16, 1 => 0..0x800_u16];
    // Server command bytes of every kind, so that transfers get far.
    let b0 = prop_oneof![prop::sample::select(vec![0x43_u8, 0x4F, 0x41, 0x42, 0x60, 0x00, 0x01, 0x10, 0x11, 0x0B, 0x20, 0x30, 0x80]), any::<u8>()];
    let frame = (id, any::<bool>(), b0, any::<[u8; 7]>(), prop_oneof![4 => Just(8_u8), 1 => 0..=8_u8]).prop_map(move |(id, rtr, b0, rest, len)| {
        let mut data = [b0, 0, 0, 0, 0, 0, 0, 0];
        data[1..].copy_from_slice(&rest);
        Input::Frame { id, rtr: rtr && id != server, data, len }
    });
    let index = prop_oneof![Just(0x1000_u16), Just(0x1018), any::<u16>()];
    let upload = (index.clone(), 0..5_u8).prop_map(|(index, sub)| Input::Upload { index, sub });
    let download = (index, 0..5_u8, 0..20_u8).prop_map(|(index, sub, len)| Input::Download { index, sub, len });
    let scan = any::<u8>().prop_map(|node| Input::Scan { node });
    let time = (0..400_u32).prop_map(|ms| Input::Time { ms });
    prop_oneof![8 => frame, 2 => upload, 2 => download, 1 => scan, 2 => time]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn the_manager_sends_only_valid_frames_and_completes_only_on_an_answer(inputs in prop::collection::vec(input(), 1..300)) {
        check(inputs);
    }
}

/// The raw bytes cargo fuzz hands to `prop_manager_inputs` decode into these inputs.
#[test]
fn raw_bytes_decode_into_inputs() {
    let bytes = [0x40, 0x00, 0x43, 0x18, 0x10, 0x01, 0x58, 0, 0, 0, 0x04, 0x18, 0x10, 0x01, 0x06, 0x07, 0x0F];
    let inputs: Vec<Input> = decode(&bytes).collect();
    assert_eq!(
        inputs,
        [
            Input::Frame { id: 0x585, rtr: false, data: [0x43, 0x18, 0x10, 0x01, 0x58, 0, 0, 0], len: 8 },
            Input::Upload { index: 0x1018, sub: 1 },
            Input::Scan { node: 7 },
            Input::Time { ms: 25 },
        ]
    );
}

/// The invariants let correct answers through: the property is not vacuous.
#[test]
fn answered_transfers_and_scans_complete() {
    let outcomes = coforge_verification::manager::check(coforge_verification::manager::answered_run());
    assert_eq!((outcomes.completed, outcomes.aborted, outcomes.scans_complete), (2, 0, 1));
}
