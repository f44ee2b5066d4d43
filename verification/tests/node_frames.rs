//! `prop_node_frames` on bounded random traffic (the fuzz target `node_frames` runs the same
//! property for longer), plus hand-picked sequences that reach each SDO phase.

use coforge_verification::node::prop_node_frames;
use proptest::prelude::*;

/// 12 bytes per frame: time step, identifier choice (0..=199 picks a service), flags, data.
fn frame(step: u8, pick: u8, flags: u8, data: [u8; 8]) -> Vec<u8> {
    let mut v = vec![step, pick, 0, flags];
    v.extend_from_slice(&data);
    v
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, ..ProptestConfig::default() })]

    #[test]
    fn any_traffic_keeps_the_invariants(input in proptest::collection::vec(any::<u8>(), 0..600)) {
        prop_node_frames(&input);
    }
}

#[test]
fn every_sdo_phase_under_garbage() {
    // Selector 2 = SDO request 0x605, flags 0x80 = DLC 8.
    let sdo = |data| frame(1, 2, 0x80, data);
    let phases: [[u8; 8]; 5] = [
        [0x40, 0x08, 0x10, 0, 0, 0, 0, 0],    // segmented upload of 1008h
        [0x21, 0x17, 0x10, 0, 8, 0, 0, 0],    // segmented download announced
        [0xC6, 0x17, 0x10, 0, 2, 0, 0, 0],    // block download initiate
        [0xA4, 0x08, 0x10, 0, 10, 0, 0, 0],   // block upload initiate
        [0x00, 0x01, 0x02, 0x03, 0, 0, 0, 0], // a stray segment
    ];
    for device in 0..3_u8 {
        for phase in phases {
            for garbage in [[0xFF; 8], [0x60, 0, 0, 0, 0, 0, 0, 0], [0xA3, 0, 0, 0, 0, 0, 0, 0], [0x81, 0, 0, 0, 0, 0, 0, 0]] {
                let mut input = vec![device];
                input.extend(frame(0, 0, 0x20, [0x01, 0, 0, 0, 0, 0, 0, 0])); // NMT start all
                input.extend(sdo(phase));
                input.extend(sdo(garbage));
                input.extend(frame(255, 3, 0x18, [0; 8])); // guarding RTR after a long pause
                input.extend(sdo(garbage));
                prop_node_frames(&input);
            }
        }
    }
}

#[test]
fn fuzz_regression_remote_frame_during_block_upload() {
    // Found by the fuzzer: the checker, not the node, took a remote frame on the SDO
    // identifier for a client request that ends a block upload.
    prop_node_frames(include_bytes!("../fuzz/corpus/node_frames/regression_rtr_during_block_upload"));
}
