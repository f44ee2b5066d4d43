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
    /// Whether the LED is lit `now_ms` after an arbitrary epoch. (The remainder is taken by
    /// [`div_rem_u64`]: no 64-bit division on a Cortex-M0.)
    pub const fn level(self, now_ms: u64) -> bool {
        self.level_in_period(div_rem_u64(now_ms, self.period()).1)
    }

    /// The pattern's period in ms (1 for the steady states).
    pub const fn period(self) -> u16 {
        match self {
            LedState::Off | LedState::On => 1,
            LedState::Flickering => 100,
            LedState::Blinking => 400,
            // n flashes of 200 ms on / 200 ms off, the last off phase stretched to 1000 ms.
            LedState::SingleFlash => 1200,
            LedState::DoubleFlash => 1600,
            LedState::TripleFlash => 2000,
        }
    }

    /// Whether the LED is lit `t` ms into its period (`t` < [`period`](Self::period)): a
    /// board that keeps its milliseconds in 32 bits takes the remainder itself.
    pub const fn level_in_period(self, t: u32) -> bool {
        match self {
            LedState::Off => false,
            LedState::On => true,
            LedState::Flickering => t < 50,
            LedState::Blinking => t < 200,
            LedState::SingleFlash | LedState::DoubleFlash | LedState::TripleFlash => t < self.period() as u32 - 800 && t % 400 < 200,
        }
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
    fn the_level_is_the_level_in_the_period_on_any_clock() {
        // The 64-bit clock's patterns, computed with u64 remainders, as they always were.
        fn reference(s: LedState, now_ms: u64) -> bool {
            let flashes = match s {
                LedState::Off => return false,
                LedState::On => return true,
                LedState::Flickering => return now_ms % 100 < 50,
                LedState::Blinking => return now_ms % 400 < 200,
                LedState::SingleFlash => 1,
                LedState::DoubleFlash => 2,
                LedState::TripleFlash => 3,
            };
            let t = now_ms % (flashes * 400 + 800);
            t < flashes * 400 && t % 400 < 200
        }
        let all = [LedState::Off, LedState::On, LedState::Flickering, LedState::Blinking, LedState::SingleFlash, LedState::DoubleFlash, LedState::TripleFlash];
        for s in all {
            for base in [0, 1 << 32, u64::MAX - 5000, 123_456_789_012] {
                for t in (0..4000).map(|t| base.wrapping_add(t)) {
                    assert_eq!(s.level(t), reference(s, t), "{s:?} at {t}");
                    assert_eq!(s.level_in_period((t % u64::from(s.period())) as u32), reference(s, t));
                }
            }
        }
    }

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
