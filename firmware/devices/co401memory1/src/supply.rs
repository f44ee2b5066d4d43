//! The supply-voltage guard: below 15 V memory writes are refused (voltage low), below 11 V
//! the critical emergency follows. A 200 mV hysteresis keeps a supply hovering at a threshold
//! from sending a stream of emergencies; the datasheet gives only the thresholds.

/// Below this, writes to the memory are refused (datasheet: 15 V).
pub const LOW_MV: u16 = 15_000;
/// Below this, the critical emergency is raised as well (datasheet: 11 V).
pub const CRITICAL_MV: u16 = 11_000;
/// How far above a threshold the supply must rise before the condition ends.
pub const HYSTERESIS_MV: u16 = 200;

/// The guard's state.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord)]
pub enum Supply {
    #[default]
    Normal,
    Low,
    Critical,
}

impl Supply {
    /// The state after measuring `mv`.
    pub fn next(self, mv: u16) -> Supply {
        let above = |threshold: u16| mv >= threshold.saturating_add(HYSTERESIS_MV);
        match self {
            _ if mv < CRITICAL_MV => Supply::Critical,
            _ if mv < LOW_MV => {
                if self == Supply::Critical && !above(CRITICAL_MV) {
                    Supply::Critical
                } else {
                    Supply::Low
                }
            }
            Supply::Normal => Supply::Normal,
            _ if above(LOW_MV) => Supply::Normal,
            _ => Supply::Low,
        }
    }

    /// Memory writes are allowed.
    pub fn writes_allowed(self) -> bool {
        self == Supply::Normal
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_and_hysteresis() {
        let s = Supply::Normal.next(24_000);
        assert_eq!(s, Supply::Normal);
        let s = s.next(14_999);
        assert_eq!(s, Supply::Low);
        assert_eq!(s.next(15_100), Supply::Low, "inside the hysteresis band");
        assert_eq!(s.next(15_200), Supply::Normal);
        let s = s.next(10_999);
        assert_eq!(s, Supply::Critical);
        assert_eq!(s.next(11_100), Supply::Critical);
        assert_eq!(s.next(11_200), Supply::Low);
        assert_eq!(s.next(24_000), Supply::Normal);
        assert_eq!(Supply::Normal.next(0), Supply::Critical);
        assert!(!Supply::Low.writes_allowed());
    }
}
