//! One data record on the card, as a PC tool reads it (the README has the same table):
//!
//! | bytes | content |
//! |---|---|
//! | 0..2 | time stamp: milliseconds, u16 little-endian (0..999) |
//! | 2..8 | seconds, minutes, hours, day of the month, month, year (years since 2000), u8 each |
//! | 8 | modification status: bit c set when component c + 1 was written into this record |
//! | 9.. | the relevant components (3x01h bit c set), in component order, each at its type's size (3x1ch.2), little-endian |
//!
//! The time stamp has the fields of 2010h and 5x00h.1..7; records follow each other without
//! gaps, record n at n x the record length.

/// A component's data type, 3x1ch.2 (the index of its DEFTYPE object).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ComponentType {
    /// 0003h INTEGER16.
    Int,
    /// 0004h INTEGER32.
    Dint,
    /// 0005h UNSIGNED8.
    Byte,
    /// 0006h UNSIGNED16, the factory default.
    Word,
    /// 0007h UNSIGNED32.
    Dword,
    /// 0008h REAL32.
    Real,
}

impl ComponentType {
    /// The type of DEFTYPE index `code` (0003h..0008h).
    pub const fn of_code(code: u16) -> Option<ComponentType> {
        Some(match code {
            3 => ComponentType::Int,
            4 => ComponentType::Dint,
            5 => ComponentType::Byte,
            6 => ComponentType::Word,
            7 => ComponentType::Dword,
            8 => ComponentType::Real,
            _ => return None,
        })
    }

    /// The DEFTYPE index (3x1ch.2).
    pub const fn code(self) -> u16 {
        match self {
            ComponentType::Int => 3,
            ComponentType::Dint => 4,
            ComponentType::Byte => 5,
            ComponentType::Word => 6,
            ComponentType::Dword => 7,
            ComponentType::Real => 8,
        }
    }

    /// Bytes on the card, over SDO and in a PDO.
    pub const fn size(self) -> usize {
        match self {
            ComponentType::Byte => 1,
            ComponentType::Int | ComponentType::Word => 2,
            ComponentType::Dint | ComponentType::Dword | ComponentType::Real => 4,
        }
    }
}

/// Components in a record.
pub const COMPONENTS: usize = 8;
/// Bytes of the time stamp and of the modification status.
pub const TIME_STAMP: usize = 8;
const HEADER: usize = TIME_STAMP + 1;
/// The longest record: eight 4-byte components.
pub const MAX_RECORD: usize = HEADER + COMPONENTS * 4;

/// A point in time as the records and 2010h hold it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct TimeStamp {
    pub millisecond: u16,
    pub second: u8,
    pub minute: u8,
    pub hour: u8,
    pub day: u8,
    pub month: u8,
    /// Years since 2000.
    pub year: u8,
}

impl TimeStamp {
    /// Orders time stamps: later ones have greater keys.
    pub fn order_key(&self) -> u64 {
        let date = u64::from(self.year) << 16 | u64::from(self.month) << 8 | u64::from(self.day);
        let time = u64::from(self.hour) << 24 | u64::from(self.minute) << 16 | u64::from(self.second) << 10 | u64::from(self.millisecond);
        date << 32 | time
    }

    pub fn encode(&self) -> [u8; TIME_STAMP] {
        let [m0, m1] = self.millisecond.to_le_bytes();
        [m0, m1, self.second, self.minute, self.hour, self.day, self.month, self.year]
    }

    pub fn decode(b: &[u8; TIME_STAMP]) -> TimeStamp {
        let [m0, m1, second, minute, hour, day, month, year] = *b;
        TimeStamp { millisecond: u16::from_le_bytes([m0, m1]), second, minute, hour, day, month, year }
    }
}

/// Which components a file's records hold, and their types.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecordLayout {
    /// 3x01h: bit c, component c + 1 is relevant.
    pub relevant: u8,
    pub types: [ComponentType; COMPONENTS],
}

impl Default for RecordLayout {
    /// No relevant component, every type WORD (the factory settings).
    fn default() -> Self {
        RecordLayout { relevant: 0, types: [ComponentType::Word; COMPONENTS] }
    }
}

impl RecordLayout {
    fn is_relevant(&self, c: usize) -> bool {
        c < COMPONENTS && self.relevant & (1 << c) != 0
    }

    /// Bytes of one record.
    pub fn len(&self) -> usize {
        HEADER + (0..COMPONENTS).filter(|&c| self.is_relevant(c)).map(|c| self.size(c)).sum::<usize>()
    }

    /// Always false: a record has at least its time stamp.
    pub fn is_empty(&self) -> bool {
        false
    }

    fn size(&self, c: usize) -> usize {
        self.types.get(c).map_or(0, |t| t.size())
    }

