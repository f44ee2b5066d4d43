//! The card's own configuration, `CANMEM.CFG` in the root directory (erratum CR-48): the card
//! name (2000h), the allocation in effect (2002h/2003h) and every file's configuration and
//! pointers (3x00h..3x1ch). It travels with the card, as the manual has it, and a PC tool
//! reads it with the record files.
//!
//! | bytes | content |
//! |---|---|
//! | 0..4 | `CMEM` |
//! | 4 | format version, 1 |
//! | 5..16 | 2000h card name (NUL-padded) |
//! | 16..48 | 2002h.1..8 file sizes, u32 little-endian |
//! | 48..936 | files 1..8, 111 bytes each ([`FileConfig::encode`]) |
//! | 936..944 | when it was saved: a time stamp as the records have it |
//! | 944..946 | CRC-16/XMODEM of bytes 0..944, little-endian |
//!
//! The file is pre-allocated at 1024 bytes and rewritten in place, like the record files.

use super::files::FILES;
use super::record::{TIME_STAMP, TimeStamp};
use crate::logger::file_config::{ENCODED_LEN, FileConfig, Text};
use coforge_link::crc::CCITT;

/// The file's name on the card.
pub const FILE_NAME: &str = "CANMEM.CFG";
/// Its size on the card.
pub const LEN: usize = 1024;
const MAGIC: [u8; 4] = *b"CMEM";
const VERSION: u8 = 1;
const FILES_AT: usize = 48;
const SAVED_AT: usize = FILES_AT + FILES * ENCODED_LEN;
const CRC_AT: usize = SAVED_AT + TIME_STAMP;
const _: () = assert!(CRC_AT + 2 <= LEN, "the configuration fits its file");

/// What the configuration file holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Settings {
    /// 2000h.
    pub name: Text<11>,
    /// The file sizes in effect (2002h/2003h when they agree).
    pub allocation: [u32; FILES],
    pub files: [FileConfig; FILES],
    /// When the file was written: records on the card older than this were logged before
    /// it, and its pointers count them.
    pub saved_at: TimeStamp,
}

impl Settings {
    /// A card the device has not configured: 2000h "00000000000", no file allocated, the
    /// files' factory configurations.
    pub fn factory() -> Settings {
        Settings {
            name: Text::new(b"00000000000").unwrap_or_default(),
            allocation: [0; FILES],
            files: core::array::from_fn(FileConfig::factory),
            saved_at: TimeStamp::default(),
        }
    }

    pub fn encode(&self) -> [u8; LEN] {
        fn put(out: &mut [u8; LEN], at: usize, bytes: &[u8]) {
            if let Some(dst) = out.get_mut(at..at + bytes.len()) {
                dst.copy_from_slice(bytes);
            }
        }
        let mut out = [0; LEN];
        put(&mut out, 0, &MAGIC);
        put(&mut out, 4, &[VERSION]);
        put(&mut out, 5, self.name.as_bytes());
        for (n, size) in self.allocation.iter().enumerate() {
            put(&mut out, 16 + 4 * n, &size.to_le_bytes());
        }
        for (n, file) in self.files.iter().enumerate() {
            put(&mut out, FILES_AT + n * ENCODED_LEN, &file.encode());
        }
        put(&mut out, SAVED_AT, &self.saved_at.encode());
        let crc = CCITT.checksum(out.get(..CRC_AT).unwrap_or_default());
        put(&mut out, CRC_AT, &crc.to_le_bytes());
        out
    }

    /// The settings of a configuration file; `None` for a file this format cannot take (another
    /// version, a bad CRC, a field no write could have stored).
    pub fn decode(bytes: &[u8; LEN]) -> Option<Settings> {
        let body = bytes.get(..CRC_AT)?;
        let crc = u16::from_le_bytes([*bytes.get(CRC_AT)?, *bytes.get(CRC_AT + 1)?]);
        if bytes.get(..4)? != MAGIC || *bytes.get(4)? != VERSION || CCITT.checksum(body) != crc {
            return None;
        }
        let mut settings = Settings::factory();
        settings.name = Text::new(bytes.get(5..16)?)?;
        for (n, size) in settings.allocation.iter_mut().enumerate() {
            *size = u32::from_le_bytes(bytes.get(16 + 4 * n..20 + 4 * n)?.try_into().ok()?);
        }
        for (n, file) in settings.files.iter_mut().enumerate() {
            let at = FILES_AT + n * ENCODED_LEN;
            *file = FileConfig::decode(bytes.get(at..at + ENCODED_LEN)?.try_into().ok()?)?;
        }
        settings.saved_at = TimeStamp::decode(bytes.get(SAVED_AT..CRC_AT)?.try_into().ok()?);
        Some(settings)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_round_trip_and_any_corruption_is_refused() {
        let mut s = Settings::factory();
        s.name = Text::new(b"TRUCK 17").unwrap();
        s.allocation = [4096, 0, 1 << 20, 0, 0, 0, 0, 512];
        s.files[2].set_name(b"OIL_TEMP").unwrap();
        s.saved_at = TimeStamp { millisecond: 1, second: 2, minute: 3, hour: 4, day: 5, month: 6, year: 26 };
        let bytes = s.encode();
        assert_eq!(Settings::decode(&bytes), Some(s));
        assert_eq!(&bytes[..5], b"CMEM\x01");
        for at in [0, 4, 5, 20, FILES_AT + 3, SAVED_AT, CRC_AT, CRC_AT + 1] {
            let mut bad = bytes;
            bad[at] ^= 0x10;
            assert_eq!(Settings::decode(&bad), None, "byte {at} flipped");
        }
        assert_eq!(Settings::decode(&[0; LEN]), None, "an empty file");
    }
}
