//! The small dictionary the SDO server tests run against (shared by `sdo_transfers.rs` and
//! `sdo_malformed.rs`).
#![allow(dead_code)]

use coforge_stack::od::{ReadLen, SdoAbort};
use coforge_stack::sdo::SdoTarget;

pub const U32: u16 = 0x2000;
pub const U8_RO: u16 = 0x2001;
pub const STRING: u16 = 0x2002;
pub const DOMAIN: u16 = 0x2003;

/// One object at sub-index 0: up to 200 bytes.
#[derive(Debug, Clone, PartialEq)]
pub struct Entry {
    pub index: u16,
    pub writable: bool,
    /// The value must have exactly `max` bytes (an integer), else up to `max` (string, domain).
    pub fixed: bool,
    pub max: usize,
    pub len: usize,
    pub data: [u8; 200],
}

impl Entry {
    fn new(index: u16, writable: bool, fixed: bool, max: usize, value: &[u8]) -> Entry {
        let mut data = [0; 200];
        data[..value.len()].copy_from_slice(value);
        Entry { index, writable, fixed, max, len: value.len(), data }
    }
}

/// A u32 rw, a u8 ro, a 40-byte rw string and a 200-byte rw domain; counts writes.
#[derive(Debug, Clone, PartialEq)]
pub struct Dict {
    pub entries: [Entry; 4],
    /// Successful writes so far.
    pub writes: usize,
}

impl Dict {
    pub fn new() -> Dict {
        let domain: Vec<u8> = (0..100).map(|i| (i * 7 + 3) as u8).collect();
        Dict {
            entries: [
                Entry::new(U32, true, true, 4, &0x1234_5678_u32.to_le_bytes()),
                Entry::new(U8_RO, false, true, 1, &[0x5A]),
                Entry::new(STRING, true, false, 40, b"coforge sdo string!"),
                Entry::new(DOMAIN, true, false, 200, &domain),
            ],
            writes: 0,
        }
    }

    pub fn entry(&mut self, index: u16, sub: u8) -> Result<&mut Entry, SdoAbort> {
        let entry = self.entries.iter_mut().find(|e| e.index == index).ok_or(SdoAbort::NoObject)?;
        if sub == 0 { Ok(entry) } else { Err(SdoAbort::NoSubIndex) }
    }

    pub fn value(&self, index: u16) -> &[u8] {
        let e = self.entries.iter().find(|e| e.index == index).expect("a test object");
        &e.data[..e.len]
    }

    pub fn set(&mut self, index: u16, value: &[u8]) {
        let e = self.entry(index, 0).expect("a test object");
        e.data[..value.len()].copy_from_slice(value);
        e.len = value.len();
    }
}

impl SdoTarget for Dict {
    fn read(&mut self, index: u16, sub: u8, offset: usize, buf: &mut [u8]) -> Result<ReadLen, SdoAbort> {
        let e = self.entry(index, sub)?;
        let rest = e.data[..e.len].get(offset..).ok_or(SdoAbort::LengthTooHigh)?;
        let copied = rest.len().min(buf.len());
        buf[..copied].copy_from_slice(&rest[..copied]);
        Ok(ReadLen { copied, total: e.len })
    }

    fn check_download(&mut self, index: u16, sub: u8, size: Option<usize>) -> Result<(), SdoAbort> {
        let e = self.entry(index, sub)?;
        match size {
            _ if !e.writable => Err(SdoAbort::ReadOnly),
            Some(size) if size > e.max => Err(SdoAbort::LengthTooHigh),
            Some(size) if e.fixed && size < e.max => Err(SdoAbort::LengthTooLow),
            _ => Ok(()),
        }
    }

    fn write(&mut self, index: u16, sub: u8, data: &[u8]) -> Result<(), SdoAbort> {
        self.check_download(index, sub, Some(data.len()))?;
        self.set(index, data);
        self.writes += 1;
        Ok(())
    }
}
