//! Field access for generated codecs: fixed-offset integers in either byte order. Lengths are
//! checked before these run; out-of-range reads give 0 and writes are dropped, never a panic.

/// An unsigned integer of `n` (1..=8) bytes at `at`.
pub fn read_uint(data: &[u8], at: usize, n: usize, big_endian: bool) -> u64 {
    let bytes = data.get(at..at.saturating_add(n)).unwrap_or(&[]);
    if big_endian { bytes.iter().fold(0, |acc, &b| acc << 8 | u64::from(b)) } else { bytes.iter().rev().fold(0, |acc, &b| acc << 8 | u64::from(b)) }
}

/// A signed integer of `n` (1..=8) bytes at `at`, sign-extended.
pub fn read_int(data: &[u8], at: usize, n: usize, big_endian: bool) -> i64 {
    let raw = read_uint(data, at, n, big_endian);
    let shift = 64 - 8 * n.clamp(1, 8) as u32;
    ((raw << shift) as i64) >> shift
}

/// Writes the low `n` bytes of `value` at `at`.
pub fn write_uint(out: &mut [u8], at: usize, n: usize, big_endian: bool, value: u64) {
    for i in 0..n {
        let shift = if big_endian { 8 * (n - 1 - i) } else { 8 * i };
        if let Some(b) = out.get_mut(at + i) {
            *b = (value >> shift) as u8;
        }
    }
}

/// `N` bytes at `at`.
pub fn read_bytes<const N: usize>(data: &[u8], at: usize) -> [u8; N] {
    let mut out = [0; N];
    if let Some(src) = data.get(at..at.saturating_add(N)) {
        out.copy_from_slice(src);
    }
    out
}

/// Copies `bytes` to `out` at `at` (dropped if it does not fit).
pub fn write_bytes(out: &mut [u8], at: usize, bytes: &[u8]) {
    if let Some(dst) = out.get_mut(at..at.saturating_add(bytes.len())) {
        dst.copy_from_slice(bytes);
    }
}

/// Why a frame is not a command of the protocol.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DecodeError {
    /// No command of this direction uses the code (and length code).
    UnknownCommand { code: u8 },
    /// The command exists but its data length is wrong.
    Length { min: usize, max: usize, got: usize },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integers_in_both_byte_orders() {
        let d = [0x12, 0x50, 0x04, 0xFF, 0xFE];
        assert_eq!(read_uint(&d, 0, 2, false), 0x5012);
        assert_eq!(read_uint(&d, 0, 2, true), 0x1250);
        assert_eq!(read_int(&d, 3, 2, false), -257);
        assert_eq!(read_int(&d, 3, 1, false), -1);
        assert_eq!(read_uint(&d, 4, 4, false), 0, "a field past the end reads as 0");
        let mut out = [0; 4];
        write_uint(&mut out, 1, 2, true, 0xABCD);
        assert_eq!(out, [0, 0xAB, 0xCD, 0]);
        write_uint(&mut out, 3, 2, false, 0xFFFF);
        assert_eq!(out, [0, 0xAB, 0xCD, 0xFF], "the byte past the end is dropped");
        assert_eq!(read_bytes::<2>(&d, 1), [0x50, 0x04]);
        assert_eq!(read_bytes::<2>(&d, 4), [0, 0]);
    }
}
