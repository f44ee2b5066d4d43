//! CANopenIA under any host bytes and CAN frames: no panic, only whole valid frames to the
//! host, no write the host rule or the access rules forbid (see
//! `coforge_verification::canopenia`).
#![no_main]

use coforge_verification::canopenia::prop_canopenia_inputs;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: &[u8]| prop_canopenia_inputs(input));
