//! CO401GW1 under arbitrary input on both of its inputs: host bytes at any times and CAN
//! frames, in both I/O modes, before and after enable. Nothing may panic, no host telegram
//! may be longer than the output buffer, and:
//! - host bytes alone never change an entry the host rule does not let the host write;
//! - whatever the mix, an entry that neither the bus nor the host may write keeps its value.
//!
//! Entries the chip itself maintains are left out: 1001h (error register), 1002h (status
//! register, from EMY0#/EMY1#), 1003h; the pins stay as the board sets them throughout.
//! Checked by proptest (`tests/gw1_inputs.rs`, inputs weighted towards the protocol) and by
//! cargo fuzz (`fuzz/fuzz_targets/gw1_inputs.rs`, [`prop_gw1_inputs`] on raw bytes).

use crate::inputs::{Snapshot, bus_writable, decode_inputs, feed, host_writable};
use co401gw1::{FixedBoard, Gw1};
use coforge_stack::device::Device;
use coforge_stack::od::{EntryAccess, Side};
use coforge_stack::store::NoStore;

pub use crate::inputs::Input;

/// The chip's node-ID on its ID pins.
pub const NODE: u16 = 5;
const MAINTAINED: [u16; 3] = [0x1001, 0x1002, 0x1003];

type Chip = Gw1<FixedBoard, NoStore>;

/// The setting a run starts from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Setup {
    /// Mixed mode (CFG1 high); digital only otherwise.
    pub mixed: bool,
    /// The host has enabled CAN (`02 00`) before the inputs.
    pub enabled: bool,
}

fn snapshot(chip: &mut Chip) -> Snapshot {
    let entries = chip.node().od().entries();
    Snapshot::take(entries, &MAINTAINED, |index, sub, buf| chip.node_mut().read(index, sub, 0, buf, Side::Device))
}

/// Runs `inputs` on a fresh chip and checks the invariants; `with_can` says whether the
/// inputs may hold frames (without, the host rule alone is checked).
pub fn check(setup: Setup, with_can: bool, inputs: impl IntoIterator<Item = Input>) {
    let Setup { mixed, enabled } = setup;
    let mut chip: Chip = Gw1::new(FixedBoard::new(NODE as u8, mixed), NoStore);
    chip.start(0);
    if enabled {
        assert!(chip.enable(false, 0), "enable at a valid node-ID");
    }
    let before = snapshot(&mut chip);
    let (mut now_ms, mut out) = (1_u64, [0_u8; 256]);
    for input in inputs {
        let n = feed(&mut chip, input, with_can, &mut now_ms, &mut out);
        // The longest telegram: command, DataLen, 127 data bytes.
        assert!(n <= 129, "a host telegram of {n} bytes");
    }
    let after = snapshot(&mut chip);
    // `02 81` in the digital modes chooses PDO5's identifiers: the one change the enable
    // command itself makes to entries the host may not write.
    let chosen_by_enable = |i: u16, s: u8| !mixed && !enabled && s == 1 && (i == 0x1404 || i == 0x1804);
    before.assert_changed_only(&after, |b| {
        if with_can { host_writable(b.host) || bus_writable(b.access) } else { host_writable(b.host) || chosen_by_enable(b.index, b.sub) }
    });
}

/// The invariants for raw bytes (cargo fuzz): see [`decode`].
pub fn prop_gw1_inputs(input: &[u8]) {
    if let Some((setup, with_can, inputs)) = decode(input) {
        check(setup, with_can, inputs);
    }
}

/// Raw bytes as a run: the first byte picks the mode (bit 0), enable (bit 1) and whether
/// frames count (bit 2); the rest are inputs ([`decode_inputs`]).
pub fn decode(input: &[u8]) -> Option<(Setup, bool, impl Iterator<Item = Input> + '_)> {
    let (&first, rest) = input.split_first()?;
    let setup = Setup { mixed: first & 1 != 0, enabled: first & 2 != 0 };
    Some((setup, first & 4 != 0, decode_inputs(rest)))
}
