//! Any traffic and any caller into coforge-stack's manager: no panic, only valid frames sent,
//! a transfer completes only on an answer (see `coforge_verification::manager`).
#![no_main]

use coforge_verification::manager::prop_manager_inputs;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: &[u8]| prop_manager_inputs(input));
