//! Per-bank status bits (CO401Memory1 6000h.1/.2, serial Read Status MS1/MS2).

/// The status byte of one bank. Bits stay set until the host clears them (command 0x91).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BankStatus(pub u8);

impl BankStatus {
    /// The EEPROM did not answer (a read or write returned an error).
    pub const ACCESS_TIMEOUT: u8 = 0x01;
    /// A block's commit record did not match its data.
    pub const CHECKSUM_ERROR: u8 = 0x10;
    /// A block was rewritten from the other bank.
    pub const OVERWRITTEN: u8 = 0x20;
    /// The bank was formatted (blank, or both copies of a block were lost and rewritten).
    pub const CLEARED: u8 = 0x40;

    pub const fn bits(self) -> u8 {
        self.0
    }

    /// Any bit set: the bank's error output is active and its emergency is raised.
    pub const fn is_error(self) -> bool {
        self.0 != 0
    }

    pub(crate) fn set(&mut self, bits: u8) {
        self.0 |= bits;
    }
}
