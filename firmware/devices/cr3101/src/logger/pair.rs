//! A redundant pair (2002h/2003h): a change takes effect only once both halves hold the same
//! value, so that one stray write cannot re-lay out the card.

/// The two halves and the value in effect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RedundantPair<T> {
    first: T,
    second: T,
    effective: T,
}

impl<T: Copy + PartialEq> RedundantPair<T> {
    /// Both halves and the effective value `value` (at start-up: what the card holds).
    pub const fn new(value: T) -> Self {
        RedundantPair { first: value, second: value, effective: value }
    }

    pub fn first(&self) -> T {
        self.first
    }

    pub fn second(&self) -> T {
        self.second
    }

    pub fn effective(&self) -> T {
        self.effective
    }

    /// Writes the first half: `Some(new value)` if the pair now agrees on a value other than
    /// the effective one (the change takes effect).
    pub fn write_first(&mut self, value: T) -> Option<T> {
        self.first = value;
        self.settle()
    }

    /// Writes the second half, as [`RedundantPair::write_first`].
    pub fn write_second(&mut self, value: T) -> Option<T> {
        self.second = value;
        self.settle()
    }

    fn settle(&mut self) -> Option<T> {
        (self.first == self.second && self.first != self.effective).then(|| {
            self.effective = self.first;
            self.effective
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_change_takes_effect_when_both_halves_agree() {
        let mut p = RedundantPair::new(1000_u32);
        assert_eq!(p.write_first(2048), None, "one half alone changes nothing");
        assert_eq!(p.effective(), 1000);
        assert_eq!(p.write_second(4096), None, "halves that disagree change nothing");
        assert_eq!(p.write_second(2048), Some(2048));
        assert_eq!(p.effective(), 2048);
        assert_eq!(p.write_first(2048), None, "agreeing on the value in effect is no change");
        // Either order.
        assert_eq!(p.write_second(512), None);
        assert_eq!(p.write_first(512), Some(512));
        assert_eq!((p.first(), p.second(), p.effective()), (512, 512, 512));
    }
}
