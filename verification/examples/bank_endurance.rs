//! `bank_endurance`: what writes, reads, checks and start-up cost the two EEPROMs of
//! CO401Memory1's mirrored banks (64 blocks of 128 bytes, 8448 bytes per bank), in byte
//! writes, byte reads and the writes of the most-written cell, as a Markdown table. Counts,
//! so deterministic; `tests/banks_endurance.rs` asserts the same figures.

use coforge_verification::banks::{Power, co401memory1_fixture, endurance};

fn main() {
    let power = Power::new();
    let (settled, garbage) = co401memory1_fixture(&power);
    println!("| Operation (64 blocks x 128 bytes, 2 banks) | Operations | EEPROM byte writes | EEPROM byte reads | Writes of the most-written cell |");
    println!("|---|---:|---:|---:|---:|");
    for c in endurance::<8448, 64, 128>(&settled, &garbage) {
        println!("| {} | {} | {} | {} | {} |", c.what, c.operations, c.byte_writes, c.byte_reads, c.max_cell_writes);
    }
}
