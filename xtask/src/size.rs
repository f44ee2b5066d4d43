//! `cargo xtask size`: flash and RAM of each device's generated code on a Cortex-M0
//! (thumbv6m-none-eabi, opt-level "z", LTO), measured against an image without it.

use crate::{Result, root, run};
use std::path::PathBuf;
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

/// Sums the allocated sections of an image by kind.
pub fn sections(elf: &[u8]) -> std::result::Result<Sections, String> {
    let mut s = Sections::default();
    for section in crate::elf::sections(elf)? {
        let size = u64::from(section.size);
        match section.name.as_str() {
            ".vector_table" | ".text" => s.text += size,
            ".rodata" => s.rodata += size,
            ".data" => s.data += size,
            ".bss" | ".uninit" => s.bss += size,
            _ => {}
        }
    }
    Ok(s)
}

/// The devices with a size-probe image.
pub const DEVICES: [&str; 4] = ["co401memory1", "co401gw1", "cr3101", "canopenia"];

/// Builds the size-probe images (`firmware/boards/size-probe`).
pub fn build_probes() -> Result {
    run(Command::new("cargo").args(["build", "--quiet", "--release", "--target", "thumbv6m-none-eabi"]).current_dir(root().join("firmware/boards/size-probe")))
}

/// The size-probe image of `device` (or `baseline`).
pub fn probe_elf(device: &str) -> PathBuf {
    root().join("firmware/boards/size-probe/target/thumbv6m-none-eabi/release").join(device)
}

/// Prints [`table`].
pub fn report() -> Result {
    for line in table()?.lines() {
        println!("xtask: {line}");
    }
    Ok(())
}

/// The size of each device's code above the baseline image, as text lines.
pub fn table() -> Result<String> {
    build_probes()?;
    let bin = probe_elf;
    let read = |name: &str| -> Result<Sections> {
        let bytes = std::fs::read(bin(name)).map_err(|e| format!("cannot read {}: {e}", bin(name).display()))?;
        sections(&bytes).map_err(|e| format!("{name}: {e}"))
    };
    let base = read("baseline")?;
    let mut out = format!("generated code on thumbv6m-none-eabi (opt-level z, LTO), above a {}-byte baseline image:\n", base.flash());
    out.push_str(&format!("{:<14} {:>8} {:>8} {:>10} {:>10}\n", "device", ".text", ".rodata", "flash", "static RAM"));
    for device in DEVICES {
        let s = read(device)?;
        let text = s.text.saturating_sub(base.text);
        let rodata = s.rodata.saturating_sub(base.rodata);
        let flash = s.flash().saturating_sub(base.flash());
        let ram = (s.data + s.bss).saturating_sub(base.data + base.bss);
        out.push_str(&format!("{device:<14} {text:>8} {rodata:>8} {flash:>10} {ram:>10}\n"));
    }
    Ok(out)
}
