//! CO401GW1 under arbitrary input on both of its inputs, with proptest: random host bytes at
//! random times (command bytes of the protocol weighted up) and random CAN frames (the chip's
//! SDO, RPDO, NMT and guarding identifiers weighted up), in both I/O modes, before and after
//! enable. The invariants are `coforge_verification::gw1::check` (cargo fuzz checks the same
//! on raw bytes).

use coforge_verification::gw1::{Input, NODE, Setup, check, decode};
use proptest::prelude::*;

fn input() -> impl Strategy<Value = Input> {
    // Command bytes and small DataLens, so short inputs form telegrams; any byte otherwise.
    let byte = prop_oneof![prop::sample::select(vec![0x02_u8, 0x20, 0x21, 0x30, 0x31, 0x34, 0x40, 0x41, 0x44, 0x50, 0x51, 0x81]), 0..8_u8, any::<u8>(),];
    let host = (byte, prop_oneof![4 => 0..3_u32, 1 => 8..70_u32]).prop_map(|(byte, gap_ms)| Input::Host { byte, gap_ms });
    let id = prop_oneof![Just(0x000), Just(0x080), Just(0x600 + NODE), Just(0x200 + NODE), Just(0x300 + NODE), Just(0x700 + NODE), 0..0x800_u16];
    let can = (id, any::<bool>(), any::<[u8; 8]>(), 0..=8_u8).prop_map(|(id, rtr, data, len)| Input::Can { id, rtr, data, len });
    let time = (0..600_u32).prop_map(|ms| Input::Time { ms });
    prop_oneof![6 => host, 3 => can, 1 => time]
}

fn setup() -> impl Strategy<Value = Setup> {
    (any::<bool>(), any::<bool>()).prop_map(|(mixed, enabled)| Setup { mixed, enabled })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn host_bytes_write_only_what_the_host_rule_allows(setup in setup(), inputs in prop::collection::vec(input(), 1..200)) {
        // The frames among the inputs are skipped: the host's bytes alone.
        check(setup, false, inputs);
    }

    #[test]
    fn host_and_bus_together_never_write_what_neither_may(setup in setup(), inputs in prop::collection::vec(input(), 1..200)) {
        check(setup, true, inputs);
    }
}

/// The raw bytes cargo fuzz hands to `prop_gw1_inputs` decode into these inputs.
#[test]
fn raw_bytes_decode_into_inputs() {
    let bytes = [0b101, 0x00, 0x20, 0x8A, 0x02, 0x05, 0x22, 0x05, 0xAA, 0xBB, 0x86, 0x07, 0x05, 0x0F, 0x03];
    let (setup, with_can, inputs) = decode(&bytes).unwrap();
    assert_eq!((setup, with_can), (Setup { mixed: true, enabled: false }, true));
    let inputs: Vec<Input> = inputs.collect();
    assert_eq!(
        inputs,
        [
            Input::Host { byte: 0x20, gap_ms: 0 },
            Input::Host { byte: 0x02, gap_ms: 68 },
            Input::Can { id: 0x205, rtr: false, data: [0xAA, 0xBB, 0, 0, 0, 0, 0, 0], len: 2 },
            Input::Can { id: 0x705, rtr: true, data: [0; 8], len: 0 },
            Input::Time { ms: 20 },
        ]
    );
    assert!(decode(&[]).is_none());
}
