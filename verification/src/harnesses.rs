//! Kani harnesses: each calls one `prop_*` function with symbolic inputs up to a bound.
//! Run with `cargo kani -p coforge-verification` (see `.github/workflows/kani.yml`).

use crate::framing::*;
use crate::integrity::*;
use crate::stack::*;
use coforge_link::crc::Crc16;

static TABLES: [Crc16; 3] = [Crc16::new(PARAMS[0]), Crc16::new(PARAMS[1]), Crc16::new(PARAMS[2])];

fn any_table() -> &'static Crc16 {
    let i: usize = kani::any();
    kani::assume(i < TABLES.len());
    &TABLES[i]
}

#[kani::proof]
#[kani::unwind(9)]
fn crc_table_step_equals_bitwise() {
    prop_crc_table_step(any_table(), kani::any(), kani::any());
}

#[kani::proof]
#[kani::unwind(9)]
fn crc_equals_reference_up_to_4_bytes() {
    let data: [u8; 4] = kani::any();
    let len: usize = kani::any();
    kani::assume(len <= data.len());
    prop_crc_matches_reference(any_table(), &data[..len]);
}

#[kani::proof]
#[kani::unwind(17)]
fn crc_detects_bursts_up_to_16_bits_in_4_bytes() {
    let mut data: [u8; 4] = kani::any();
    prop_crc_detects_burst(&TABLES[0], &mut data, kani::any(), kani::any());
}

#[kani::proof]
fn sum32_update_step() {
    prop_sum32_step(kani::any(), kani::any(), kani::any());
}

#[kani::proof]
#[kani::unwind(9)]
fn sum32_update_equals_recompute_8_bytes() {
    let mut data: [u8; 8] = kani::any();
    prop_sum32_update(&mut data, kani::any(), kani::any());
}

#[kani::proof]
#[kani::unwind(17)]
fn nibble_round_trip() {
    let data: [u8; 15] = kani::any();
    let len: usize = kani::any();
    kani::assume(len <= 15);
    prop_nibble_round_trip(kani::any(), &data[..len]);
}

#[kani::proof]
#[kani::unwind(11)]
fn length_byte_round_trip_up_to_8_bytes() {
    let data: [u8; 8] = kani::any();
    let len: usize = kani::any();
    kani::assume(len <= 8);
    let extension: Option<u8> = if kani::any() { Some(kani::any()) } else { None };
    prop_length_byte_round_trip(kani::any(), &data[..len], extension);
}

#[kani::proof]
#[kani::unwind(12)]
fn start_crc_round_trip_up_to_6_bytes() {
    let data: [u8; 6] = kani::any();
    let len: usize = kani::any();
    kani::assume(len <= 6);
    prop_start_crc_round_trip(kani::any(), &data[..len]);
}

#[kani::proof]
#[kani::unwind(9)]
fn decoders_are_total_for_8_bytes() {
    let bytes: [u8; 8] = kani::any();
    let gaps: [u8; 8] = kani::any();
    prop_decoders_total(&bytes, &gaps);
}

#[kani::proof]
#[kani::unwind(14)]
fn resync_after_4_bytes_of_garbage() {
    let garbage: [u8; 4] = kani::any();
    let data: [u8; 2] = kani::any();
    prop_resync_after_garbage(&garbage, kani::any(), &data);
}

#[kani::proof]
#[kani::unwind(7)]
fn emcy_register_follows_active_errors_for_6_operations() {
    let ops: [u8; 6] = kani::any();
    prop_emcy_register(&ops);
}

#[kani::proof]
fn nmt_commands_address_only_this_node() {
    let payload: [u8; 3] = kani::any();
    let len: usize = kani::any();
    kani::assume(len <= payload.len());
    prop_nmt_parse(&payload[..len], kani::any());
}

#[kani::proof]
#[kani::unwind(9)]
fn sdo_first_request_answers_validly() {
    let request: [u8; 8] = kani::any();
    prop_sdo_first_request(&request);
}
