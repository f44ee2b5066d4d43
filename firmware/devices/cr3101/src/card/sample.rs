//! The sample records the card tests write: the simulator's (`firmware/sim/tests/
//! cr3101_card.rs`) and QEMU's `cr3101-card` fixture image, whose card
//! `tests/python/test_cr3101_card.py` checks against the same formula. Only with the feature
//! `card-sample`.

use super::record::{ComponentType, Record, RecordLayout, TimeStamp};

/// Component 1 WORD, component 2 DINT, component 4 BYTE: 16-byte records.
pub fn layout() -> RecordLayout {
    let mut l = RecordLayout { relevant: 0b0000_1011, ..RecordLayout::default() };
    l.types[1] = ComponentType::Dint;
    l.types[3] = ComponentType::Byte;
    l
}

/// Record `n`: component 1 = n, component 2 = -1000 n, component 4 = n mod 251, stamped
/// 2026-12-03 06:30 with n's seconds and milliseconds.
pub fn record(n: u32) -> Record {
    let l = layout();
    let mut r = Record::new(&l);
    r.set(&l, 0, &(n as u16).to_le_bytes());
    r.set(&l, 1, &(n as i32).wrapping_mul(-1000).to_le_bytes());
    r.set(&l, 3, &[(n % 251) as u8]);
    r.stamp(&TimeStamp { millisecond: (n % 1000) as u16, second: (n % 60) as u8, minute: 30, hour: 6, day: 3, month: 12, year: 26 });
    r
}
