//! A device with a serial host under arbitrary input on both of its inputs: host bytes at any
//! times, CAN frames and time passing; the snapshots of its entries that the invariants
//! compare; and the raw-byte form of a run that cargo fuzz feeds. Used by [`crate::gw1`] and
//! [`crate::canopenia`].

use coforge_stack::device::{Device, HostPort};
use coforge_stack::frame::CanFrame;
use coforge_stack::od::{Access, HostAccess, ReadLen, SdoAbort, Table};

/// The longest value compared (strings included).
const VALUE: usize = 32;
/// Entries watched: more than any device's dictionary has sub-indices in any mode.
const WATCHED: usize = 600;

/// One input to the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Input {
    /// A byte from the host `gap_ms` after the previous input.
    Host { byte: u8, gap_ms: u32 },
    /// A frame from the bus (a remote frame's DLC is `len`).
    Can { id: u16, rtr: bool, data: [u8; 8], len: u8 },
    /// Time passes without input.
    Time { ms: u32 },
}

/// Raw bytes as inputs: a tag byte each, then what it needs. Tags 0..4 (mod 8): a host byte,
/// the next one, after a gap of `(tag >> 3) % 3` ms, or `(tag >> 3) * 4` ms with bit 7 set;
/// 5 and 6: a frame, two bytes of DLC (high nibble) and identifier (11 bits), then its data
/// (6 with bit 7: a remote frame); 7: `(tag >> 3) * 20` ms pass.
pub fn decode_inputs(mut rest: &[u8]) -> impl Iterator<Item = Input> + '_ {
    core::iter::from_fn(move || {
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
    })
}

/// Hands one input to `device` at the clock `now_ms` (advanced by the input's time), polls it
/// until it is quiet, and returns how many bytes it had for the host (copied into `out`).
/// Frames are skipped unless `with_can`.
pub fn feed<D: Device + HostPort>(device: &mut D, input: Input, with_can: bool, now_ms: &mut u64, out: &mut [u8]) -> usize {
    match input {
        Input::Host { byte, gap_ms } => {
            *now_ms += u64::from(gap_ms);
            device.on_host_byte(byte, *now_ms);
        }
        Input::Can { id, rtr, data, len } if with_can => {
            let frame = if rtr { CanFrame::remote(id, len.min(8)) } else { CanFrame::data(id, data.get(..usize::from(len.min(8))).unwrap_or(&[])) };
            if let Some(frame) = frame {
                device.on_frame(&frame, *now_ms * 1000);
            }
        }
        Input::Can { .. } => {}
        Input::Time { ms } => *now_ms += u64::from(ms),
    }
    for _ in 0..64 {
        if device.poll(*now_ms * 1000).is_none() {
            break;
        }
    }
    device.host_output(*now_ms, out)
}

/// One entry's value as the device side reads it, with what may write it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Value {
    pub index: u16,
    pub sub: u8,
    pub access: Access,
    pub host: HostAccess,
    len: usize,
    bytes: [u8; VALUE],
}

/// Every entry's value, but those of the objects a device maintains itself.
pub struct Snapshot {
    values: [Option<Value>; WATCHED],
    n: usize,
}

impl Snapshot {
    /// Reads every sub-index of `entries` with `read` (the device side), but `maintained`.
    pub fn take(entries: Table<'_>, maintained: &[u16], mut read: impl FnMut(u16, u8, &mut [u8]) -> Result<ReadLen, SdoAbort>) -> Snapshot {
        let mut s = Snapshot { values: [None; WATCHED], n: 0 };
        for e in entries.iter().filter(|e| !maintained.contains(&e.index)) {
            for sub in e.sub..=e.last_sub {
                let mut bytes = [0_u8; VALUE];
                if let Ok(r) = read(e.index, sub, &mut bytes) {
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

    /// Fails unless every entry that changed since `self` is one `may_change` allows.
    pub fn assert_changed_only(&self, after: &Snapshot, may_change: impl Fn(&Value) -> bool) {
        assert_eq!(self.n, after.n, "entries appeared or vanished");
        for (b, a) in self.values.iter().zip(&after.values).take(self.n) {
            let (Some(b), Some(a)) = (b, a) else { continue };
            assert!(may_change(b) || b == a, "{:04X}h.{} changed: {:02X?} -> {:02X?}", b.index, b.sub, b.bytes.get(..b.len), a.bytes.get(..a.len));
        }
    }
}

pub fn host_writable(host: HostAccess) -> bool {
    matches!(host, HostAccess::Wo | HostAccess::Rw)
}

pub fn bus_writable(access: Access) -> bool {
    !matches!(access, Access::Ro | Access::Const | Access::None)
}
