//! One file's configuration (3x00h..3x1ch) and the rules its entries follow beyond what the
//! dictionary checks (types, `values`, limits): each rule refuses with one abort code.
//!
//! | rule | abort |
//! |---|---|
//! | a designation that is not a valid 8.3 FAT name (3x00h.1/.2) | 0609 0030h invalid value |
//! | interval 0 outside autoincrement writing, and cyclic writing with interval 0 (erratum CR-23) | 0609 0030h |
//! | 3x06h written with anything but 55h, which resets the count (erratum CR-24) | 0609 0030h |
//! | a record address at or past the file's last record (3x04h, 3x05h) | 0609 0031h value too high |

use crate::card::record::{COMPONENTS, ComponentType, RecordLayout};
use coforge_stack::od::SdoAbort;

/// 3x03h.1, the operating mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// 01h: direct writing at the record 3x04h addresses.
    DirectWriting,
    /// 02h: cyclic writing every interval.
    Cyclic,
    /// 03h: autoincrement writing, a window opened by the first write.
    Autoincrement,
    /// 10h: direct reading of the record at 3x04h.
    DirectReading,
}

impl Mode {
    pub const fn of_code(code: u8) -> Option<Mode> {
        Some(match code {
            0x01 => Mode::DirectWriting,
            0x02 => Mode::Cyclic,
            0x03 => Mode::Autoincrement,
            0x10 => Mode::DirectReading,
            _ => return None,
        })
    }

    pub const fn code(self) -> u8 {
        match self {
            Mode::DirectWriting => 0x01,
            Mode::Cyclic => 0x02,
            Mode::Autoincrement => 0x03,
            Mode::DirectReading => 0x10,
        }
    }
}

/// 3x03h.2 and 3x06h: the value that means "ring", and the only value 3x06h takes.
pub const RING: u8 = 0x55;
pub const RESET_COUNT: u32 = 0x55;

/// A short text of up to `N` bytes (a designation or a component name), without padding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Text<const N: usize> {
    bytes: [u8; N],
    /// Bytes in use (`N` is at most 11).
    len: u8,
}

impl<const N: usize> Default for Text<N> {
    fn default() -> Self {
        Text { bytes: [0; N], len: 0 }
    }
}

impl<const N: usize> Text<N> {
    /// `value` without trailing blanks and NULs; `None` if longer than `N`.
    pub fn new(value: &[u8]) -> Option<Self> {
        let end = value.iter().rposition(|&b| b != b' ' && b != 0).map_or(0, |i| i + 1);
        let value = value.get(..end)?;
        let mut bytes = [0; N];
        bytes.get_mut(..value.len())?.copy_from_slice(value);
        Some(Text { bytes, len: u8::try_from(value.len()).ok()? })
    }

    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.get(..usize::from(self.len)).unwrap_or(&[])
    }
}

/// Characters FAT allows in a short name besides letters and digits.
const FAT_SPECIAL: &[u8] = b"!#$%&'()-@^_`{}~";

fn fat_name_part(text: &[u8], max: usize) -> bool {
    !text.is_empty() && text.len() <= max && text.iter().all(|b| b.is_ascii_alphanumeric() || FAT_SPECIAL.contains(b))
}

/// A component: 3x1ch.1 and .2.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Component {
    pub name: Text<8>,
    pub ty: ComponentType,
}

/// One file's configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileConfig {
    name: Text<8>,
    extension: Text<3>,
    /// 3x01h: bit c, component c + 1 is in the records (bits 8..15 kept, not used: CR-22).
    pub relevant: u16,
    mode: Mode,
    /// 3x03h.2 = 55h.
    pub ring: bool,
    /// 3x03h.3, in 10 ms.
    interval: u32,
    /// 3x04h, 3x05h, 3x06h.
    current: u32,
    write_pointer: u32,
    count: u32,
    pub components: [Component; COMPONENTS],
}

