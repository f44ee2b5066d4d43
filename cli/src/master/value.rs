//! How `coforge master sdo` reads and writes values: a CiA 301 data type named on the command
//! line (`--type`) or found in an EDS file (`--eds`), each value little-endian on the bus.

use std::path::Path;

/// The data types a user can name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Type {
    Bool,
    I8,
    I16,
    I32,
    I64,
    U8,
    U16,
    U32,
    U64,
    F32,
    F64,
    /// VISIBLE_STRING.
    Str,
    /// OCTET_STRING and DOMAIN: bytes in hex.
    Bytes,
}

/// The names `--type` takes, with the type each means.
pub const NAMES: &[(&str, Type)] = &[
    ("bool", Type::Bool),
    ("i8", Type::I8),
    ("i16", Type::I16),
    ("i32", Type::I32),
    ("i64", Type::I64),
    ("u8", Type::U8),
    ("u16", Type::U16),
    ("u32", Type::U32),
    ("u64", Type::U64),
    ("f32", Type::F32),
    ("f64", Type::F64),
    ("str", Type::Str),
    ("bytes", Type::Bytes),
];

impl Type {
    pub fn named(name: &str) -> Result<Type, String> {
        NAMES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t).ok_or_else(|| {
            let names: Vec<&str> = NAMES.iter().map(|(n, _)| *n).collect();
            format!("unknown type `{name}`; types are: {}", names.join(", "))
        })
    }

    /// The type of a CiA 301 data type index (the `DataType=` of an EDS).
    fn of_cia(code: u16) -> Option<Type> {
        Some(match code {
            0x0001 => Type::Bool,
            0x0002 => Type::I8,
            0x0003 => Type::I16,
            0x0004 => Type::I32,
            0x0015 => Type::I64,
            0x0005 => Type::U8,
            0x0006 => Type::U16,
            0x0007 => Type::U32,
            0x001B => Type::U64,
            0x0008 => Type::F32,
            0x0011 => Type::F64,
            0x0009 => Type::Str,
            0x000A | 0x000F => Type::Bytes,
            _ => return None,
        })
    }

    /// The value's size for fixed-size types.
    fn size(self) -> Option<usize> {
        Some(match self {
            Type::Bool | Type::I8 | Type::U8 => 1,
            Type::I16 | Type::U16 => 2,
            Type::I32 | Type::U32 | Type::F32 => 4,
            Type::I64 | Type::U64 | Type::F64 => 8,
            Type::Str | Type::Bytes => return None,
        })
    }

    /// The bytes of `text` as a value of this type.
    pub fn encode(self, text: &str) -> Result<Vec<u8>, String> {
        let bad = |why: &str| format!("`{text}` is not a {self:?} value{why}");
        let int = |text: &str| -> Result<i128, String> {
            let (neg, digits) = text.strip_prefix('-').map_or((false, text), |d| (true, d));
            let v = match digits.strip_prefix("0x").or_else(|| digits.strip_prefix("0X")) {
                Some(hex) => i128::from_str_radix(hex, 16),
                None => digits.parse(),
            }
            .map_err(|_| bad(""))?;
            Ok(if neg { -v } else { v })
        };
        let fit = |v: i128, bytes: usize, signed: bool| -> Result<Vec<u8>, String> {
            let bits = 8 * bytes as u32;
            let (lo, hi) = if signed { (-(1_i128 << (bits - 1)), (1_i128 << (bits - 1)) - 1) } else { (0, (1_i128 << bits) - 1) };
            if v < lo || v > hi {
                return Err(bad(&format!(" (range {lo}..={hi})")));
            }
            Ok(v.to_le_bytes()[..bytes].to_vec())
        };
        match self {
            Type::Bool => match text {
                "0" | "false" => Ok(vec![0]),
                "1" | "true" => Ok(vec![1]),
                _ => Err(bad(" (0, 1, false or true)")),
            },
            Type::I8 | Type::I16 | Type::I32 | Type::I64 => fit(int(text)?, self.size().unwrap_or(8), true),
            Type::U8 | Type::U16 | Type::U32 | Type::U64 => fit(int(text)?, self.size().unwrap_or(8), false),
            Type::F32 => text.parse::<f32>().map(|v| v.to_le_bytes().to_vec()).map_err(|_| bad("")),
            Type::F64 => text.parse::<f64>().map(|v| v.to_le_bytes().to_vec()).map_err(|_| bad("")),
            Type::Str => Ok(text.as_bytes().to_vec()),
            Type::Bytes => {
                let digits: String = text.chars().filter(|c| !c.is_whitespace()).collect();
                if !digits.len().is_multiple_of(2) {
                    return Err(bad(" (hex bytes: an even number of digits)"));
                }
                (0..digits.len()).step_by(2).map(|i| u8::from_str_radix(&digits[i..i + 2], 16).map_err(|_| bad(" (hex bytes)"))).collect()
            }
        }
    }

    /// `bytes` read as this type; a length the type cannot have is shown as hex with a note.
    pub fn decode(self, bytes: &[u8]) -> String {
        let hex = |b: &[u8]| b.iter().map(|x| format!("{x:02X}")).collect::<Vec<_>>().join(" ");
        if self.size().is_some_and(|n| n != bytes.len()) {
            return format!("{} ({} bytes, not a {self:?})", hex(bytes), bytes.len());
        }
        let mut le = [0_u8; 8];
        le[..bytes.len().min(8)].copy_from_slice(&bytes[..bytes.len().min(8)]);
        let unsigned = u64::from_le_bytes(le);
        let signed = |bits: u32| (unsigned << (64 - bits)) as i64 >> (64 - bits);
        match self {
            Type::Bool => (unsigned != 0).to_string(),
            Type::U8 | Type::U16 | Type::U32 | Type::U64 => format!("{unsigned} (0x{unsigned:0width$X})", width = 2 * bytes.len()),
            Type::I8 | Type::I16 | Type::I32 | Type::I64 => signed(8 * bytes.len() as u32).to_string(),
            Type::F32 => f32::from_le_bytes([le[0], le[1], le[2], le[3]]).to_string(),
            Type::F64 => f64::from_le_bytes(le).to_string(),
            Type::Str => format!("{:?}", String::from_utf8_lossy(bytes)),
            Type::Bytes => hex(bytes),
        }
    }
}

