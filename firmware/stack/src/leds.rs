//! CiA 303-3 indicator states: what the run and error LEDs show, as levels the board puts on
//! its pins.

use crate::time::div_rem_u64;

/// A CiA 303-3 LED pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LedState {
    Off,
    On,
    /// 50 ms on, 50 ms off (auto-baud / LSS).
    Flickering,
    /// 200 ms on, 200 ms off.
    Blinking,
    /// One 200 ms flash, then 1000 ms off.
    SingleFlash,
    /// Two flashes, then 1000 ms off.
    DoubleFlash,
    /// Three flashes, then 1000 ms off.
    TripleFlash,
}

impl LedState {
    /// Whether the LED is lit `now_ms` after an arbitrary epoch.
    /// (The remainders are taken by [`div_rem_u64`]: no 64-bit division on a Cortex-M0.)
    pub const fn level(self, now_ms: u64) -> bool {
        let flashes = match self {
            LedState::Off => return false,
            LedState::On => return true,
            LedState::Flickering => return div_rem_u64(now_ms, 100).1 < 50,
            LedState::Blinking => return div_rem_u64(now_ms, 400).1 < 200,
            LedState::SingleFlash => 1,
            LedState::DoubleFlash => 2,
            LedState::TripleFlash => 3,
        };
        // n flashes of 200 ms on / 200 ms off, the last off phase stretched to 1000 ms.
        let period = flashes * 400 + 800;
        let t = div_rem_u64(now_ms, period).1;
        t < flashes as u32 * 400 && t % 400 < 200
    }
}

/// Both indicators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Leds {
    pub run: LedState,
    pub error: LedState,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_follow_cia_303_3_timing() {
        assert!(LedState::On.level(123) && !LedState::Off.level(123));
        assert!(LedState::Blinking.level(0) && !LedState::Blinking.level(200) && LedState::Blinking.level(400));
        assert!(LedState::Flickering.level(49) && !LedState::Flickering.level(50));
        let lit = |s: LedState, period: u64| (0..period).filter(|&t| s.level(t)).count();
        assert_eq!(lit(LedState::SingleFlash, 1200), 200);
        assert_eq!(lit(LedState::DoubleFlash, 1600), 400);
        assert_eq!(lit(LedState::TripleFlash, 2000), 600);
        // The double flash: on, off, on, then 1000 ms dark.
        assert!(LedState::DoubleFlash.level(0) && !LedState::DoubleFlash.level(250) && LedState::DoubleFlash.level(450));
        assert!((600..1600).all(|t| !LedState::DoubleFlash.level(t)));
    }
}
