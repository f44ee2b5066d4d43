//! The stack's obligations checked here: exhaustively where the domain is small, randomly
//! where it is not (the Kani harnesses in `src/harnesses.rs` take the same functions).

use coforge_verification::stack::{prop_emcy_register, prop_nmt_parse, prop_sdo_first_request};
use proptest::prelude::*;

#[test]
fn emcy_register_every_sequence_of_5_operations() {
    // 8 operations (raise or clear one of 4 emergencies), every sequence of length 5.
    let mut ops = [0_u8; 5];
    for n in 0..8_u32.pow(5) {
        for (i, op) in ops.iter_mut().enumerate() {
            *op = (n >> (3 * i) & 7) as u8;
        }
        prop_emcy_register(&ops);
    }
}

#[test]
fn nmt_parse_every_payload_up_to_2_bytes_and_node() {
    for node in 1..=127_u8 {
        prop_nmt_parse(&[], node);
        for a in 0..=255_u8 {
            prop_nmt_parse(&[a], node);
            for b in 0..=255_u8 {
                prop_nmt_parse(&[a, b], node);
            }
        }
        prop_nmt_parse(&[0x01, node, 0], node);
    }
}

#[test]
fn sdo_first_request_every_command_byte_and_object() {
    for cs in 0..=255_u8 {
        for (lo, hi, sub) in [(0x00, 0x20, 0), (0x01, 0x20, 0), (0x00, 0x20, 1), (0x00, 0x30, 0)] {
            for data in [[0, 0, 0, 0], [4, 0, 0, 0], [21, 0, 0, 0], [0xFF; 4], [0, 0, 0, 0x80]] {
                prop_sdo_first_request(&[cs, lo, hi, sub, data[0], data[1], data[2], data[3]]);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 20_000, ..ProptestConfig::default() })]

    #[test]
    fn sdo_first_request_random(request in proptest::collection::vec(any::<u8>(), 0..10)) {
        prop_sdo_first_request(&request);
    }

    #[test]
    fn emcy_register_random(ops in proptest::collection::vec(any::<u8>(), 0..40)) {
        prop_emcy_register(&ops);
    }
}
