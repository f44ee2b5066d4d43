//! Any CAN traffic into a device's node: no panic, no change to read-only entries, every
//! SDO answer valid (see `coforge_verification::node`).
#![no_main]

use coforge_verification::node::prop_node_frames;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: &[u8]| prop_node_frames(input));
