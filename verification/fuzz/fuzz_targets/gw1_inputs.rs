//! CO401GW1 under any host bytes and CAN frames: no panic, no write the host rule or the
//! access rules forbid (see `coforge_verification::gw1`).
#![no_main]

use coforge_verification::gw1::prop_gw1_inputs;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: &[u8]| prop_gw1_inputs(input));
