//! Reading the little-endian ELF32 files the Cortex-M builds leave: the header fields, the
//! section table (names resolved) and symbol values. One reader for the size report, the
//! memory-map check, the raw binary and the bench markers; a few lines instead of a
//! dependency.

/// One section header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Section {
    pub name: String,
    pub kind: u32,
    pub flags: u32,
    pub addr: u32,
    /// Where its bytes are in the file.
    pub offset: usize,
    pub size: u32,
    pub link: u32,
    pub entsize: u32,
}

impl Section {
    /// SHF_ALLOC: the section occupies memory on the target.
    pub fn allocated(&self) -> bool {
        self.flags & 0x2 != 0
    }
}

pub fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}

pub fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

/// A field of the file at `at`, or an error naming what is cut short.
pub fn field(elf: &[u8], at: usize) -> Result<u32, String> {
    u32_at(elf, at).ok_or_else(|| "truncated ELF file".to_string())
}

/// Fails unless `elf` starts as a little-endian ELF32 file.
pub fn check_header(elf: &[u8]) -> Result<(), String> {
    if elf.get(..6) == Some(&[0x7F, b'E', b'L', b'F', 1, 1][..]) { Ok(()) } else { Err("not a little-endian ELF32 file".into()) }
}

/// The NUL-terminated string at `at`.
fn string_at(elf: &[u8], at: usize) -> String {
    let bytes = elf.get(at..).unwrap_or_default();
    String::from_utf8_lossy(bytes.get(..bytes.iter().position(|&b| b == 0).unwrap_or(0)).unwrap_or_default()).into_owned()
}

/// Every section header, with its name from the section-name string table.
pub fn sections(elf: &[u8]) -> Result<Vec<Section>, String> {
    check_header(elf)?;
    let bad = || "truncated ELF header".to_string();
    let (shoff, shentsize) = (field(elf, 32)? as usize, usize::from(u16_at(elf, 46).ok_or_else(bad)?));
    let (shnum, shstrndx) = (usize::from(u16_at(elf, 48).ok_or_else(bad)?), usize::from(u16_at(elf, 50).ok_or_else(bad)?));
    let raw = |i: usize| -> Result<[u32; 10], String> {
        let at = shoff + i * shentsize;
        let mut h = [0; 10];
        for (n, word) in h.iter_mut().enumerate() {
            *word = u32_at(elf, at + 4 * n).ok_or_else(|| format!("truncated section header {i}"))?;
        }
        Ok(h)
    };
    let names = raw(shstrndx)?[4] as usize;
    (0..shnum)
        .map(|i| {
            let h = raw(i)?;
            Ok(Section {
                name: string_at(elf, names + h[0] as usize),
                kind: h[1],
                flags: h[2],
                addr: h[3],
                offset: h[4] as usize,
                size: h[5],
                link: h[6],
                entsize: h[9],
            })
        })
        .collect()
}

/// The value of symbol `name` in the symbol table (`.symtab`, its names in the string table
/// its `sh_link` names).
pub fn symbol(elf: &[u8], name: &str) -> Result<u32, String> {
    const SHT_SYMTAB: u32 = 2;
    let sections = sections(elf)?;
    for table in sections.iter().filter(|s| s.kind == SHT_SYMTAB && s.entsize >= 16) {
        let strings = sections.get(table.link as usize).ok_or("symbol table without string table")?.offset;
        for sym in (table.offset..table.offset + table.size as usize).step_by(table.entsize as usize) {
            if string_at(elf, strings + field(elf, sym)? as usize) == name {
                return field(elf, sym + 4);
            }
        }
    }
    Err(format!("no symbol `{name}` in the symbol table"))
}

/// One entry of the symbol table that occupies memory: a function or an object.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Symbol {
    pub name: String,
    pub addr: u32,
    pub size: u32,
    /// The section it lives in (`.text`, `.rodata`, `.bss`...).
    pub section: String,
}

/// Every function and object symbol with a size, from `.symtab`.
pub fn symbols(elf: &[u8]) -> Result<Vec<Symbol>, String> {
    const SHT_SYMTAB: u32 = 2;
    const STT_OBJECT: u8 = 1;
    const STT_FUNC: u8 = 2;
    let sections = sections(elf)?;
    let mut out = Vec::new();
    for table in sections.iter().filter(|s| s.kind == SHT_SYMTAB && s.entsize >= 16) {
        let strings = sections.get(table.link as usize).ok_or("symbol table without string table")?.offset;
        for sym in (table.offset..table.offset + table.size as usize).step_by(table.entsize as usize) {
            let info = elf.get(sym + 12).copied().ok_or("truncated symbol table")?;
            let shndx = usize::from(u16_at(elf, sym + 14).ok_or("truncated symbol table")?);
            let size = field(elf, sym + 8)?;
            if size == 0 || !matches!(info & 0xF, STT_OBJECT | STT_FUNC) {
                continue;
            }
            let Some(section) = sections.get(shndx) else { continue };
            out.push(Symbol { name: string_at(elf, strings + field(elf, sym)? as usize), addr: field(elf, sym + 4)?, size, section: section.name.clone() });
        }
    }
    Ok(out)
}
