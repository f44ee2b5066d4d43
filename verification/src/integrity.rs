//! CRC-16 and the 32-bit additive checksum.

use coforge_link::checksum::{sum32, sum32_update};
use coforge_link::crc::{Crc16, CrcParams, bitwise_step, reference};

/// The table step equals the bitwise definition for this `(crc, byte)`.
pub fn prop_crc_table_step(crc16: &Crc16, crc: u16, byte: u8) {
    let p = crc16.params();
    let input = if p.reflect_in { byte.reverse_bits() } else { byte };
    assert_eq!(crc16.step(crc, byte), bitwise_step(p.poly, crc, input));
}

/// The table-driven CRC of a message equals the bitwise reference.
pub fn prop_crc_matches_reference(crc16: &Crc16, data: &[u8]) {
    assert_eq!(crc16.checksum(data), reference(crc16.params(), data));
}

/// Flipping bits `burst` (a pattern of at most 16 bits) at bit offset `at` of `data` changes
/// the CRC: every single-bit error and every burst of 16 bits or less is detected.
pub fn prop_crc_detects_burst(crc16: &Crc16, data: &mut [u8], at: usize, burst: u16) {
    let bits = data.len() * 8;
    if burst == 0 || bits == 0 {
        return;
    }
    let at = at % bits;
    let before = crc16.checksum(data);
    let flipped = flip(data, at, burst);
    let after = crc16.checksum(data);
    flip(data, at, burst);
    // Bits past the end are dropped; if none was left, no error was introduced.
    if flipped {
        assert_ne!(before, after, "burst {burst:#06X} at bit {at} went undetected");
    }
}

/// XORs `pattern` into `data` starting at bit `at` (MSB-first within bytes); bits that would
/// fall past the end are dropped, which only shortens the burst. True if any bit flipped.
fn flip(data: &mut [u8], at: usize, pattern: u16) -> bool {
    let mut any = false;
    for i in 0..16 {
        if pattern >> (15 - i) & 1 == 1 {
            let bit = at + i;
            if let Some(b) = data.get_mut(bit / 8) {
                *b ^= 0x80 >> (bit % 8);
                any = true;
            }
        }
    }
    any
}

/// Updating the checksum for one changed byte equals recomputing it.
pub fn prop_sum32_update(data: &mut [u8], index: usize, new: u8) {
    let Some(slot) = data.get_mut(index) else { return };
    let old = *slot;
    let before = sum32(data);
    if let Some(slot) = data.get_mut(index) {
        *slot = new;
    }
    assert_eq!(sum32_update(before, old, new), sum32(data));
}

/// The update step alone, for every `(sum, old, new)`.
pub fn prop_sum32_step(sum: u32, old: u8, new: u8) {
    let recomputed = sum.wrapping_sub(u32::from(old)).wrapping_add(u32::from(new));
    assert_eq!(sum32_update(sum, old, new), recomputed);
    assert_eq!(sum32_update(sum32_update(sum, old, new), new, old), sum, "an update is undone by the reverse update");
}

/// The CRC parameter sets the devices use or that test the reflected paths.
pub const PARAMS: [CrcParams; 3] = [
    coforge_link::crc::XMODEM,
    CrcParams { poly: 0x8005, init: 0, reflect_in: true, reflect_out: true, xor_out: 0 },
    CrcParams { poly: 0x1021, init: 0xFFFF, reflect_in: true, reflect_out: true, xor_out: 0xFFFF },
];