    /// Where component `c` (0-based) lies in a record, if it is relevant.
    pub fn component(&self, c: usize) -> Option<core::ops::Range<usize>> {
        if !self.is_relevant(c) {
            return None;
        }
        let start = HEADER + (0..c).filter(|&k| self.is_relevant(k)).map(|k| self.size(k)).sum::<usize>();
        Some(start..start + self.size(c))
    }
}

/// A record being filled, or read back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Record {
    bytes: [u8; MAX_RECORD],
    len: usize,
}

impl Record {
    /// An empty record of `layout`: no component written, time stamp zero.
    pub fn new(layout: &RecordLayout) -> Record {
        Record { bytes: [0; MAX_RECORD], len: layout.len().min(MAX_RECORD) }
    }

    /// A record as stored (`bytes` as long as `layout` says).
    pub fn from_bytes(layout: &RecordLayout, bytes: &[u8]) -> Option<Record> {
        let mut r = Record::new(layout);
        r.bytes.get_mut(..r.len)?.copy_from_slice(bytes.get(..r.len)?);
        Some(r)
    }

    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.get(..self.len).unwrap_or(&[])
    }

    pub fn time_stamp(&self) -> TimeStamp {
        let mut t = [0; TIME_STAMP];
        t.iter_mut().zip(&self.bytes).for_each(|(d, s)| *d = *s);
        TimeStamp::decode(&t)
    }

    pub fn stamp(&mut self, time: &TimeStamp) {
        self.bytes.iter_mut().zip(time.encode()).for_each(|(d, s)| *d = s);
    }

    /// The modification status: bit c, component c + 1 was written.
    pub fn modified(&self) -> u8 {
        self.bytes.get(TIME_STAMP).copied().unwrap_or(0)
    }

    /// A new record's modification status: nothing written into it yet.
    pub fn clear_modified(&mut self) {
        if let Some(m) = self.bytes.get_mut(TIME_STAMP) {
            *m = 0;
        }
    }

    /// Writes component `c` (0-based; `value` at its type's size): `false` if it is not
    /// relevant or the value's length is not its type's.
    pub fn set(&mut self, layout: &RecordLayout, c: usize, value: &[u8]) -> bool {
        let Some(range) = layout.component(c) else { return false };
        let Some(dst) = self.bytes.get_mut(range).filter(|d| d.len() == value.len()) else { return false };
        dst.copy_from_slice(value);
        if let Some(m) = self.bytes.get_mut(TIME_STAMP) {
            *m |= 1 << c;
        }
        true
    }

    /// Component `c`'s bytes, if relevant.
    pub fn get(&self, layout: &RecordLayout, c: usize) -> Option<&[u8]> {
        self.bytes.get(layout.component(c)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn components_lie_in_order_at_their_sizes() {
        let mut layout = RecordLayout { relevant: 0b1010_0101, ..RecordLayout::default() };
        layout.types[0] = ComponentType::Byte;
        layout.types[2] = ComponentType::Dword;
        layout.types[5] = ComponentType::Int;
        layout.types[7] = ComponentType::Real;
        assert_eq!(layout.len(), 9 + 1 + 4 + 2 + 4);
        assert_eq!((layout.component(0), layout.component(1), layout.component(2)), (Some(9..10), None, Some(10..14)));
        assert_eq!((layout.component(5), layout.component(7)), (Some(14..16), Some(16..20)));
        let mut r = Record::new(&layout);
        assert!(r.set(&layout, 2, &0x1122_3344_u32.to_le_bytes()));
        assert!(!r.set(&layout, 2, &[1, 2]), "a DWORD takes 4 bytes");
        assert!(!r.set(&layout, 1, &[1, 2]), "component 2 is not relevant");
        let t = TimeStamp { millisecond: 999, second: 59, minute: 7, hour: 23, day: 31, month: 12, year: 26 };
        r.stamp(&t);
        let back = Record::from_bytes(&layout, r.as_bytes()).unwrap();
        assert_eq!((back.time_stamp(), back.modified()), (t, 0b100));
        assert_eq!(back.get(&layout, 2), Some(&[0x44, 0x33, 0x22, 0x11][..]));
        assert_eq!(r.as_bytes()[..9], [0xE7, 0x03, 59, 7, 23, 31, 12, 26, 0b100]);
    }

    #[test]
    fn every_deftype_code_has_its_size() {
        let sizes: [Option<usize>; 7] = core::array::from_fn(|i| ComponentType::of_code(i as u16 + 2).map(ComponentType::size));
        assert_eq!(sizes, [None, Some(2), Some(4), Some(1), Some(2), Some(4), Some(4)]);
        assert_eq!(ComponentType::of_code(9), None);
        (3..=8).for_each(|code| assert_eq!(ComponentType::of_code(code).map(ComponentType::code), Some(code)));
    }
}