impl FileConfig {
    /// File `n` (0-based) as the spec's defaults have it: "DateiN.dat", direct writing,
    /// linear, interval 1 (10 ms), components "KompC" of type WORD, none relevant.
    pub fn factory(n: usize) -> FileConfig {
        let digit = [b'1' + (n as u8 % 8)];
        let text = |prefix: &[u8], digit: &[u8]| {
            let mut b = [0_u8; 8];
            b.iter_mut().zip(prefix.iter().chain(digit)).for_each(|(d, s)| *d = *s);
            Text::new(&b).unwrap_or(Text { bytes: [0; 8], len: 0 })
        };
        let components = core::array::from_fn(|c| Component { name: text(b"Komp", &[b'1' + c as u8]), ty: ComponentType::Word });
        FileConfig {
            name: text(b"Datei", &digit),
            extension: Text::new(b"dat").unwrap_or(Text { bytes: [0; 3], len: 0 }),
            relevant: 0,
            mode: Mode::DirectWriting,
            ring: false,
            interval: 1,
            current: 0,
            write_pointer: 0,
            count: 0,
            components,
        }
    }

    pub fn name(&self) -> &[u8] {
        self.name.as_bytes()
    }

    pub fn extension(&self) -> &[u8] {
        self.extension.as_bytes()
    }

    /// 3x00h.1: a FAT short name of 1..8 characters.
    pub fn set_name(&mut self, value: &[u8]) -> Result<(), SdoAbort> {
        let text = Text::new(value).filter(|t| fat_name_part(t.as_bytes(), 8)).ok_or(SdoAbort::InvalidValue)?;
        self.name = text;
        Ok(())
    }

    /// 3x00h.2: a FAT extension of 1..3 characters.
    pub fn set_extension(&mut self, value: &[u8]) -> Result<(), SdoAbort> {
        let text = Text::new(value).filter(|t| fat_name_part(t.as_bytes(), 3)).ok_or(SdoAbort::InvalidValue)?;
        self.extension = text;
        Ok(())
    }

    /// The file's name on the card, "NAME.EXT", as `out`'s first bytes; their number.
    pub fn file_name(&self, out: &mut [u8; 12]) -> usize {
        let mut n = 0;
        for &b in self.name.as_bytes().iter().chain(b".").chain(self.extension.as_bytes()) {
            if let Some(slot) = out.get_mut(n) {
                *slot = b.to_ascii_uppercase();
                n += 1;
            }
        }
        n
    }

    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// 3x03h.1 (the dictionary allows 01h, 02h, 03h and 10h only).
    pub fn set_mode(&mut self, code: u8) -> Result<(), SdoAbort> {
        let mode = Mode::of_code(code).ok_or(SdoAbort::InvalidValue)?;
        if mode == Mode::Cyclic && self.interval == 0 {
            return Err(SdoAbort::InvalidValue);
        }
        self.mode = mode;
        Ok(())
    }

    pub fn interval(&self) -> u32 {
        self.interval
    }

    /// 3x03h.3: 0 only for autoincrement writing (a record per write).
    pub fn set_interval(&mut self, value: u32) -> Result<(), SdoAbort> {
        if value == 0 && self.mode != Mode::Autoincrement {
            return Err(SdoAbort::InvalidValue);
        }
        self.interval = value;
        Ok(())
    }

    /// The records' layout: the relevant components at their types.
    pub fn layout(&self) -> RecordLayout {
        RecordLayout { relevant: self.relevant as u8, types: self.components.map(|c| c.ty) }
    }

    /// Whole records in a file of `size` bytes.
    pub fn records(&self, size: u32) -> u32 {
        size / self.layout().len() as u32
    }

    pub fn current(&self) -> u32 {
        self.current
    }

    pub fn write_pointer(&self) -> u32 {
        self.write_pointer
    }

    pub fn count(&self) -> u32 {
        self.count
    }

    /// 3x04h for a file of `size` bytes: a record it holds.
    pub fn set_current(&mut self, record: u32, size: u32) -> Result<(), SdoAbort> {
        if record >= self.records(size) {
            return Err(SdoAbort::ValueTooHigh);
        }
        self.current = record;
        Ok(())
    }

    /// 3x05h for a file of `size` bytes: a record it holds.
    pub fn set_write_pointer(&mut self, record: u32, size: u32) -> Result<(), SdoAbort> {
        if record >= self.records(size) {
            return Err(SdoAbort::ValueTooHigh);
        }
        self.write_pointer = record;
        Ok(())
    }

