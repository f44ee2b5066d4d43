//! Runtime state of one RPDO or TPDO: its communication parameters (14xxh/18xxh), cached
//! mapping, and the timers and buffers its transmission type needs.

use super::{COB_EXTENDED, COB_INVALID, COB_NO_RTR, Dir, Mapping};
use crate::od::{EntryAccess, SdoAbort};

/// Communication parameters as read from 14xxh/18xxh.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Comm {
    pub cob_id: u32,
    pub transmission_type: u8,
    /// Multiples of 100 us (sub 3).
    pub inhibit_time: u16,
    /// Milliseconds (sub 5).
    pub event_timer: u16,
    /// SYNC counter value that starts a synchronous TPDO (sub 6).
    pub sync_start: u8,
}

impl Comm {
    /// Reads the parameters of the PDO whose communication object is `index`; sub-entries
    /// the spec leaves out read as 0.
    pub fn read(od: &mut impl EntryAccess, index: u16) -> Comm {
        let int = |od: &mut _, sub| crate::node::read_u32(od, index, sub).unwrap_or(0);
        Comm {
            cob_id: int(od, 1),
            transmission_type: int(od, 2) as u8,
            inhibit_time: int(od, 3) as u16,
            event_timer: int(od, 5) as u16,
            sync_start: int(od, 6) as u8,
        }
    }

    /// Valid (bit 31 clear) and an 11-bit identifier.
    pub const fn valid(&self) -> bool {
        self.cob_id & (COB_INVALID | COB_EXTENDED) == 0
    }

    pub const fn id(&self) -> u16 {
        (self.cob_id & 0x7FF) as u16
    }

    pub const fn rtr_allowed(&self) -> bool {
        self.cob_id & COB_NO_RTR == 0
    }

    /// Transmission types 0..=240: acted on at SYNC.
    pub const fn synchronous(&self) -> bool {
        self.transmission_type <= 240
    }

    /// Transmission types 254 and 255: event-driven.
    pub const fn event_driven(&self) -> bool {
        self.transmission_type >= 254
    }
}

/// The first `count` entries (subs 1..=count) of mapping object `index`: `PdoTooLong` if
/// more than a frame can carry, `InvalidValue` if the object has fewer sub-indices.
pub fn mapping_words(od: &mut impl EntryAccess, index: u16, count: u32) -> Result<([u32; 8], usize), SdoAbort> {
    let mut words = [0_u32; 8];
    let count = usize::try_from(count).unwrap_or(usize::MAX);
    if count > words.len() {
        return Err(SdoAbort::PdoTooLong);
    }
    for (sub, w) in (1..=8_u8).zip(words.iter_mut()).take(count) {
        od.entry(index, sub).map_err(|_| SdoAbort::InvalidValue)?;
        *w = crate::node::read_u32(od, index, sub).unwrap_or(0);
    }
    Ok((words, count))
}

/// Reads a mapping object (sub 0 = count, subs 1..=count the entries) and checks it; an
/// invalid stored mapping counts as empty.
pub fn read_mapping(od: &mut impl EntryAccess, index: u16, dir: Dir) -> Mapping {
    let count = crate::node::read_u32(od, index, 0).unwrap_or(0);
    mapping_words(od, index, count).and_then(|(words, n)| Mapping::check(od, words.get(..n).unwrap_or(&[]), dir)).unwrap_or_default()
}

/// A receive PDO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rpdo {
    /// 1400h + `offset` is its communication object.
    pub offset: u16,
    pub comm: Comm,
    pub mapping: Mapping,
    /// Data of a synchronous RPDO, applied at the next SYNC.
    pub latched: Option<([u8; 8], u8)>,
    /// The next reception is due by then (event timer, sub 5); [`NEVER`] until the first
    /// reception or without an event timer.
    pub deadline_us: u64,
    /// The deadline passed and was reported.
    pub timed_out: bool,
}

impl Rpdo {
    pub fn load(od: &mut impl EntryAccess, offset: u16) -> Rpdo {
        let index = Dir::Rx.comm_base() + offset;
        Rpdo {
            offset,
            comm: Comm::read(od, index),
            mapping: read_mapping(od, Dir::mapping_of(index), Dir::Rx),
            latched: None,
            deadline_us: NEVER,
            timed_out: false,
        }
    }

