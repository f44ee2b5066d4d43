//! CANopenIA's configuration loading under any file: no panic, a refused file leaves the
//! active one running, an accepted one starts (see `coforge_verification::canopenia_files`).
#![no_main]

use coforge_verification::canopenia_files::prop_config_file;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: &[u8]| prop_config_file(input));
