//! Properties every generated dictionary must have, generic over its [`EntryAccess`]: the
//! harnesses the generator emits for each device under `cfg(kani)` (`od::proofs`) call them
//! with symbolic inputs, and the verification crate's random tests with random ones. Each
//! returns normally when the property holds and panics (an assertion) when it does not.
//!
//! The rules are [`EntryInfo`]'s (one place each); what is checked here is that the
//! dictionary applies them to every access, with the abort each rule names, and that a
//! refused write changes nothing.
#![allow(clippy::panic)]

use super::{Access, AccessContext, EntryAccess, EntryInfo, HostAccess, Limits, NoAppObjects, SdoAbort, Side, Storage, Table};

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

/// A dictionary with a generated table over a value image of `S` bytes (the generated
/// dictionary's size) holding any bytes, without the device's app-backed objects. The Kani
/// write harnesses prove [`prop_write_is_checked`] on it: the lookup, the access, length and
/// value checks and the image writes are the real code, the image's bytes symbolic; the
/// app-backed entries (whose owners serve them, not the dictionary) answer as absent.
#[derive(Debug, Clone, PartialEq)]
pub struct ImageCells<const S: usize> {
    entries: Table<'static>,
    limits: &'static [Limits],
    app: NoAppObjects,
    image: [u8; S],
}

impl<const S: usize> ImageCells<S> {
    /// The table (and limits) of `od` over `image`. Harnesses pass symbolic bytes, so that "a
    /// refused write changes nothing" is checked against any stored value, not only against
    /// the defaults.
    pub fn over<D: EntryAccess>(od: &D, image: [u8; S]) -> Self {
        Self::new(od.entries(), od.limits(), image)
    }

    /// A table and its limits over `image`, without a dictionary to take them from (the
    /// harnesses: building one would unroll its reset over every byte of the image).
    pub fn new(entries: Table<'static>, limits: &'static [Limits], image: [u8; S]) -> Self {
        ImageCells { entries, limits, app: NoAppObjects, image }
    }
}

impl<const S: usize> EntryAccess for ImageCells<S> {
    type App = NoAppObjects;

    fn entries(&self) -> Table<'static> {
        self.entries
    }

    fn limits(&self) -> &'static [Limits] {
        self.limits
    }

    fn image(&self) -> &[u8] {
        &self.image
    }

    fn image_mut(&mut self) -> &mut [u8] {
        &mut self.image
    }

    fn app(&mut self) -> &mut NoAppObjects {
        &mut self.app
    }
}