    /// A reception at `now_us`: restarts deadline monitoring. True if it ends a timeout.
    pub fn received(&mut self, now_us: u64) -> bool {
        if self.comm.event_timer != 0 {
            self.deadline_us = crate::time::later_us(now_us, self.comm.event_timer.into(), 1000);
        }
        core::mem::take(&mut self.timed_out)
    }

    /// Whether the deadline passed at `now_us` (reported once per timeout).
    pub fn overdue(&mut self, now_us: u64) -> bool {
        if self.comm.valid() && !self.timed_out && now_us > self.deadline_us {
            self.timed_out = true;
            return true;
        }
        false
    }
}

/// An event timer that is off (a plain `u64` keeps each TPDO 8 bytes smaller than `Option`).
pub const NEVER: u64 = u64::MAX;

/// A transmit PDO.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tpdo {
    /// 1800h + `offset` is its communication object.
    pub offset: u16,
    pub comm: Comm,
    pub mapping: Mapping,
    /// An event is waiting for the inhibit time (254/255) or the next SYNC (0).
    pub pending: bool,
    /// No transmission before this time (inhibit time).
    pub inhibit_until_us: u64,
    /// When the event timer next fires ([`NEVER`] if it is off).
    pub event_due_us: u64,
    /// SYNCs counted towards the next transmission (types 1..=240).
    pub sync_count: u8,
    /// Waiting for the SYNC counter to reach `sync_start`.
    pub waiting_for_start: bool,
    /// Data sampled at the last SYNC (type 252), sent on RTR.
    pub sampled: Option<([u8; 8], u8)>,
}

impl Tpdo {
    pub fn load(od: &mut impl EntryAccess, offset: u16, now_us: u64) -> Tpdo {
        let index = Dir::Tx.comm_base() + offset;
        let comm = Comm::read(od, index);
        let mut t = Tpdo {
            offset,
            comm,
            mapping: read_mapping(od, Dir::mapping_of(index), Dir::Tx),
            pending: false,
            inhibit_until_us: 0,
            event_due_us: NEVER,
            sync_count: 0,
            waiting_for_start: false,
            sampled: None,
        };
        t.restart(now_us);
        t
    }

    /// Back to the state after configuration: event timer armed, counters cleared.
    pub fn restart(&mut self, now_us: u64) {
        self.pending = false;
        self.sync_count = 0;
        self.sampled = None;
        self.waiting_for_start = self.comm.sync_start != 0;
        self.inhibit_until_us = now_us;
        self.event_due_us =
            if self.comm.event_driven() && self.comm.event_timer != 0 { crate::time::later_us(now_us, self.comm.event_timer.into(), 1000) } else { NEVER };
    }

    /// Whether a SYNC with optional `counter` makes this TPDO send (types 0..=240), or
    /// sample (252). Returns true if it should go out now.
    pub fn on_sync(&mut self, counter: Option<u8>) -> bool {
        let t = self.comm.transmission_type;
        if self.waiting_for_start {
            // CiA 301: with a SYNC counter, start counting at the SYNC whose counter equals sub 6.
            match counter {
                Some(c) if c == self.comm.sync_start => self.waiting_for_start = false,
                Some(_) => return false,
                None => self.waiting_for_start = false,
            }
        }
        match t {
            0 => core::mem::take(&mut self.pending),
            1..=240 => {
                self.sync_count = self.sync_count.saturating_add(1);
                if self.sync_count >= t {
                    self.sync_count = 0;
                    true
                } else {
                    false
                }
            }
            _ => false,
        }
    }

    /// An application event (or a write to a mapped object).
    pub fn trigger(&mut self) {
        if matches!(self.comm.transmission_type, 0 | 254 | 255) {
            self.pending = true;
        }
    }

    /// Whether an event-driven TPDO should go out at `now_us` (event timer or a pending event,
    /// inhibit time respected).
    pub fn due(&mut self, now_us: u64) -> bool {
        if !self.comm.event_driven() {
            return false;
        }
        if now_us >= self.event_due_us {
            self.pending = true;
        }
        self.pending && now_us >= self.inhibit_until_us
    }

    /// Records a transmission at `now_us`: inhibit time and event timer restart.
    pub fn sent(&mut self, now_us: u64) {
        self.pending = false;
        self.inhibit_until_us = crate::time::later_us(now_us, self.comm.inhibit_time.into(), 100);
        if self.comm.event_driven() && self.comm.event_timer != 0 {
            self.event_due_us = crate::time::later_us(now_us, self.comm.event_timer.into(), 1000);
        }
    }
}