/// The data type of `index`/`sub` in an EDS file (CiA 306): the `DataType` of section
/// `[IIII]` for sub-index 0 of a variable, else `[IIIIsubS]`.
pub fn from_eds(path: &Path, index: u16, sub: u8) -> Result<Type, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let wanted = [format!("{index:04X}sub{sub:X}"), format!("{index:04X}")];
    let mut section = String::new();
    let mut found: Option<(usize, u16)> = None;
    for line in text.lines().map(str::trim) {
        if let Some(name) = line.strip_prefix('[').and_then(|l| l.strip_suffix(']')) {
            section = name.to_ascii_uppercase();
            continue;
        }
        let Some(rank) = wanted.iter().position(|w| w.to_ascii_uppercase() == section) else { continue };
        // A record's own section has no DataType; sub-index 0 of a variable is the section.
        if rank == 1 && sub != 0 {
            continue;
        }
        if let Some(value) = line.split_once('=').filter(|(k, _)| k.trim().eq_ignore_ascii_case("DataType")).map(|(_, v)| v.trim()) {
            let code = match value.strip_prefix("0x").or_else(|| value.strip_prefix("0X")) {
                Some(hex) => u16::from_str_radix(hex, 16),
                None => value.parse(),
            }
            .map_err(|_| format!("{}: [{section}] DataType={value} is not a number", path.display()))?;
            if found.is_none_or(|(r, _)| rank < r) {
                found = Some((rank, code));
            }
        }
    }
    let (_, code) = found.ok_or_else(|| format!("{} has no entry {index:04X}h sub {sub}", path.display()))?;
    Type::of_cia(code)
        .ok_or_else(|| format!("{}: {index:04X}h sub {sub} has data type 0x{code:04X}, which `coforge master` does not format; use --type", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_encode_and_decode_by_type() {
        assert_eq!(Type::U16.encode("0x1234"), Ok(vec![0x34, 0x12]));
        assert_eq!(Type::U16.encode("100"), Ok(vec![100, 0]));
        assert!(Type::U16.encode("65536").is_err_and(|e| e.contains("0..=65535")));
        assert_eq!(Type::I8.encode("-128"), Ok(vec![0x80]));
        assert!(Type::I8.encode("128").is_err());
        assert_eq!(Type::Bytes.encode("01 ab FF"), Ok(vec![1, 0xAB, 0xFF]));
        assert!(Type::Bytes.encode("123").is_err());
        assert_eq!(Type::Str.encode("hi"), Ok(b"hi".to_vec()));
        assert_eq!(Type::U32.decode(&[0x58, 0, 0, 0]), "88 (0x00000058)");
        assert_eq!(Type::I16.decode(&[0xFE, 0xFF]), "-2");
        assert_eq!(Type::Str.decode(b"CO401"), "\"CO401\"");
        assert_eq!(Type::U8.decode(&[1, 2]), "01 02 (2 bytes, not a U8)");
        assert_eq!(Type::F32.decode(&1.5_f32.to_le_bytes()), "1.5");
        assert!(Type::named("u17").is_err_and(|e| e.contains("u16")));
    }

    #[test]
    fn eds_data_types() {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let path = dir.path().join("t.eds");
        std::fs::write(&path, "[1000]\nParameterName=Device type\nDataType=0x0007\n[1018]\nSubNumber=5\n[1018sub1]\nDataType=0x0007\n[1008]\nDataType=0x0009\n[2000sub3]\nDataType=0x0020\n").expect("a temporary EDS");
        assert_eq!(from_eds(&path, 0x1000, 0), Ok(Type::U32));
        assert_eq!(from_eds(&path, 0x1018, 1), Ok(Type::U32));
        assert_eq!(from_eds(&path, 0x1008, 0), Ok(Type::Str));
        assert!(from_eds(&path, 0x1018, 2).is_err_and(|e| e.contains("no entry 1018h sub 2")));
        assert!(from_eds(&path, 0x2000, 3).is_err_and(|e| e.contains("0x0020")));
    }
}
