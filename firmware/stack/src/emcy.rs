//! Emergency producer (CiA 301 7.2.7; objects 1001h, 1003h, 1014h, 1015h).
//!
//! The producer keeps the set of active errors, so that 1001h is always the OR of their
//! register bits and an error that clears sends the "error reset" emergency. Frames wait in a
//! short queue and leave no closer together than the inhibit time.

use crate::ring::Ring;
pub use coforge_types::EmcyEvent;
use heapless::Vec;

/// The NMT reaction a spec emergency asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reaction {
    None,
    /// As 1029h says (sub 1 for communication errors, sub 2 for application errors).
    ErrorBehaviour,
    PreOperational,
    Stopped,
}

/// An emergency as the spec lists it. Its spec name is not here, so that no image carries
/// the names: hosts find emergencies by name through the generated `emcy::by_name`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EmcyDefault {
    pub code: u16,
    pub register: u8,
    /// Bytes 3..7 (bytes the spec marks as varying are zero).
    pub manufacturer: [u8; 5],
    pub reaction: Reaction,
    pub event: Option<EmcyEvent>,
    /// An object whose value 0 disables this emergency.
    pub enabled_by: Option<u16>,
}

impl EmcyDefault {
    /// The spec emergency for `event`, or the CiA 301 one.
    pub fn for_event(event: EmcyEvent, spec: &'static [EmcyDefault]) -> EmcyDefault {
        spec.iter().find(|e| e.event == Some(event)).copied().unwrap_or(EmcyDefault {
            code: event.default_code(),
            // Every stack event is a communication error: generic + communication bits.
            register: 0x11,
            manufacturer: [0; 5],
            reaction: if event.is_communication_error() { Reaction::ErrorBehaviour } else { Reaction::None },
            event: Some(event),
            enabled_by: None,
        })
    }
}

/// Error register bits (1001h): bit 0 generic, bit 4 communication, and so on.
pub type ErrorRegister = u8;

/// One active error: its code, manufacturer bytes and stack event identify it (two CiA
/// defaults may share a code, such as 8100h for a CAN warning and a SYNC timeout).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Active {
    code: u16,
    register: ErrorRegister,
    manufacturer: [u8; 5],
    event: Option<EmcyEvent>,
}

impl Active {
    fn is(&self, e: &EmcyDefault) -> bool {
        self.code == e.code && self.manufacturer == e.manufacturer && self.event == e.event
    }
}

/// How many errors can be active at once; more are still sent, but not tracked for 1001h.
pub const MAX_ACTIVE: usize = 8;
const QUEUE: usize = 6;

/// What the producer changed, for the node to mirror into the dictionary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Change {
    /// The new 1001h value.
    pub register: ErrorRegister,
    /// A new error to put at the top of 1003h.
    pub history: Option<u32>,
}

#[derive(Debug, Clone)]
pub struct EmcyProducer {
    active: Vec<Active, MAX_ACTIVE>,
    queue: Ring<[u8; 8], QUEUE>,
    last_sent_us: Option<u64>,
    /// Frames lost because the queue was full (CAN overrun of our own making).
    pub dropped: u32,
    /// Bytes 3..7 of every frame carry the OR of the active errors' manufacturer bytes
    /// (frenzel+berg CO40xx codes: "the bitmap of all active errors is combined with OR").
    combine: bool,
    /// Counts changes of the active set (raise, clear, reset), wrapping: a byte, since a
    /// reader compares it after every input, never 256 changes apart.
    changes: u8,
}

impl Default for EmcyProducer {
    fn default() -> Self {
        EmcyProducer::new()
    }
}

impl EmcyProducer {
    pub const fn new() -> Self {
        EmcyProducer { active: Vec::new(), queue: Ring::new([0; 8]), last_sent_us: None, dropped: 0, combine: false, changes: 0 }
    }

    /// A producer whose frames carry the OR of every active error's manufacturer bytes.
    pub const fn combining() -> Self {
        EmcyProducer { active: Vec::new(), queue: Ring::new([0; 8]), last_sent_us: None, dropped: 0, combine: true, changes: 0 }
    }

    /// The manufacturer bytes of a frame sent now: the raised error's own (`own`), or the OR
    /// of every active error's when combining.
    fn manufacturer(&self, own: [u8; 5]) -> [u8; 5] {
        if !self.combine {
            return own;
        }
        self.active.iter().fold([0; 5], |mut acc, a| {
            acc.iter_mut().zip(a.manufacturer).for_each(|(x, m)| *x |= m);
            acc
        })
    }

    /// The error register: the OR of the active errors, with the generic bit when any is.
    pub fn register(&self) -> ErrorRegister {
        let bits = self.active.iter().fold(0, |acc, a| acc | a.register);
        if self.active.is_empty() { 0 } else { bits | 0x01 }
    }

    pub fn is_active(&self, e: &EmcyDefault) -> bool {
        self.active.iter().any(|a| a.is(e))
    }

    /// How often the set of active errors changed (raise, clear, reset; wrapping): whoever
    /// mirrors conditions into errors needs to look again only when this moved.
    pub const fn changes(&self) -> u8 {
        self.changes
    }

