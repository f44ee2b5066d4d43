//! Node guarding and life guarding (CiA 301 7.2.8.3.2.1; objects 100Ch, 100Dh).

/// What the guarding monitor detected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GuardEvent {
    /// No guarding request within the guard time (frenzel+berg's early warning).
    Warning,
    /// No guarding request within the node life time: a life guarding error.
    LifeLost,
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Guarding {
    guard_ms: u16,
    factor: u8,
    toggle: bool,
    /// Life guarding starts with the first guarding request.
    last_rtr_us: Option<u64>,
    warned: bool,
    lost: bool,
}

impl Guarding {
    pub fn configure(&mut self, guard_ms: u16, factor: u8) {
        self.guard_ms = guard_ms;
        self.factor = factor;
    }

    /// Back to the state after reset communication: toggle 0, not started.
    pub fn reset(&mut self) {
        *self = Guarding { guard_ms: self.guard_ms, factor: self.factor, ..Guarding::default() };
    }

    /// A guarding request: the answer's byte (toggle bit 7 + state code) and the events that
    /// ended with it.
    pub fn on_request(&mut self, state_code: u8, now_us: u64) -> (u8, bool, bool) {
        let byte = state_code & 0x7F | if self.toggle { 0x80 } else { 0 };
        self.toggle = !self.toggle;
        self.last_rtr_us = Some(now_us);
        (byte, core::mem::take(&mut self.warned), core::mem::take(&mut self.lost))
    }

    pub const fn life_time_us(&self) -> u64 {
        self.guard_ms as u64 * self.factor as u64 * 1000
    }

    /// The next guarding event due at `now_us`, each reported once per missing request.
    pub fn check(&mut self, now_us: u64) -> Option<GuardEvent> {
        let since = now_us.saturating_sub(self.last_rtr_us?);
        let life = self.life_time_us();
        if life != 0 && since > life && !self.lost {
            self.lost = true;
            return Some(GuardEvent::LifeLost);
        }
        if self.guard_ms != 0 && since > u64::from(self.guard_ms) * 1000 && !self.warned {
            self.warned = true;
            return Some(GuardEvent::Warning);
        }
        None
    }

    pub const fn lost(&self) -> bool {
        self.lost
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn answers_toggle_and_life_time_is_guard_time_times_factor() {
        let mut g = Guarding::default();
        g.configure(100, 3);
        assert_eq!(g.check(10_000_000), None, "not started before the first request");
        assert_eq!(g.on_request(0x7F, 0).0, 0x7F);
        assert_eq!(g.on_request(0x05, 50_000).0, 0x85);
        assert_eq!(g.on_request(0x05, 100_000).0, 0x05);
        assert_eq!(g.check(200_000), None);
        assert_eq!(g.check(200_001), Some(GuardEvent::Warning));
        assert_eq!(g.check(300_000), None);
        assert_eq!(g.check(400_001), Some(GuardEvent::LifeLost));
        assert_eq!(g.check(900_000), None, "reported once");
        let (_, warned, lost) = g.on_request(0x05, 1_000_000);
        assert!(warned && lost);
        g.reset();
        assert_eq!(g.on_request(0x7F, 0).0, 0x7F, "reset communication restarts the toggle at 0");
    }
}
