//! Which copy of a block wins when the two banks are read.
//!
//! Bank 1 (index 0) is always written first and bank 2 second, so after a completed write
//! both carry the same sequence number, and a write cut between the banks leaves bank 1 one
//! step ahead. Repairs copy the winner to the loser with the winner's sequence number.

use crate::status::BankStatus;

/// What reading one copy found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CopyState {
    /// The EEPROM returned an error.
    Unreadable,
    /// Torn or corrupt: the record does not commit this data.
    Invalid,
    /// Committed with this sequence number.
    Valid(u8),
}

/// The decision for one block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Both copies valid, same sequence number, same data.
    Agree,
    /// Use bank `winner`'s copy; rewrite the other bank from it if `repair`, and set `flags`
    /// in the other bank's status.
    Use { winner: usize, repair: bool, flags: u8 },
    /// No valid copy in either bank.
    Lost,
}

/// Decides a block from its two copies; `same_data` says whether their data bytes are equal.
pub fn resolve(a: CopyState, b: CopyState, same_data: bool) -> Verdict {
    use CopyState::*;
    let stale = BankStatus::OVERWRITTEN;
    let corrupt = BankStatus::CHECKSUM_ERROR | BankStatus::OVERWRITTEN;
    match (a, b) {
        (Valid(sa), Valid(sb)) if sa == sb && same_data => Verdict::Agree,
        // A write cut after bank 1 committed: bank 1 holds the newer contents.
        (Valid(sa), Valid(sb)) if sa == sb.wrapping_add(1) => Verdict::Use { winner: 0, repair: true, flags: stale },
        // Same sequence, different data (or sequence numbers no write order produces): an
        // undetectable corruption of one copy. Bank 2 is written last, so it is kept.
        (Valid(sa), Valid(sb)) => Verdict::Use { winner: 1, repair: true, flags: if sa == sb { corrupt } else { stale } },
        (Valid(_), Invalid) => Verdict::Use { winner: 0, repair: true, flags: corrupt },
        (Invalid, Valid(_)) => Verdict::Use { winner: 1, repair: true, flags: corrupt },
        (Valid(_), Unreadable) => Verdict::Use { winner: 0, repair: false, flags: 0 },
        (Unreadable, Valid(_)) => Verdict::Use { winner: 1, repair: false, flags: 0 },
        (Invalid | Unreadable, Invalid | Unreadable) => Verdict::Lost,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use CopyState::*;

    #[test]
    fn the_newer_copy_wins_across_sequence_wrap() {
        assert_eq!(resolve(Valid(0), Valid(255), false), Verdict::Use { winner: 0, repair: true, flags: BankStatus::OVERWRITTEN });
        assert_eq!(resolve(Valid(3), Valid(3), true), Verdict::Agree);
        assert!(matches!(resolve(Valid(3), Valid(3), false), Verdict::Use { winner: 1, .. }));
    }

    #[test]
    fn a_single_valid_copy_wins_and_two_invalid_ones_are_lost() {
        assert!(matches!(resolve(Invalid, Valid(9), false), Verdict::Use { winner: 1, repair: true, .. }));
        assert!(matches!(resolve(Valid(9), Unreadable, false), Verdict::Use { winner: 0, repair: false, .. }));
        assert_eq!(resolve(Invalid, Unreadable, false), Verdict::Lost);
        assert_eq!(resolve(Invalid, Invalid, true), Verdict::Lost);
    }
}