    /// Raises an error; `None` if it was already active (nothing is sent twice).
    pub fn raise(&mut self, e: &EmcyDefault) -> Option<Change> {
        if self.is_active(e) {
            return None;
        }
        // A full table still reports the error; it only cannot be cleared individually.
        let _ = self.active.push(Active { code: e.code, register: e.register, manufacturer: e.manufacturer, event: e.event });
        self.changes = self.changes.wrapping_add(1);
        let register = self.register();
        self.enqueue(e.code, register, self.manufacturer(e.manufacturer));
        Some(Change { register, history: Some(u32::from(e.code) | u32::from(e.manufacturer[0]) << 16 | u32::from(e.manufacturer[1]) << 24) })
    }

    /// Clears an active error and sends "error reset" (code 0000h) with what remains.
    pub fn clear(&mut self, e: &EmcyDefault) -> Option<Change> {
        let at = self.active.iter().position(|a| a.is(e))?;
        // `swap_remove` by hand: heapless's copies with `ptr::copy`, which links a 1.3 KiB
        // `memmove` into images that need it nowhere else.
        let last = self.active.pop()?;
        if let Some(slot) = self.active.get_mut(at) {
            *slot = last;
        }
        self.changes = self.changes.wrapping_add(1);
        let register = self.register();
        self.enqueue(0x0000, register, self.manufacturer([0; 5]));
        Some(Change { register, history: None })
    }

    /// Forgets every active error without sending anything (NMT reset).
    pub fn reset(&mut self) {
        self.active.clear();
        self.changes = self.changes.wrapping_add(1);
        self.queue.clear();
        self.last_sent_us = None;
    }

    fn enqueue(&mut self, code: u16, register: ErrorRegister, m: [u8; 5]) {
        let [c0, c1] = code.to_le_bytes();
        if self.queue.push_back([c0, c1, register, m[0], m[1], m[2], m[3], m[4]]).is_err() {
            self.dropped = self.dropped.saturating_add(1);
        }
    }

    /// The next frame's payload if the inhibit time (in 100 us units, 1015h) allows one now.
    pub fn next(&mut self, now_us: u64, inhibit_100us: u16) -> Option<[u8; 8]> {
        let inhibit = u64::from(inhibit_100us) * 100;
        if self.last_sent_us.is_some_and(|t| now_us.saturating_sub(t) < inhibit) {
            return None;
        }
        let frame = self.queue.pop_front()?;
        self.last_sent_us = Some(now_us);
        Some(frame)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const OVERLOAD: EmcyDefault =
        EmcyDefault { code: 0x2310, register: 0x03, manufacturer: [0, 1, 0, 0, 0], reaction: Reaction::ErrorBehaviour, event: None, enabled_by: None };

    #[test]
    fn raising_and_clearing_keeps_the_register_consistent() {
        let mut p = EmcyProducer::new();
        let change = p.raise(&OVERLOAD).unwrap();
        assert_eq!(change.register, 0x03);
        assert_eq!(change.history, Some(0x0100_2310));
        assert_eq!(p.raise(&OVERLOAD), None, "an active error is not sent again");
        let guard = EmcyDefault::for_event(EmcyEvent::LifeGuarding, &[]);
        assert_eq!((guard.code, guard.register), (0x8130, 0x11));
        assert_eq!(p.raise(&guard).unwrap().register, 0x13);
        assert_eq!(p.clear(&OVERLOAD).unwrap().register, 0x11);
        assert_eq!(p.clear(&OVERLOAD), None, "already cleared");
        assert_eq!(p.next(0, 0), Some([0x10, 0x23, 0x03, 0, 1, 0, 0, 0]));
        assert_eq!(p.next(0, 0), Some([0x30, 0x81, 0x13, 0, 0, 0, 0, 0]));
        assert_eq!(p.next(0, 0), Some([0x00, 0x00, 0x11, 0, 0, 0, 0, 0]), "error reset carries what remains");
        assert_eq!(p.next(0, 0), None);
    }

    #[test]
    fn inhibit_time_spaces_frames() {
        let mut p = EmcyProducer::new();
        p.raise(&OVERLOAD);
        p.clear(&OVERLOAD);
        assert!(p.next(1_000, 50).is_some());
        assert_eq!(p.next(5_999, 50), None, "5 ms inhibit");
        assert!(p.next(6_000, 50).is_some());
    }

    #[test]
    fn a_combining_producer_ors_the_codes_of_every_active_error() {
        let bank1 = EmcyDefault { code: 0x1000, register: 0x01, manufacturer: [0, 0x10, 0, 0, 0], reaction: Reaction::None, event: None, enabled_by: None };
        let low = EmcyDefault { manufacturer: [0, 0x40, 0, 0, 0], ..bank1 };
        let mut p = EmcyProducer::combining();
        p.raise(&bank1);
        p.raise(&low);
        p.clear(&bank1);
        let frames: Vec<[u8; 8], 4> = core::iter::from_fn(|| p.next(0, 0)).collect();
        assert_eq!(frames.as_slice(), [[0x00, 0x10, 0x01, 0, 0x10, 0, 0, 0], [0x00, 0x10, 0x01, 0, 0x50, 0, 0, 0], [0, 0, 0x01, 0, 0x40, 0, 0, 0]]);
    }

    #[test]
    fn spec_emergencies_take_precedence_over_cia_defaults() {
        static SPEC: [EmcyDefault; 1] = [EmcyDefault { event: Some(EmcyEvent::BusOff), code: 0x8140, register: 0x11, ..OVERLOAD }];
        assert_eq!(EmcyDefault::for_event(EmcyEvent::BusOff, &SPEC).manufacturer, [0, 1, 0, 0, 0]);
        assert_eq!(EmcyDefault::for_event(EmcyEvent::RpdoLength, &SPEC).code, 0x8210);
    }
}
