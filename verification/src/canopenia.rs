//! CANopenIA under arbitrary input on both of its inputs: host bytes at any times, CAN frames
//! (its own SDO, RPDO and NMT identifiers, other nodes' boot-ups, heartbeats, SDO answers and
//! TPDOs for its manager) and time. Nothing may panic, and:
//! - everything it sends its host is whole frames of the protocol, one after the other: a
//!   fresh decoder reads them without skipping a byte, each with a valid CRC, a payload of at
//!   most 35 bytes, and a message the protocol has;
//! - an entry that neither the host nor the bus may write keeps its value (S and U addressed
//!   to the coprocessor's own node-ID are served with the bus's rules, erratum COIA-44, so the
//!   host alone may change what the bus may).
//!
//! Entries the coprocessor maintains itself are left out: 1001h (error register), 5F00h (its
//! status) and 5F04h (the node table). Checked by proptest (`tests/canopenia_inputs.rs`) and
//! by cargo fuzz (`fuzz/fuzz_targets/canopenia_inputs.rs`, [`prop_canopenia_inputs`]).

use crate::inputs::{Snapshot, bus_writable, decode_inputs, feed, host_writable};
use canopenia::Canopenia;
use canopenia::serial::{self, DeviceToHost};
use coforge_link::Deframer;
use coforge_stack::device::Device;
use coforge_stack::od::{EntryAccess, Side};
use coforge_stack::store::NoStore;

pub use crate::inputs::Input;

/// The coprocessor's node-ID.
pub const NODE: u16 = 2;
/// Entries the device keeps itself: the error register, the error history (each emergency it
/// sends), its status (5F00h) and every node's (5F04h).
const MAINTAINED: [u16; 4] = [0x1001, 0x1003, 0x5F00, 0x5F04];

type Chip = Canopenia<NoStore>;

fn snapshot(chip: &mut Chip) -> Snapshot {
    let entries = chip.node().od().entries();
    Snapshot::take(entries, &MAINTAINED, |index, sub, buf| chip.node_mut().read(index, sub, 0, buf, Side::Device))
}

/// Runs `inputs` on a fresh coprocessor (AUTORUN as given) and checks the invariants;
/// frames among the inputs count only `with_can`. Returns how many frames the host read.
pub fn check(autorun: bool, with_can: bool, inputs: impl IntoIterator<Item = Input>) -> usize {
    let mut chip = Canopenia::new(NODE as u8, NoStore);
    chip.set_autorun(autorun);
    chip.start(0);
    let before = snapshot(&mut chip);
    let mut host = serial::decoder();
    let (mut now_ms, mut out, mut frames) = (1_u64, [0_u8; 512], 0);
    for input in inputs {
        let n = feed(&mut chip, input, with_can, &mut now_ms, &mut out);
        for &byte in out.get(..n).unwrap_or(&[]) {
            match host.push(byte, 0) {
                None => {}
                Some(Ok(frame)) => {
                    assert!(DeviceToHost::decode(&frame).is_ok(), "a frame the protocol does not have: {frame:?}");
                    frames += 1;
                }
                Some(Err(e)) => panic!("the host read a broken frame: {e:?}"),
            }
        }
        assert_eq!(host.skipped, 0, "bytes between frames");
    }
    let after = snapshot(&mut chip);
    before.assert_changed_only(&after, |b| host_writable(b.host) || bus_writable(b.access));
    frames
}

/// The invariants for raw bytes (cargo fuzz): see [`decode`].
pub fn prop_canopenia_inputs(input: &[u8]) {
    if let Some((autorun, with_can, inputs)) = decode(input) {
        check(autorun, with_can, inputs);
    }
}

/// Raw bytes as a run: the first byte sets AUTORUN (bit 0) and whether frames count (bit 2);
/// the rest are inputs ([`decode_inputs`]).
pub fn decode(input: &[u8]) -> Option<(bool, bool, impl Iterator<Item = Input> + '_)> {
    let (&first, rest) = input.split_first()?;
    Some((first & 1 != 0, first & 4 != 0, decode_inputs(rest)))
}
