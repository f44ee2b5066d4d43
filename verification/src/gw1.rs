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

use co401gw1::{FixedBoard, Gw1};
use coforge_stack::device::{Device, HostPort};
use coforge_stack::frame::CanFrame;
use coforge_stack::od::{Access, EntryAccess, HostAccess, Side};
use coforge_stack::store::NoStore;

/// The chip's node-ID on its ID pins.
pub const NODE: u16 = 5;
const MAINTAINED: [u16; 3] = [0x1001, 0x1002, 0x1003];
/// The longest value compared (1008h/1009h/100Ah strings are shorter).
const VALUE: usize = 32;
/// Entries watched: more than the chip's dictionary has sub-indices in either mode.
const WATCHED: usize = 600;

type Chip = Gw1<FixedBoard, NoStore>;

/// One input to the chip.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Input {
    /// A byte from the host `gap_ms` after the previous input.
    Host { byte: u8, gap_ms: u32 },
    /// A frame from the bus (a remote frame's DLC is `len`).
    Can { id: u16, rtr: bool, data: [u8; 8], len: u8 },
    /// Time passes without input.
    Time { ms: u32 },
}

/// The setting a run starts from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Setup {
    /// Mixed mode (CFG1 high); digital only otherwise.
    pub mixed: bool,
    /// The host has enabled CAN (`02 00`) before the inputs.
    pub enabled: bool,
}

/// One entry's value as the device side reads it, with what may write it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Value {
    index: u16,
    sub: u8,
    access: Access,
    host: HostAccess,
    len: usize,
    bytes: [u8; VALUE],
}

struct Snapshot {
    values: [Option<Value>; WATCHED],
    n: usize,
}

fn snapshot(chip: &mut Chip) -> Snapshot {
    let mut s = Snapshot { values: [None; WATCHED], n: 0 };
    let entries = chip.node().od().entries();
    for e in entries.iter().filter(|e| !MAINTAINED.contains(&e.index)) {
        for sub in e.sub..=e.last_sub {
            let mut bytes = [0_u8; VALUE];
            if let Ok(r) = chip.node_mut().read(e.index, sub, 0, &mut bytes, Side::Device) {
                let value = Value { index: e.index, sub, access: e.access(), host: e.host_access(), len: r.copied, bytes };
                let slot = s.values.get_mut(s.n);
                assert!(slot.is_some(), "more than {WATCHED} entries: raise WATCHED");
                if let Some(slot) = slot {
                    *slot = Some(value);
                }
                s.n += 1;
            }
        }
    }
    s
}

fn host_writable(host: HostAccess) -> bool {
    matches!(host, HostAccess::Wo | HostAccess::Rw)
}

fn bus_writable(access: Access) -> bool {
    !matches!(access, Access::Ro | Access::Const | Access::None)
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
        match input {
            Input::Host { byte, gap_ms } => {
                now_ms += u64::from(gap_ms);
                chip.on_host_byte(byte, now_ms);
            }
            Input::Can { id, rtr, data, len } if with_can => {
                let frame = if rtr { CanFrame::remote(id, len.min(8)) } else { CanFrame::data(id, data.get(..usize::from(len.min(8))).unwrap_or(&[])) };
                if let Some(frame) = frame {
                    chip.on_frame(&frame, now_ms * 1000);
                }
            }
            Input::Can { .. } => {}
            Input::Time { ms } => now_ms += u64::from(ms),
        }
        for _ in 0..64 {
            if chip.poll(now_ms * 1000).is_none() {
                break;
            }
        }
        // The longest telegram: command, DataLen, 127 data bytes.
        let n = chip.host_output(now_ms, &mut out);
        assert!(n <= 129, "a host telegram of {n} bytes");
    }
    let after = snapshot(&mut chip);
    assert_eq!(before.n, after.n, "entries appeared or vanished");
    // `02 81` in the digital modes chooses PDO5's identifiers: the one change the enable
    // command itself makes to entries the host may not write.
    let chosen_by_enable = |i: u16, s: u8| !mixed && !enabled && s == 1 && (i == 0x1404 || i == 0x1804);
    for (b, a) in before.values.iter().zip(&after.values).take(before.n) {
        let (Some(b), Some(a)) = (b, a) else { continue };
        let may_change = if with_can { host_writable(b.host) || bus_writable(b.access) } else { host_writable(b.host) || chosen_by_enable(b.index, b.sub) };
        assert!(may_change || b == a, "{:04X}h.{} changed: {:02X?} -> {:02X?}", b.index, b.sub, b.bytes.get(..b.len), a.bytes.get(..a.len));
    }
}

/// The invariants for raw bytes (cargo fuzz): see [`decode`].
pub fn prop_gw1_inputs(input: &[u8]) {
    if let Some((setup, with_can, inputs)) = decode(input) {
        check(setup, with_can, inputs);
    }
}

/// Raw bytes as a run: the first byte picks the mode (bit 0), enable (bit 1) and whether
/// frames count (bit 2); then each input is a tag byte and what it needs. Tags 0..4 (mod 8):
/// a host byte, the next one, after a gap of `(tag >> 3) % 3` ms, or `(tag >> 3) * 4` ms with
/// bit 7 set; 5 and 6: a frame, two bytes of DLC (high nibble) and identifier (11 bits), then
/// its data (6 with bit 7: a remote frame); 7: `(tag >> 3) * 20` ms pass.
pub fn decode(input: &[u8]) -> Option<(Setup, bool, impl Iterator<Item = Input> + '_)> {
    let (&first, mut rest) = input.split_first()?;
    let setup = Setup { mixed: first & 1 != 0, enabled: first & 2 != 0 };
    let with_can = first & 4 != 0;
    let inputs = core::iter::from_fn(move || {
        let (&tag, tail) = rest.split_first()?;
        rest = tail;
        Some(match tag % 8 {
            0..=4 => {
                let (&byte, tail) = rest.split_first()?;
                rest = tail;
                Input::Host { byte, gap_ms: if tag & 0x80 != 0 { u32::from(tag >> 3) * 4 } else { u32::from(tag >> 3) % 3 } }
            }
            5 | 6 => {
                let [hi, lo, tail @ ..] = rest else { return None };
                let len = usize::from(hi >> 4).min(8);
                let id = u16::from_be_bytes([hi & 0x07, *lo]);
                let (payload, tail) = tail.split_at(len.min(tail.len()));
                rest = tail;
                let mut data = [0_u8; 8];
                for (d, s) in data.iter_mut().zip(payload) {
                    *d = *s;
                }
                Input::Can { id, rtr: tag & 0x80 != 0 && tag % 8 == 6, data, len: payload.len() as u8 }
            }
            _ => Input::Time { ms: u32::from(tag >> 3) * 20 },
        })
    });
    Some((setup, with_can, inputs))
}
