//! Properties every generated dictionary must have, generic over its [`EntryAccess`]: the
//! harnesses the generator emits for each device under `cfg(kani)` (`od::proofs`) call them
//! with symbolic inputs, and the verification crate's random tests with random ones. Each
//! returns normally when the property holds and panics (an assertion) when it does not.
//!
//! The rules are [`EntryInfo`]'s (one place each); what is checked here is that the
//! dictionary applies them to every access, with the abort each rule names, and that a
//! refused write changes nothing.
#![allow(clippy::panic)]

use super::{Access, AccessContext, DataType, EntryAccess, EntryInfo, HostAccess, Limits, NoAppObjects, SdoAbort, Side, Storage};
use crate::value::{Bytes, OdValue};

/// The longest value the properties read back.
const BUF: usize = 16;

/// What the entry `index`/`sub` holds, read by the device itself: `None` for an entry whose
/// value the properties do not compare (app-backed ones, whose owner serves them, and values
/// longer than [`BUF`]).
fn local_value<D: EntryAccess>(od: &mut D, index: u16, sub: u8) -> Option<([u8; BUF], usize)> {
    let info = od.entry(index, sub).ok()?;
    if info.storage() == Storage::App || usize::from(info.size) > BUF {
        return None;
    }
    let mut buf = [0; BUF];
    let n = od.read(index, sub, 0, &mut buf, Side::Device).ok()?;
    Some((buf, n.copied))
}

/// The abort the access rules require of a write by `side` in `ctx`, stated apart from
/// [`EntryInfo::check_write_access`]: the bus by the entry's access and NMT states, the host
/// by its host access and, for entries it may write only before CAN is enabled, that.
fn required_write_abort(info: &EntryInfo, side: Side, ctx: &AccessContext) -> Option<SdoAbort> {
    match side {
        Side::Device => None,
        Side::Bus if info.access() == Access::None => Some(SdoAbort::NoObject),
        Side::Bus if !info.access().writable() => Some(SdoAbort::ReadOnly),
        Side::Bus if !info.writable_in().contains(ctx.nmt) => Some(SdoAbort::DataTransferState),
        Side::Host if info.host_access() == HostAccess::None => Some(SdoAbort::UnsupportedAccess),
        Side::Host if !info.host_access().writable() => Some(SdoAbort::ReadOnly),
        Side::Host if info.host_write_before_can_enabled() && ctx.can_enabled => Some(SdoAbort::DataTransferState),
        Side::Bus | Side::Host => None,
    }
}

/// A write of `data` to `index`/`sub` by `side` in `ctx`:
/// - an entry the dictionary lacks is refused with 0602 0000h or 0609 0011h, as the lookup says;
/// - an entry the bus may not reach answers 0602 0000h (the host 0601 0000h), one the side may
///   not write 0601 0002h, one not writable in this state 0800 0022h, before any value check;
/// - then a value longer than the entry 0607 0012h, shorter than a fixed-size one 0607 0013h;
/// - a refused write leaves a local entry's value as it was;
/// - an accepted write of a local entry reads back as written.
pub fn prop_write_is_checked<D: EntryAccess>(od: &mut D, index: u16, sub: u8, data: &[u8], side: Side, ctx: &AccessContext) {
    let before = local_value(od, index, sub);
    let result = od.write(index, sub, data, side, ctx);
    let Ok(info) = od.entry(index, sub) else {
        assert!(matches!(result, Err(SdoAbort::NoObject | SdoAbort::NoSubIndex)), "a missing entry is refused as missing");
        return;
    };
    let required = required_write_abort(info, side, ctx).or(if data.len() > usize::from(info.size) {
        Some(SdoAbort::LengthTooHigh)
    } else if data.len() < usize::from(info.size) && !info.is_variable_length() {
        Some(SdoAbort::LengthTooLow)
    } else {
        None
    });
    if let Some(abort) = required {
        assert!(result == Err(abort), "the rule's abort");
    }
    let after = local_value(od, index, sub);
    match result {
        Err(_) => assert!(after == before, "a refused write changes nothing"),
        Ok(()) => {
            if let Some((value, n)) = after {
                assert!(value.get(..n) == Some(data), "a write reads back as written");
            }
        }
    }
}

