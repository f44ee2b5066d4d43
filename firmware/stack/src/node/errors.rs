//! Errors: the EMCY producer's view of the node (1001h, 1003h, 1014h/1015h), the 1029h
//! reaction, bus states and bus-off restart, and the CiA 303-3 indicators.

use super::{BusState, Core, NodeEvent, read_u32};
use crate::emcy::{EmcyDefault, EmcyEvent, Reaction};
use crate::leds::{LedState, Leds};
use crate::nmt::{self, NmtState};
use crate::od::{NodeDictionary, Side};
use crate::pdo::slot::NEVER;
use crate::store::ParamStore;

impl<D: NodeDictionary, S: ParamStore, const P: usize> Core<D, S, P> {
    /// The next queued emergency, if the state and the inhibit time allow it now.
    pub(super) fn send_emcy(&mut self) {
        if nmt::allows_emcy_and_sync(self.state)
            && let Some(cob) = self.emcy_cob
            && let Some(frame) = self.emcy.next(self.now_us, self.emcy_inhibit)
            && self.send(cob, &frame)
        {
            self.event(NodeEvent::EmergencySent(frame));
        }
    }

    /// Bus-off: tells the board to restart the controller once the restart time has passed.
    pub(super) fn check_restart(&mut self, now_us: u64) {
        let since = self.bus_off_since;
        if since == NEVER {
            return;
        }
        let restart_ms = self.cfg.restart_time_object.and_then(|i| read_u32(&mut self.od, i, 0));
        if restart_ms.is_some_and(|ms| ms != 0 && now_us.saturating_sub(since) >= u64::from(ms) * 1000) {
            self.bus_off_since = NEVER;
            self.event(NodeEvent::RestartController);
        }
    }

    pub(super) fn on_bus_state(&mut self, bus: BusState, now_us: u64) {
        let was = core::mem::replace(&mut self.bus, bus);
        if was == bus {
            return;
        }
        match bus {
            BusState::BusOff => {
                self.bus_off_since = now_us;
                self.raise_event(EmcyEvent::BusOff);
            }
            BusState::Warning => self.raise_event(EmcyEvent::CanWarning),
            BusState::Passive => self.raise_event(EmcyEvent::CanPassive),
            BusState::Active => {}
        }
        if was == BusState::BusOff && bus != BusState::BusOff {
            self.bus_off_since = NEVER;
            self.clear_event(EmcyEvent::BusOff);
            // "Return from bus-off" is an event, not a condition: raised and cleared at once.
            self.raise_event(EmcyEvent::BusOffRecovered);
            self.clear_event(EmcyEvent::BusOffRecovered);
        }
        if matches!(bus, BusState::Active) {
            self.clear_event(EmcyEvent::CanWarning);
            self.clear_event(EmcyEvent::CanPassive);
        }
    }

    /// The emergency a stack event sends: the spec's, else the CiA 301 default. This is the
    /// only place the node makes a default emergency, and it makes none where a device sends
    /// only what its spec lists (`listed_emergencies_only`). Events whose frame is
    /// device-specific are only sent if the spec lists them: the guarding warning, and bus-off
    /// and its end (a node cannot send while bus-off; datasheets differ in what goes out on
    /// the return).
    pub(super) fn event_emcy(&self, event: EmcyEvent) -> Option<EmcyDefault> {
        // One search of the spec's list; the CiA 301 default only where none is listed.
        match (self.od.emergencies().iter().find(|e| e.event == Some(event)), event) {
            (Some(e), _) => Some(*e),
            (None, _) if self.cfg.listed_emergencies_only => None,
            (None, EmcyEvent::GuardingWarning | EmcyEvent::BusOff | EmcyEvent::BusOffRecovered) => None,
            (None, _) => Some(EmcyDefault::for_event(event, &[])),
        }
    }

    pub(super) fn raise_event(&mut self, event: EmcyEvent) {
        match self.event_emcy(event) {
            Some(e) => self.raise(&e, event.is_communication_error()),
            // Without an emergency to send, a communication error still gets its 1029h reaction.
            None if event.is_communication_error() => self.react(Reaction::ErrorBehaviour, true),
            None => {}
        }
    }

    pub(super) fn clear_event(&mut self, event: EmcyEvent) {
        if let Some(e) = self.event_emcy(event) {
            self.clear(&e);
        }
    }

    pub(super) fn raise(&mut self, e: &EmcyDefault, communication: bool) {
        if let Some(index) = e.enabled_by
            && read_u32(&mut self.od, index, 0) == Some(0)
        {
            return;
        }
        let Some(change) = self.emcy.raise(e) else { return };
        self.mirror_error_register(change.register);
        if D::COMM.error_history
            && let Some(entry) = change.history
        {
            self.push_history(entry);
        }
        // Sent before the reaction: an error that stops the node must still be reported.
        self.send_emcy();
        self.react(e.reaction, communication);
    }

    pub(super) fn clear(&mut self, e: &EmcyDefault) {
        if let Some(change) = self.emcy.clear(e) {
            self.mirror_error_register(change.register);
        }
    }

    /// 1029h: what a communication (sub 1) or application (sub 2) error does to the state.
    pub(super) fn react(&mut self, reaction: Reaction, communication: bool) {
        let behaviour = match reaction {
            Reaction::None => return,
            Reaction::PreOperational => 0,
            Reaction::Stopped => 2,
            Reaction::ErrorBehaviour => {
                let sub = if communication { 1 } else { 2 };
                read_u32(&mut self.od, 0x1029, sub).or_else(|| read_u32(&mut self.od, 0x1029, 1)).unwrap_or(0)
            }
        };
        match behaviour {
            0 if self.state == NmtState::Operational => self.set_state(NmtState::PreOperational),
            2 => self.set_state(NmtState::Stopped),
            _ => {}
        }
    }

    pub(super) fn mirror_error_register(&mut self, register: u8) {
        let ctx = self.ctx();
        let _ = self.od.write(0x1001, 0, &[register], Side::Device, &ctx);
    }

    /// 1003h: newest error at sub 1, older ones shift down, sub 0 counts them.
    pub(super) fn push_history(&mut self, entry: u32) {
        let slots = (1..=254_u8).take_while(|&s| self.od.entry(0x1003, s).is_ok()).count() as u8;
        if slots == 0 {
            return;
        }
        let ctx = self.ctx();
        let count = read_u32(&mut self.od, 0x1003, 0).unwrap_or(0).min(u32::from(slots)) as u8;
        let mut sub = count.saturating_add(1).min(slots);
        while sub > 1 {
            if let Some(older) = read_u32(&mut self.od, 0x1003, sub - 1) {
                let _ = self.od.write(0x1003, sub, &older.to_le_bytes(), Side::Device, &ctx);
            }
            sub -= 1;
        }
        let _ = self.od.write(0x1003, 1, &entry.to_le_bytes(), Side::Device, &ctx);
        let _ = self.od.write(0x1003, 0, &[count.saturating_add(1).min(slots)], Side::Device, &ctx);
    }

    pub(super) fn leds(&self) -> Leds {
        let run = match self.state {
            NmtState::Stopped => LedState::SingleFlash,
            NmtState::PreOperational => LedState::Blinking,
            NmtState::Operational => LedState::On,
        };
        let error = match self.bus {
            BusState::BusOff => LedState::On,
            _ if self.guarding.lost() || self.consumer.any_lost() => LedState::DoubleFlash,
            _ if self.sync_lost => LedState::TripleFlash,
            BusState::Warning | BusState::Passive => LedState::SingleFlash,
            BusState::Active => LedState::Off,
        };
        Leds { run, error }
    }
}
