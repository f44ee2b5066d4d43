//! The endurance and start-up figures of `examples/bank_endurance.rs`, asserted: they are
//! counts of EEPROM byte accesses, not timings, so they are exact.

use coforge_verification::banks::{Cost, Power, co401memory1_fixture, endurance};

/// Bytes of one block's slot (128 data bytes and the 4-byte record), and of one bank.
const SLOT: u32 = 132;
const BANK: u32 = 64 * SLOT;

#[test]
fn eeprom_costs_of_writes_reads_and_mounts() {
    let power = Power::new();
    let (settled, garbage) = co401memory1_fixture(&power);
    let costs = endurance::<8448, 64, 128>(&settled, &garbage);
    for c in &costs {
        println!("{c:?}");
    }
    let row = |what: &str| -> Cost { *costs.iter().find(|c| c.what == what).unwrap_or_else(|| panic!("no row {what}")) };
    let is =
        |c: Cost, writes: u32, reads: u32, max_cell: u16| assert_eq!((c.byte_writes, c.byte_reads, c.max_cell_writes), (writes, reads, max_cell), "{}", c.what);
    // A write loads both copies of each block it touches, then writes per bank: the mark,
    // the changed data bytes, the two CRC bytes and the commit byte. No cell is written twice.
    is(row("write 1 byte"), 2 * (1 + 1 + 2 + 1), 2 * SLOT, 1);
    is(row("write 1 byte, value already stored"), 0, 2 * SLOT, 0);
    is(row("write 1 block, every byte changed"), 2 * (1 + 128 + 2 + 1), 2 * SLOT, 1);
    is(row("write 1 block's length across 2 blocks"), 2 * 2 * (1 + 64 + 2 + 1), 2 * 2 * SLOT, 1);
    // Every cell of both banks exactly once.
    is(row("write every block once, every byte changed"), 2 * BANK, 2 * BANK, 1);
    // The record cells of a block take one write per write to the block: they wear fastest.
    is(row("1000 writes of 1 byte walking through one block"), 1000 * 10, 1000 * 2 * SLOT, 1000);
    // Reads compare the requested bytes of both banks; a check loads both copies.
    is(row("read 1 byte"), 0, 2, 0);
    is(row("read 1 block"), 0, 2 * 128, 0);
    is(row("check_block (one scrub step)"), 0, 2 * SLOT, 0);
    // Start-up reads both banks once; a repair rewrites what differs in the bad bank.
    is(row("mount, banks agree"), 0, 2 * BANK, 0);
    is(row("mount, bank 2 erased (repair)"), BANK, 2 * BANK, 1);
    let ruined = row("mount, bank 1 garbage (repair)");
    assert_eq!((ruined.byte_reads, ruined.max_cell_writes), (2 * BANK, 1));
    assert!(ruined.byte_writes <= BANK && ruined.byte_writes > BANK - 64 * 4, "{ruined:?}");
    // The format reads every block again before staging it.
    is(row("mount, blank banks (format)"), 2 * BANK, 4 * BANK, 1);
}
