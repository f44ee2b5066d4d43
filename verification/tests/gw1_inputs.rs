#![allow(clippy::unwrap_used, clippy::indexing_slicing)]
//! CO401GW1 under arbitrary input on both of its inputs: random host bytes at random times
//! (command bytes of the protocol weighted up) and random CAN frames (the chip's SDO, RPDO,
//! NMT and guarding identifiers weighted up), in both I/O modes, before and after enable.
//! Nothing may panic, no host telegram may be longer than the framing allows, and:
//! - host bytes alone never change an entry the host rule does not let the host write;
//! - whatever the mix, an entry that neither the bus nor the host may write keeps its value.
//!
//! Entries the chip itself maintains are left out: 1001h (error register), 1002h (status
//! register, from EMY0#/EMY1#), 1003h; the pins stay as the board sets them throughout.

use co401gw1::{FixedBoard, Gw1};
use coforge_stack::device::{Device, HostPort};
use coforge_stack::frame::CanFrame;
use coforge_stack::od::{Access, EntryAccess, HostAccess, Side};
use coforge_stack::store::NoStore;
use proptest::prelude::*;

const NODE: u16 = 5;
const MAINTAINED: [u16; 3] = [0x1001, 0x1002, 0x1003];

type Chip = Gw1<FixedBoard, NoStore>;

#[derive(Debug, Clone)]
enum Input {
    Host { byte: u8, gap_ms: u32 },
    Can { id: u16, rtr: bool, data: Vec<u8> },
    Time { ms: u32 },
}

fn input(with_can: bool) -> impl Strategy<Value = Input> {
    // Command bytes and small DataLens, so short inputs form telegrams; any byte otherwise.
    let byte = prop_oneof![prop::sample::select(vec![0x02_u8, 0x20, 0x21, 0x30, 0x31, 0x34, 0x40, 0x41, 0x44, 0x50, 0x51, 0x81]), 0..8_u8, any::<u8>(),];
    let host = (byte, prop_oneof![4 => 0..3_u32, 1 => 8..70_u32]).prop_map(|(byte, gap_ms)| Input::Host { byte, gap_ms });
    let id = prop_oneof![Just(0x000), Just(0x080), Just(0x600 + NODE), Just(0x200 + NODE), Just(0x300 + NODE), Just(0x700 + NODE), 0..0x800_u16];
    let can = (id, any::<bool>(), prop::collection::vec(any::<u8>(), 0..=8)).prop_map(|(id, rtr, data)| Input::Can { id, rtr, data });
    let time = (0..600_u32).prop_map(|ms| Input::Time { ms });
    let can_weight = if with_can { 3 } else { 0 };
    prop_oneof![6 => host, can_weight => can, 1 => time]
}

/// One entry's value as the device side reads it, with what may write it.
type Value = (u16, u8, Access, HostAccess, Vec<u8>);

/// Every entry's value.
fn snapshot(chip: &mut Chip) -> Vec<Value> {
    let entries = chip.node().od().entries();
    let mut out = Vec::new();
    for e in entries.iter().filter(|e| !MAINTAINED.contains(&e.index)) {
        for sub in e.sub..=e.last_sub {
            let mut buf = [0_u8; 32];
            if let Ok(n) = chip.node_mut().read(e.index, sub, 0, &mut buf, Side::Device) {
                out.push((e.index, sub, e.access(), e.host_access(), buf[..n.copied].to_vec()));
            }
        }
    }
    out
}

/// Runs `inputs` on a fresh chip (mode `mixed`, enabled first if `enabled`); returns the
/// snapshots before and after.
fn run(mixed: bool, enabled: bool, inputs: Vec<Input>) -> (Vec<Value>, Vec<Value>) {
    let mut chip: Chip = Gw1::new(FixedBoard::new(NODE as u8, mixed), NoStore);
    chip.start(0);
    if enabled {
        assert!(chip.enable(false, 0));
    }
    let before = snapshot(&mut chip);
    let (mut now_ms, mut out) = (1_u64, [0_u8; 256]);
    for input in inputs {
        match input {
            Input::Host { byte, gap_ms } => {
                now_ms += u64::from(gap_ms);
                chip.on_host_byte(byte, now_ms);
            }
            Input::Can { id, rtr, data } => {
                let frame = if rtr { CanFrame::remote(id, data.len() as u8) } else { CanFrame::data(id, &data) };
                chip.on_frame(&frame.unwrap(), now_ms * 1000);
            }
            Input::Time { ms } => now_ms += u64::from(ms),
        }
        for _ in 0..64 {
            if chip.poll(now_ms * 1000).is_none() {
                break;
            }
        }
        let n = chip.host_output(now_ms, &mut out);
        // The longest telegram: command, DataLen, 127 data bytes.
        assert!(n <= out.len());
    }
    (before, snapshot(&mut chip))
}

fn host_writable(host: HostAccess) -> bool {
    matches!(host, HostAccess::Wo | HostAccess::Rw)
}

fn bus_writable(access: Access) -> bool {
    !matches!(access, Access::Ro | Access::Const | Access::None)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn host_bytes_write_only_what_the_host_rule_allows(mixed in any::<bool>(), enabled in any::<bool>(), inputs in prop::collection::vec(input(false), 1..200)) {
        let (before, after) = run(mixed, enabled, inputs);
        prop_assert_eq!(before.len(), after.len());
        // `02 81` in the digital modes chooses PDO5's identifiers: the one change the enable
        // command itself makes to entries the host may not write.
        let chosen_by_enable = |i: u16, s: u8| !mixed && !enabled && s == 1 && (i == 0x1404 || i == 0x1804);
        for (b, a) in before.iter().zip(&after) {
            if !host_writable(b.3) && !chosen_by_enable(b.0, b.1) {
                prop_assert!(b == a, "the host changed {:04X}h.{}: {:02X?} -> {:02X?}", b.0, b.1, b.4, a.4);
            }
        }
    }

    #[test]
    fn host_and_bus_together_never_write_what_neither_may(mixed in any::<bool>(), enabled in any::<bool>(), inputs in prop::collection::vec(input(true), 1..200)) {
        let (before, after) = run(mixed, enabled, inputs);
        prop_assert_eq!(before.len(), after.len());
        for (b, a) in before.iter().zip(&after) {
            if !host_writable(b.3) && !bus_writable(b.2) {
                prop_assert!(b == a, "{:04X}h.{} changed: {:02X?} -> {:02X?}", b.0, b.1, b.4, a.4);
            }
        }
    }
}
