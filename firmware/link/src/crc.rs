//! CRC-16 in the Rocksoft model, driven by a 16-entry nibble table, with its parameters taken
//! from the spec.

/// CRC-16 parameters (width 16).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CrcParams {
    pub poly: u16,
    pub init: u16,
    pub reflect_in: bool,
    pub reflect_out: bool,
    pub xor_out: u16,
}

/// CRC-16/XMODEM: what CANopenIA's host reference code uses (check value 0x31C3).
pub const XMODEM: CrcParams = CrcParams { poly: 0x1021, init: 0, reflect_in: false, reflect_out: false, xor_out: 0 };

/// The table of polynomial 0x1021 (CRC-16-CCITT), shared by every user of it: the SDO block
/// transfer (XMODEM, start 0) and the EEPROM bank records (start 0xFFFF, see
/// [`Crc16::update`]) use one table, not one each.
pub static CCITT: Crc16 = Crc16::new(XMODEM);

/// One CRC step over a byte, bit by bit: the reference the table is checked against.
pub const fn bitwise_step(poly: u16, crc: u16, byte: u8) -> u16 {
    let mut crc = crc ^ ((byte as u16) << 8);
    let mut i = 0;
    while i < 8 {
        crc = if crc & 0x8000 != 0 { (crc << 1) ^ poly } else { crc << 1 };
        i += 1;
    }
    crc
}

/// A CRC-16 with its table, built at compile time when used in a `const`. The table holds
/// one entry per nibble (32 bytes, two lookups per byte) rather than per byte (512 bytes):
/// on the 32 KiB STM32F042K6 the flash matters more than the few cycles.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Crc16 {
    params: CrcParams,
    table: [u16; 16],
}

impl Crc16 {
    // Indexing in a const loop bounded by the table length; `get_mut` is not const-usable here.
    #[allow(clippy::indexing_slicing)]
    pub const fn new(params: CrcParams) -> Self {
        let mut table = [0_u16; 16];
        let mut i = 0;
        while i < 16 {
            // Four bit steps of the nibble `i` at the top of the register.
            let mut crc = (i as u16) << 12;
            let mut bit = 0;
            while bit < 4 {
                crc = if crc & 0x8000 != 0 { (crc << 1) ^ params.poly } else { crc << 1 };
                bit += 1;
            }
            table[i] = crc;
            i += 1;
        }
        Crc16 { params, table }
    }

    pub const fn params(&self) -> CrcParams {
        self.params
    }

    /// One table step; equal to [`bitwise_step`] for every `(crc, byte)`.
    #[inline]
    pub fn step(&self, crc: u16, byte: u8) -> u16 {
        let byte = if self.params.reflect_in { byte.reverse_bits() } else { byte };
        // The byte enters at the top; each half shifts out one nibble, whose effect the table
        // holds. `crc >> 12` is below 16, so the lookups never miss.
        let nibble = |crc: u16| (crc << 4) ^ self.table.get(usize::from(crc >> 12)).copied().unwrap_or(0);
        nibble(nibble(crc ^ (u16::from(byte) << 8)))
    }

    pub fn start(&self) -> u16 {
        self.params.init
    }

    #[inline]
    pub fn update(&self, crc: u16, data: &[u8]) -> u16 {
        // Indexed, not `fold` or `for &b in data`: Kani (CBMC 6.6) never reduces a `fold`
        // over known bytes to a constant, and cannot bound a slice iterator's loop when the
        // slice may point into more than one array (it unrolls it to the harness's bound).
        let mut crc = crc;
        let mut i = 0;
        while let Some(&b) = data.get(i) {
            crc = self.step(crc, b);
            i += 1;
        }
        crc
    }

    pub fn finish(&self, crc: u16) -> u16 {
        let crc = if self.params.reflect_out { crc.reverse_bits() } else { crc };
        crc ^ self.params.xor_out
    }

    /// The CRC of `data` in one call.
    pub fn checksum(&self, data: &[u8]) -> u16 {
        self.finish(self.update(self.start(), data))
    }
}

/// The CRC computed bit by bit, with no table: the reference implementation.
pub fn reference(params: CrcParams, data: &[u8]) -> u16 {
    let mut crc = params.init;
    for &b in data {
        let b = if params.reflect_in { b.reverse_bits() } else { b };
        crc = bitwise_step(params.poly, crc, b);
    }
    let crc = if params.reflect_out { crc.reverse_bits() } else { crc };
    crc ^ params.xor_out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_values_of_catalogued_crcs() {
        // Check values over "123456789" from the CRC catalogue.
        assert_eq!(Crc16::new(XMODEM).checksum(b"123456789"), 0x31C3);
        let arc = CrcParams { poly: 0x8005, init: 0, reflect_in: true, reflect_out: true, xor_out: 0 };
        assert_eq!(Crc16::new(arc).checksum(b"123456789"), 0xBB3D);
        let ibm_3740 = CrcParams { poly: 0x1021, init: 0xFFFF, reflect_in: false, reflect_out: false, xor_out: 0 };
        assert_eq!(Crc16::new(ibm_3740).checksum(b"123456789"), 0x29B1);
        let x25 = CrcParams { poly: 0x1021, init: 0xFFFF, reflect_in: true, reflect_out: true, xor_out: 0xFFFF };
        assert_eq!(Crc16::new(x25).checksum(b"123456789"), 0x906E);
        assert_eq!(reference(x25, b"123456789"), 0x906E);
    }
}