    /// 3x06h: only 55h, which resets the file: the count of records written and the write
    /// pointer go back to 0 (erratum CR-24).
    pub fn reset_count(&mut self, value: u32) -> Result<(), SdoAbort> {
        if value != RESET_COUNT {
            return Err(SdoAbort::InvalidValue);
        }
        self.count = 0;
        self.write_pointer = 0;
        Ok(())
    }

    /// Every pointer at record 0 (a file laid out afresh).
    pub fn reset_pointers(&mut self) {
        (self.current, self.write_pointer, self.count) = (0, 0, 0);
    }

    /// Logging moved on: the next record goes to `write_pointer`, `count` have been written.
    pub fn set_progress(&mut self, write_pointer: u32, count: u32) {
        (self.write_pointer, self.count) = (write_pointer, count);
    }

    /// Autoincrement writing reached the end of a linear file: the file goes over to direct
    /// reading, showing its last record, `last`.
    pub fn switch_to_reading(&mut self, last: u32) {
        self.mode = Mode::DirectReading;
        self.current = last;
    }
}

/// Bytes of one file's configuration in the card's configuration file:
///
/// | bytes | content |
/// |---|---|
/// | 0..8, 8..11 | 3x00h.1 name, 3x00h.2 extension (NUL-padded) |
/// | 11..13 | 3x01h relevant components |
/// | 13, 14 | 3x03h.1 mode, 3x03h.2 ring (55h) or linear (00h) |
/// | 15..19 | 3x03h.3 interval |
/// | 19..23, 23..27, 27..31 | 3x04h, 3x05h, 3x06h |
/// | 31..111 | per component: 3x1ch.1 name (8, NUL-padded), 3x1ch.2 type (2) |
///
/// Numbers little-endian.
pub const ENCODED_LEN: usize = 31 + COMPONENTS * 10;

fn put<const N: usize>(out: &mut [u8], at: usize, bytes: [u8; N]) {
    if let Some(dst) = out.get_mut(at..at + N) {
        dst.copy_from_slice(&bytes);
    }
}

fn take<const N: usize>(bytes: &[u8], at: usize) -> [u8; N] {
    let mut b = [0; N];
    if let Some(src) = bytes.get(at..at + N) {
        b.copy_from_slice(src);
    }
    b
}

impl<const N: usize> Text<N> {
    fn padded(&self) -> [u8; N] {
        self.bytes
    }
}

impl FileConfig {
    /// The configuration as the card's configuration file holds it.
    pub fn encode(&self) -> [u8; ENCODED_LEN] {
        let mut out = [0; ENCODED_LEN];
        put(&mut out, 0, self.name.padded());
        put(&mut out, 8, self.extension.padded());
        put(&mut out, 11, self.relevant.to_le_bytes());
        put(&mut out, 13, [self.mode.code(), if self.ring { RING } else { 0 }]);
        put(&mut out, 15, self.interval.to_le_bytes());
        put(&mut out, 19, self.current.to_le_bytes());
        put(&mut out, 23, self.write_pointer.to_le_bytes());
        put(&mut out, 27, self.count.to_le_bytes());
        for (c, component) in self.components.iter().enumerate() {
            put(&mut out, 31 + c * 10, component.name.padded());
            put(&mut out, 39 + c * 10, component.ty.code().to_le_bytes());
        }
        out
    }

