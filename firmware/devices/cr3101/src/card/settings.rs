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

    /// The file's bytes as pieces in order, `(offset, bytes)`, the CRC last: a writer copies
    /// them into whatever buffer it has (a block at a time on a card), so the whole file is
    /// never on the stack.
    pub fn pieces(&self, mut piece: impl FnMut(usize, &[u8])) {
        let mut crc = CCITT.start();
        let mut put = |at: usize, bytes: &[u8]| {
            crc = CCITT.update(crc, bytes);
            piece(at, bytes);
        };
        let mut header = [0; FILES_AT];
        header.iter_mut().zip(MAGIC.iter().chain(&[VERSION])).for_each(|(d, s)| *d = *s);
        header.iter_mut().skip(5).zip(self.name.as_bytes()).for_each(|(d, s)| *d = *s);
        for (n, size) in self.allocation.iter().enumerate() {
            header.iter_mut().skip(16 + 4 * n).zip(size.to_le_bytes()).for_each(|(d, s)| *d = s);
        }
        put(0, &header);
        for (n, file) in self.files.iter().enumerate() {
            put(FILES_AT + n * ENCODED_LEN, &file.encode());
        }
        put(SAVED_AT, &self.saved_at.encode());
        let crc = CCITT.finish(crc);
        piece(CRC_AT, &crc.to_le_bytes());
    }

    /// Back to [`Settings::factory`], in place (the settings are a kilobyte: a device resets
    /// them without a copy on its stack).
    pub fn reset(&mut self) {
        self.name = Text::new(b"00000000000").unwrap_or_default();
        self.allocation = [0; FILES];
        for (n, file) in self.files.iter_mut().enumerate() {
            *file = FileConfig::factory(n);
        }
        self.saved_at = TimeStamp::default();
    }

    /// The whole file (tests, tools).
    pub fn encode(&self) -> [u8; LEN] {
        let mut out = [0; LEN];
        self.pieces(|at, bytes| {
            if let Some(dst) = out.get_mut(at..at + bytes.len()) {
                dst.copy_from_slice(bytes);
            }
        });
        out
    }

    /// Reads a configuration file into `self` through `read(offset, buf)` (a piece at a time);
    /// `false` for a file this format cannot take (another version, a bad CRC, a field no
    /// write could have stored, a read that failed), and then `self` holds the factory
    /// settings.
    pub fn read_from(&mut self, mut read: impl FnMut(usize, &mut [u8]) -> bool) -> bool {
        let ok = self.try_read(&mut read);
        if !ok {
            self.reset();
        }
        ok
    }

    fn try_read(&mut self, read: &mut impl FnMut(usize, &mut [u8]) -> bool) -> bool {
        let mut crc = CCITT.start();
        let mut take = |at: usize, buf: &mut [u8]| {
            let ok = read(at, buf);
            crc = CCITT.update(crc, buf);
            ok
        };
        let mut header = [0; FILES_AT];
        if !take(0, &mut header) || header.get(..4) != Some(&MAGIC[..]) || header.get(4) != Some(&VERSION) {
            return false;
        }
        let Some(name) = header.get(5..16).and_then(Text::new) else { return false };
        self.name = name;
        for (n, size) in self.allocation.iter_mut().enumerate() {
            let mut b = [0; 4];
            b.iter_mut().zip(header.iter().skip(16 + 4 * n)).for_each(|(d, s)| *d = *s);
            *size = u32::from_le_bytes(b);
        }
        for (n, file) in self.files.iter_mut().enumerate() {
            let mut bytes = [0; ENCODED_LEN];
            if !take(FILES_AT + n * ENCODED_LEN, &mut bytes) {
                return false;
            }
            let Some(decoded) = FileConfig::decode(&bytes) else { return false };
            *file = decoded;
        }
        let mut saved_at = [0; TIME_STAMP];
        if !take(SAVED_AT, &mut saved_at) {
            return false;
        }
        self.saved_at = TimeStamp::decode(&saved_at);
        let computed = CCITT.finish(crc);
        let mut stored = [0; 2];
        read(CRC_AT, &mut stored) && u16::from_le_bytes(stored) == computed
    }

    /// The settings of a whole configuration file (tests, tools); `None` for a file this
    /// format cannot take.
    pub fn decode(bytes: &[u8; LEN]) -> Option<Settings> {
        let mut settings = Settings::factory();
        let read = |at: usize, buf: &mut [u8]| match bytes.get(at..at + buf.len()) {
            Some(src) => {
                buf.copy_from_slice(src);
                true
            }
            None => false,
        };
        settings.read_from(read).then_some(settings)
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
        let mut reset = s;
        reset.reset();
        assert_eq!(reset, Settings::factory());
    }
}
