//! Any bytes at any times: the start_crc decoder must not panic, and its frames must fit the framing.
#![no_main]

use coforge_verification::framing::{prop_start_crc_total, split_fuzz_input};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: &[u8]| {
    let (gaps, bytes) = split_fuzz_input(input);
    prop_start_crc_total(bytes, gaps);
});