    /// A configuration from the card's configuration file; `None` if any field breaks a
    /// rule a write would have to keep.
    pub fn decode(bytes: &[u8; ENCODED_LEN]) -> Option<FileConfig> {
        let mut f = FileConfig::factory(0);
        f.set_name(&take::<8>(bytes, 0)).ok()?;
        f.set_extension(&take::<3>(bytes, 8)).ok()?;
        f.relevant = u16::from_le_bytes(take(bytes, 11));
        let [mode, ring] = take::<2>(bytes, 13);
        f.mode = Mode::of_code(mode)?;
        f.ring = match ring {
            RING => true,
            0 => false,
            _ => return None,
        };
        f.interval = u32::from_le_bytes(take(bytes, 15));
        if f.interval == 0 && f.mode != Mode::Autoincrement {
            return None;
        }
        f.current = u32::from_le_bytes(take(bytes, 19));
        f.write_pointer = u32::from_le_bytes(take(bytes, 23));
        f.count = u32::from_le_bytes(take(bytes, 27));
        for (c, component) in f.components.iter_mut().enumerate() {
            component.name = Text::new(&take::<8>(bytes, 31 + c * 10))?;
            component.ty = ComponentType::of_code(u16::from_le_bytes(take(bytes, 39 + c * 10)))?;
        }
        Some(f)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;

    fn name(f: &FileConfig) -> std::string::String {
        let mut b = [0; 12];
        let n = f.file_name(&mut b);
        std::string::String::from_utf8(b[..n].to_vec()).unwrap()
    }

    #[test]
    fn the_factory_files_are_datei_n_dat_with_word_components() {
        let f = FileConfig::factory(2);
        assert_eq!((name(&f), f.mode(), f.interval(), f.ring), ("DATEI3.DAT".into(), Mode::DirectWriting, 1, false));
        assert_eq!(f.components[7].name.as_bytes(), b"Komp8");
        assert_eq!(f.layout().len(), 9, "no component relevant: the time stamp and the status");
    }

    #[test]
    fn designations_must_be_fat_short_names() {
        let mut f = FileConfig::factory(0);
        f.set_name(b"oil_temp").unwrap();
        f.set_extension(b"log ").unwrap();
        assert_eq!(name(&f), "OIL_TEMP.LOG");
        assert_eq!(f.set_name(b"oil temp"), Err(SdoAbort::InvalidValue), "no blank inside");
        assert_eq!(f.set_name(b"a.b"), Err(SdoAbort::InvalidValue));
        assert_eq!(f.set_name(b"        "), Err(SdoAbort::InvalidValue), "not empty");
        assert_eq!(f.set_extension(b"toolong"), Err(SdoAbort::InvalidValue));
        assert_eq!(name(&f), "OIL_TEMP.LOG", "refused: unchanged");
    }

    #[test]
    fn interval_zero_only_for_autoincrement_and_the_count_resets_only_with_55h() {
        let mut f = FileConfig::factory(0);
        assert_eq!(f.set_interval(0), Err(SdoAbort::InvalidValue));
        f.set_mode(0x03).unwrap();
        f.set_interval(0).unwrap();
        assert_eq!(f.set_mode(0x02), Err(SdoAbort::InvalidValue), "cyclic writing every 0 ms");
        f.set_mode(0x10).unwrap();
        assert_eq!(f.set_mode(0x04), Err(SdoAbort::InvalidValue));
        assert_eq!(f.reset_count(0), Err(SdoAbort::InvalidValue));
        f.set_progress(7, 9);
        f.reset_count(0x55).unwrap();
        assert_eq!((f.count(), f.write_pointer()), (0, 0));
    }

    #[test]
    fn record_addresses_stay_inside_the_file() {
        let mut f = FileConfig::factory(0);
        f.relevant = 0b11;
        f.components[1].ty = ComponentType::Dword;
        assert_eq!(f.layout().len(), 9 + 2 + 4);
        assert_eq!(f.records(150), 10);
        f.set_current(9, 150).unwrap();
        assert_eq!(f.set_current(10, 150), Err(SdoAbort::ValueTooHigh));
        assert_eq!(f.set_write_pointer(10, 150), Err(SdoAbort::ValueTooHigh));
        assert_eq!((f.current(), f.write_pointer()), (9, 0));
    }

    #[test]
    fn a_configuration_round_trips_through_its_encoding_and_bad_fields_are_refused() {
        let mut f = FileConfig::factory(4);
        f.set_name(b"OIL_TEMP").unwrap();
        f.relevant = 0x00A5;
        f.set_mode(0x03).unwrap();
        f.set_interval(0).unwrap();
        f.ring = true;
        f.components[6] = Component { name: Text::new(b"Pressure").unwrap(), ty: ComponentType::Real };
        f.set_current(3, 1000).unwrap();
        let bytes = f.encode();
        assert_eq!(FileConfig::decode(&bytes), Some(f));
        let mut bad = bytes;
        bad[13] = 0x04;
        assert_eq!(FileConfig::decode(&bad), None, "no mode 04h");
        let mut bad = bytes;
        bad[39] = 9;
        assert_eq!(FileConfig::decode(&bad), None, "no type 0009h");
        let mut bad = bytes;
        bad[0] = b' ';
        bad[1] = b'.';
        assert_eq!(FileConfig::decode(&bad), None, "not an 8.3 name");
    }
}
