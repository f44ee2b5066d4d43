//! The commit record after each block copy, and the write order that makes a torn write
//! detectable without relying on the checksum.
//!
//! A record is `begin | crc lo | crc hi | end`. A copy is valid when `begin == end` and the
//! CRC matches the data and that sequence number. A write of sequence number `t` goes:
//!
//! 1. `begin` := a mark different from the stored `end` (normally `t` itself), so the copy
//!    is invalid before any data byte changes. Skipped when `begin != end` already: such a
//!    copy is invalid, and a mark cut to the value of the stored `end` could make its stale
//!    contents valid again;
//! 2. the changed data bytes, then the CRC of the new data with `t`;
//! 3. `begin` := `t` unless it says `t`, then `end` := `t` unless it says `t`: the last byte
//!    written makes `begin == end == t` and commits the copy (two bytes only when step 1 was
//!    skipped and neither marker said `t`).
//!
//! Every state between step 1 and the last byte of step 3 has `begin != end`, whatever the
//! data or CRC bytes hold, so a cut anywhere in it reads as invalid, never as a mix that
//! happens to match its CRC. A cut while a single marker byte is programmed leaves it old,
//! new or garbage: old or garbage-equal-to-`end` at step 1 restores the copy as it was;
//! garbage-equal-to-`end` at the first of two step-3 bytes makes `begin == end` but meets a
//! CRC computed with `t`, not `end`, so the copy is invalid; any value at the commit byte is
//! either the complete new copy or invalid. So no cut makes a copy valid unless it is the
//! complete new copy or the copy as it was. The CRC is there to catch later corruption (bit
//! rot), not torn writes: CRC-16 detects every error burst of up to 16 bits, which covers any
//! single corrupted byte.

use coforge_link::crc::{CCITT, CrcParams};

/// Bytes of the record after each block's data.
pub const RECORD: usize = 4;

/// CRC-16/IBM-3740 (CCITT-FALSE). The non-zero start value means an all-zero block with an
/// all-zero record is not valid, so a bank stuck at zero is not mistaken for data.
pub const CRC_PARAMS: CrcParams = CrcParams { poly: 0x1021, init: 0xFFFF, reflect_in: false, reflect_out: false, xor_out: 0 };

/// The CRC of a block's data committed with sequence number `seq`: the shared CCITT table
/// (same polynomial, no reflection, no final XOR) started at [`CRC_PARAMS`]'s start value.
/// A block is an array: Kani (CBMC) unrolls the CRC loop exactly `BLOCK` times only when the
/// length is a constant it can see, which a slice cut at a symbolic place does not give it.
pub fn block_crc<const BLOCK: usize>(data: &[u8; BLOCK], seq: u8) -> u16 {
    CCITT.step(CCITT.update(CRC_PARAMS.init, data), seq)
}

/// A block's commit record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Record {
    pub begin: u8,
    pub crc: u16,
    pub end: u8,
}

impl Record {
    /// The record of a complete copy of `data` committed as `seq`.
    pub fn committed<const BLOCK: usize>(data: &[u8; BLOCK], seq: u8) -> Record {
        Record { begin: seq, crc: block_crc(data, seq), end: seq }
    }

    pub fn from_bytes(b: [u8; RECORD]) -> Record {
        let [begin, lo, hi, end] = b;
        Record { begin, crc: u16::from_le_bytes([lo, hi]), end }
    }

    pub fn to_bytes(self) -> [u8; RECORD] {
        let [lo, hi] = self.crc.to_le_bytes();
        [self.begin, lo, hi, self.end]
    }

    /// The sequence number of a valid copy.
    pub fn seq(self) -> u8 {
        self.end
    }

    /// Committed, and the CRC matches `data`.
    pub fn is_valid_for<const BLOCK: usize>(self, data: &[u8; BLOCK]) -> bool {
        self.begin == self.end && self.crc == block_crc(data, self.end)
    }

    /// The mark written first when committing `seq` over this record: different from the
    /// stored `end`, so the copy is invalid until the commit byte.
    pub fn invalidating_mark(self, seq: u8) -> u8 {
        if seq != self.end { seq } else { !seq }
    }
}

/// Offsets of the record bytes within a block slot of `block` data bytes.
pub mod offset {
    pub const fn begin(block: usize) -> usize {
        block
    }
    pub const fn crc(block: usize) -> usize {
        block + 1
    }
    pub const fn end(block: usize) -> usize {
        block + 3
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn committed_records_are_valid_and_torn_ones_are_not() {
        let data = [1_u8, 2, 3, 4];
        let r = Record::committed(&data, 7);
        assert!(r.is_valid_for(&data));
        assert!(!r.is_valid_for(&[1, 2, 3, 5]));
        assert!(!Record { begin: 8, ..r }.is_valid_for(&data));
        assert_eq!(Record::from_bytes(r.to_bytes()), r);
    }

    #[test]
    fn the_shared_table_gives_the_ibm_3740_crc() {
        // The CRC-16/IBM-3740 check value; `reference` is the bitwise definition.
        assert_eq!(CCITT.update(CRC_PARAMS.init, b"123456789"), 0x29B1);
        assert_eq!(block_crc(&[1, 2, 3], 4), coforge_link::crc::reference(CRC_PARAMS, &[1, 2, 3, 4]));
    }

    #[test]
    fn blank_and_zeroed_blocks_are_invalid() {
        assert!(!Record::from_bytes([0; 4]).is_valid_for(&[0; 128]));
        assert!(!Record::from_bytes([0xFF; 4]).is_valid_for(&[0xFF; 128]));
    }

    #[test]
    fn the_mark_always_differs_from_the_stored_end() {
        for end in 0..=255_u8 {
            for seq in 0..=255_u8 {
                let r = Record { begin: end, crc: 0, end };
                assert_ne!(r.invalidating_mark(seq), end);
            }
        }
    }
}
