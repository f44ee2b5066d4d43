//! `cargo xtask size`: flash and RAM of each device's generated code on a Cortex-M0
//! (thumbv6m-none-eabi, opt-level "z", LTO), measured against an image without it.

use crate::{Result, root, run};
use std::process::Command;

/// Sizes of the allocated sections of an ELF32 little-endian image.
#[derive(Debug, Default, Clone, Copy)]
pub struct Sections {
    pub text: u64,
    pub rodata: u64,
    pub data: u64,
    pub bss: u64,
}

impl Sections {
    /// What the image takes in flash: code, constants and the initial values of variables.
    pub fn flash(self) -> u64 {
        self.text + self.rodata + self.data
    }

    /// Static RAM: variables with and without initial values.
    pub fn ram(self) -> u64 {
        self.data + self.bss
    }
}

fn u16_at(b: &[u8], at: usize) -> u64 {
    b.get(at..at + 2).map_or(0, |s| u64::from(u16::from_le_bytes([s[0], s[1]])))
}

fn u32_at(b: &[u8], at: usize) -> u64 {
    b.get(at..at + 4).map_or(0, |s| u64::from(u32::from_le_bytes([s[0], s[1], s[2], s[3]])))
}

/// Reads the section table; names come from the section-name string table.
pub fn sections(elf: &[u8]) -> std::result::Result<Sections, String> {
    if elf.get(..4) != Some(b"\x7fELF") || elf.get(4) != Some(&1) || elf.get(5) != Some(&1) {
        return Err("not a 32-bit little-endian ELF file".into());
    }
    let (shoff, shentsize, shnum, shstrndx) = (u32_at(elf, 0x20) as usize, u16_at(elf, 0x2E) as usize, u16_at(elf, 0x30) as usize, u16_at(elf, 0x32) as usize);
    let header = |i: usize| shoff + i * shentsize;
    let strtab = u32_at(elf, header(shstrndx) + 16) as usize;
    let mut s = Sections::default();
    for i in 0..shnum {
        let h = header(i);
        let name_at = strtab + u32_at(elf, h) as usize;
        let name: String = elf.get(name_at..).unwrap_or(&[]).iter().take_while(|&&c| c != 0).map(|&c| char::from(c)).collect();
        let size = u32_at(elf, h + 20);
        match name.as_str() {
            ".vector_table" | ".text" => s.text += size,
            ".rodata" => s.rodata += size,
            ".data" => s.data += size,
            ".bss" | ".uninit" => s.bss += size,
            _ => {}
        }
    }
    Ok(s)
}

pub fn report() -> Result {
    let dir = root().join("firmware/boards/size-probe");
    run(Command::new("cargo").args(["build", "--quiet", "--release", "--target", "thumbv6m-none-eabi"]).current_dir(&dir))?;
    let bin = |name: &str| dir.join("target/thumbv6m-none-eabi/release").join(name);
    let read = |name: &str| -> Result<Sections> {
        let bytes = std::fs::read(bin(name)).map_err(|e| format!("cannot read {}: {e}", bin(name).display()))?;
        sections(&bytes).map_err(|e| format!("{name}: {e}"))
    };
    let base = read("baseline")?;
    println!("xtask: generated code on thumbv6m-none-eabi (opt-level z, LTO), above a {}-byte baseline image:", base.flash());
    println!("xtask: {:<14} {:>8} {:>8} {:>10} {:>10}", "device", ".text", ".rodata", "flash", "static RAM");
    for device in ["co401memory1", "co401gw1", "cr3101", "canopenia"] {
        let s = read(device)?;
        let text = s.text.saturating_sub(base.text);
        let rodata = s.rodata.saturating_sub(base.rodata);
        let flash = s.flash().saturating_sub(base.flash());
        let ram = (s.data + s.bss).saturating_sub(base.data + base.bss);
        println!("xtask: {device:<14} {text:>8} {rodata:>8} {flash:>10} {ram:>10}");
    }
    Ok(())
}