/// A read of `index`/`sub` by `side`: an entry the bus may not reach answers 0602 0000h (the
/// host 0601 0000h), a write-only one 0601 0001h; what is read fits the entry.
pub fn prop_read_is_checked<D: EntryAccess>(od: &mut D, index: u16, sub: u8, side: Side) {
    let mut buf = [0; BUF];
    let result = od.read(index, sub, 0, &mut buf, side);
    let Ok(info) = od.entry(index, sub) else {
        assert!(matches!(result, Err(SdoAbort::NoObject | SdoAbort::NoSubIndex)), "a missing entry is refused as missing");
        return;
    };
    let required = match side {
        Side::Device => None,
        Side::Bus if info.access() == Access::None => Some(SdoAbort::NoObject),
        Side::Bus if !info.access().readable() => Some(SdoAbort::WriteOnly),
        Side::Host if info.host_access() == HostAccess::None => Some(SdoAbort::UnsupportedAccess),
        Side::Host if !info.host_access().readable() => Some(SdoAbort::WriteOnly),
        Side::Bus | Side::Host => None,
    };
    match (required, result) {
        (Some(abort), result) => assert!(result == Err(abort), "the rule's abort"),
        (None, Ok(n)) => assert!(n.total <= usize::from(info.size), "a value fits its entry"),
        (None, Err(_)) => {}
    }
}

/// A dictionary with a generated table and, in place of the generated fields, one cell per
/// Rust type a field of that data type has (`rust_type` in the generator: 24-bit integers in
/// `u32`/`i32`, strings and domains in `Bytes`, of `S` bytes here). The Kani write harnesses
/// prove [`prop_write_is_checked`] on it: symbolic execution of a write into the whole
/// generated struct through `&mut dyn OdValue` did not end (see verification/README.md), while
/// the lookup, the access, length and value checks and every `OdValue` write are the real
/// code here. That the generated fields behave as these cells do, entry by entry, is a test
/// (`tests/dictionary_properties.rs` in the verification crate).
///
/// Entries of one type share a cell: the properties only read back the entry just written.
#[derive(Debug, Clone, PartialEq)]
pub struct TypedCells<const S: usize> {
    entries: &'static [EntryInfo],
    limits: &'static [Limits],
    app: NoAppObjects,
    boolean: bool,
    u8: u8,
    u16: u16,
    u32: u32,
    u64: u64,
    i8: i8,
    i16: i16,
    i32: i32,
    i64: i64,
    f32: f32,
    f64: f64,
    bytes: Bytes<S>,
}

impl<const S: usize> TypedCells<S> {
    /// The table (and limits) of `od`, every cell holding a value taken from `raw`: each
    /// integer and float its first bytes, the boolean bit 0, the string the first `text_len`
    /// (at most 8). Harnesses pass symbolic bytes, so that "a refused write changes nothing"
    /// is checked against any stored value, not only against zero.
    pub fn over<D: EntryAccess>(od: &D, raw: [u8; 8], text_len: usize) -> Self {
        let [b0, b1, b2, b3, ..] = raw;
        TypedCells {
            entries: od.entries(),
            limits: od.limits(),
            app: NoAppObjects,
            boolean: b0 & 1 != 0,
            u8: b0,
            u16: u16::from_le_bytes([b0, b1]),
            u32: u32::from_le_bytes([b0, b1, b2, b3]),
            u64: u64::from_le_bytes(raw),
            i8: b0 as i8,
            i16: i16::from_le_bytes([b0, b1]),
            i32: i32::from_le_bytes([b0, b1, b2, b3]),
            i64: i64::from_le_bytes(raw),
            f32: f32::from_le_bytes([b0, b1, b2, b3]),
            f64: f64::from_le_bytes(raw),
            bytes: Bytes::from_slice(raw.get(..text_len).unwrap_or(&raw)),
        }
    }
}

impl<const S: usize> EntryAccess for TypedCells<S> {
    type App = NoAppObjects;

    fn entries(&self) -> &'static [EntryInfo] {
        self.entries
    }

    fn limits(&self) -> &'static [Limits] {
        self.limits
    }

    fn field(&mut self, info: &EntryInfo, _: u8) -> Option<&mut dyn OdValue> {
        use DataType::*;
        if info.storage() == Storage::App {
            return None;
        }
        Some(match info.data_type() {
            Boolean => &mut self.boolean,
            Unsigned8 => &mut self.u8,
            Unsigned16 => &mut self.u16,
            Unsigned24 | Unsigned32 => &mut self.u32,
            Unsigned40 | Unsigned48 | Unsigned56 | Unsigned64 => &mut self.u64,
            Integer8 => &mut self.i8,
            Integer16 => &mut self.i16,
            Integer24 | Integer32 => &mut self.i32,
            Integer40 | Integer48 | Integer56 | Integer64 => &mut self.i64,
            Real32 => &mut self.f32,
            Real64 => &mut self.f64,
            VisibleString | OctetString | UnicodeString | Domain | TimeOfDay | TimeDifference => &mut self.bytes,
        })
    }

    fn app(&mut self) -> &mut NoAppObjects {
        &mut self.app
    }
}
