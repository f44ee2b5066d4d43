//! Firmware images: each board crate's binaries, built for the board's target and copied to
//! `target/dist/images/<device>-<board>.elf` with a raw `.bin` for flashing.

use crate::elf::{self, Section};
use crate::{Result, cargo, root, run};
use std::path::PathBuf;

/// A board crate and the devices it has images for.
pub struct Board {
    pub name: &'static str,
    pub target: &'static str,
    pub devices: &'static [&'static str],
    /// Cargo features the images need (a pending image whose `[[bin]]` requires a feature,
    /// so that the crate's plain build stays green until it fits).
    pub features: &'static [&'static str],
    /// The chip's flash and RAM as `(origin, length)`, what every image is checked against.
    pub flash: (u32, u32),
    pub ram: (u32, u32),
}

pub const BOARDS: &[Board] = &[QEMU, STM32F0, STM32F091, STM32F072];

/// QEMU's lm3s6965evb (`firmware/boards/qemu`): 256 KiB of flash, 64 KiB of RAM.
/// `co401memory1-files` is the same module with its banks in host files (semihosting);
/// `co401gw1` keeps its parameters in a host file too, and has a pin console on UART2;
/// `canopenia` keeps its parameters in a host file; `cr3101` too, its card QEMU's SD card.
const QEMU: Board = Board {
    name: "qemu",
    target: "thumbv7m-none-eabi",
    devices: &["co401memory1", "co401memory1-files", "co401gw1", "canopenia", "cr3101"],
    features: &[],
    flash: (0, 256 * 1024),
    ram: (0x2000_0000, 64 * 1024),
};

/// Boards whose images do not fit their chip yet: `dist` tries to build them and reports by
/// how much they are over, without failing. A board moves to [`BOARDS`] once it fits (the
/// STM32F042K6 did, and the CO401GW1 image of the STM32F042C6).
pub const PENDING: &[Board] = &[STM32F0_CANOPENIA];

/// The STM32F042 boards (`firmware/boards/stm32f0`): 32 KiB of flash, 6 KiB of RAM.
/// CO401Memory1 on the K6 (LQFP32), CO401GW1 on the C6 (LQFP48): the same die.
const STM32F0: Board = Board {
    name: "stm32f0",
    target: "thumbv6m-none-eabi",
    devices: &["co401memory1", "co401gw1"],
    features: &[],
    flash: (0x0800_0000, 32 * 1024),
    ram: (0x2000_0000, 6 * 1024),
};

/// CANopenIA on the same crate's STM32F042K6, which the manual lists beside the coprocessor's
/// own F091: its `[[bin]]` requires the feature `canopenia-image` until it fits.
const STM32F0_CANOPENIA: Board = Board { devices: &["canopenia"], features: &["canopenia-image"], ..STM32F0 };

/// The STM32F091RC board (`firmware/boards/stm32f091`, the board code of `stm32f0` built for
/// this chip, the same Cortex-M0 target): 256 KiB of flash, of which the image has the first
/// 240 KiB (the last 16 KiB are CANopenIA's configuration files), and 32 KiB of RAM.
const STM32F091: Board = Board { name: "stm32f091", devices: &["canopenia"], flash: (0x0800_0000, 240 * 1024), ram: (0x2000_0000, 32 * 1024), ..STM32F0 };

/// The STM32F072CB board (`firmware/boards/stm32f072`, the board code of `stm32f0` built for
/// this chip): 128 KiB of flash, 16 KiB of RAM. The CR3101 with its SD card on SPI1 and the
/// RTC, and the CO401GW1 on the gateway's STM32F042C6 board, with which the F072CB in LQFP48
/// is pin-compatible (the bigger chip for a gateway that needs more room).
const STM32F072: Board =
    Board { name: "stm32f072", devices: &["cr3101", "co401gw1"], flash: (0x0800_0000, 128 * 1024), ram: (0x2000_0000, 16 * 1024), ..STM32F0 };

/// The ELF an image build leaves in the board crate's target directory.
pub(crate) fn built_elf(board: &Board, device: &str) -> PathBuf {
    root().join("firmware/boards").join(board.name).join("target").join(board.target).join("release").join(device)
}

/// One row of the size table.
struct Row {
    device: &'static str,
    image: String,
    flash: u64,
    flash_budget: u32,
    ram: u64,
    ram_budget: u32,
}

/// Builds every image, copies it, as ELF and raw binary, to `target/dist/images`, and prints
/// the size table: flash and static RAM per image, with the stack peak measured in QEMU.
/// Fails if an image is over its chip's flash, or its static RAM plus that stack peak is over
/// its RAM.
pub fn build() -> Result<Vec<PathBuf>> {
    let out = root().join("target/dist/images");
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let mut images = Vec::new();
    let mut rows = Vec::new();
    for board in BOARDS {
        let dir = root().join("firmware/boards").join(board.name);
        run(cargo().args(["build", "--quiet", "--release", "--target", board.target]).current_dir(&dir))?;
        for device in board.devices {
            let elf = built_elf(board, device);
            let bytes = std::fs::read(&elf).map_err(|e| format!("cannot read {}: {e}", elf.display()))?;
            let bin = raw_binary(&bytes).map_err(|e| format!("{}: {e}", elf.display()))?;
            check_memory_map(&bytes, board.flash, board.ram).map_err(|e| format!("{}: {e}", elf.display()))?;
            let stem = out.join(format!("{device}-{}", board.name));
            std::fs::write(stem.with_extension("elf"), &bytes).map_err(|e| format!("cannot write image: {e}"))?;
            std::fs::write(stem.with_extension("bin"), &bin).map_err(|e| format!("cannot write image: {e}"))?;
            println!("xtask: image {device} for {} ({}): {} bytes to flash", board.name, board.target, bin.len());
            let s = crate::size::sections(&bytes).map_err(|e| format!("{}: {e}", elf.display()))?;
            rows.push(Row {
                device,
                image: format!("{device}-{}", board.name),
                flash: s.flash(),
                flash_budget: board.flash.1,
                ram: s.ram(),
                ram_budget: board.ram.1,
            });
            images.push(stem.with_extension("elf"));
        }
    }
    // The stack is not static: each device's bench image runs it through every kind of input
    // in QEMU and measures its deepest use (painted stack).
    let stacks = crate::bench::selftest()?;
    size_table(&rows, &stacks)?;
    pending_boards(&stacks);
    Ok(images)
}

/// Prints the size table; fails if an image is over its chip's flash or RAM. `stacks` holds
/// each measured device's stack peak; an image of a device without one fails.
fn size_table(rows: &[Row], stacks: &[(&str, u64)]) -> Result {
    println!(
        "xtask: image sizes (flash = .text + .rodata + .data, static RAM = .data + .bss; stack peak measured in QEMU, Cortex-M3 build of the same device):"
    );
    println!("xtask: {:<22} {:>20} {:>11} {:>11} {:>22}", "image", "flash / budget", "static RAM", "stack peak", "RAM total / budget");
    let mut over = Vec::new();
    for r in rows {
        // Every bench of the device counts (CANopenIA's with and without a loaded file): the
        // deepest is the image's.
        let measured = |bench: &&(&str, u64)| r.device.starts_with(bench.0) || bench.0.starts_with(r.device);
        let Some(stack) = stacks.iter().filter(measured).map(|&(_, stack)| stack).max() else {
            return Err(format!("{}: no bench image measures the stack of {}", r.image, r.device));
        };
        let ram = r.ram + stack;
        println!("xtask: {:<22} {:>9} / {:>8} {:>11} {:>11} {:>10} / {:>9}", r.image, r.flash, r.flash_budget, r.ram, stack, ram, r.ram_budget);
        if r.flash > u64::from(r.flash_budget) {
            over.push(format!("{}: {} bytes of flash, the chip has {}", r.image, r.flash, r.flash_budget));
        }
        if ram > u64::from(r.ram_budget) {
            over.push(format!("{}: {} bytes of static RAM + {stack} of stack, the chip has {}", r.image, r.ram, r.ram_budget));
        }
    }
    if over.is_empty() { Ok(()) } else { Err(format!("over budget:\n  {}", over.join("\n  "))) }
}

/// Tries to link each pending board's images against its real memory map and says by how
/// much each is over. The linker's RAM figure is static RAM only; `stacks` (as for
/// [`size_table`]) adds the device's stack peak to it.
fn pending_boards(stacks: &[(&str, u64)]) {
    for board in PENDING {
        let dir = root().join("firmware/boards").join(board.name);
        let mut build = cargo();
        build.args(["build", "--quiet", "--release", "--target", board.target]).current_dir(&dir);
        if !board.features.is_empty() {
            build.args(["--features", &board.features.join(",")]);
        }
        let output = build.output();
        let verdict = match output {
            Ok(o) if o.status.success() => "links: it fits; move it from PENDING to BOARDS".to_string(),
            Ok(o) => {
                let err = String::from_utf8_lossy(&o.stderr);
                let regions = overflow(&err);
                if regions.is_empty() {
                    format!("does not build:\n{err}")
                } else {
                    let stack = stacks.iter().find(|(d, _)| board.devices.iter().all(|device| device.starts_with(d))).map(|&(_, s)| s);
                    let over: Vec<String> = regions
                        .iter()
                        .map(|(region, n)| match stack {
                            Some(stack) if region == "RAM" => format!("RAM overflowed by {n} bytes of static RAM, {} with the stack peak ({stack})", n + stack),
                            _ => format!("{region} overflowed by {n} bytes"),
                        })
                        .collect();
                    format!("does not link: {}", over.join(", "))
                }
            }
            Err(e) => format!("cannot run cargo: {e}"),
        };
        println!(
            "xtask: pending board {} ({} KiB flash, {} KiB RAM), not in dist: {}: {verdict}",
            board.name,
            board.flash.1 / 1024,
            board.ram.1 / 1024,
            board.devices.join(", ")
        );
    }
}

/// Each region's largest "region 'X' overflowed by N bytes" in a linker's output, in the
/// order the regions first appear (FLASH, then RAM).
fn overflow(linker: &str) -> Vec<(String, u64)> {
    let mut regions: Vec<(String, u64)> = Vec::new();
    for line in linker.lines() {
        let parsed = || -> Option<(String, u64)> {
            let region = line.split("in region '").nth(1)?.split('\'').next()?.to_string();
            let n = line.split("overflowed by ").nth(1)?.split(' ').next()?.parse().ok()?;
            Some((region, n))
        };
        let Some((region, n)) = parsed() else { continue };
        match regions.iter_mut().find(|(r, _)| *r == region) {
            Some((_, most)) => *most = (*most).max(n),
            None => regions.push((region, n)),
        }
    }
    regions
}

/// Checks an image against its chip's memory map: the vector table at the start of flash, its
/// initial stack pointer inside RAM, its reset vector the ELF entry point (a Thumb address),
/// code and constants in flash, variables in RAM.
pub fn check_memory_map(elf: &[u8], flash: (u32, u32), ram: (u32, u32)) -> std::result::Result<(), String> {
    let inside = |(origin, len): (u32, u32), addr: u32, size: u32| addr >= origin && u64::from(addr) + u64::from(size) <= u64::from(origin) + u64::from(len);
    let entry = elf::field(elf, 24)?;
    let mut vectors = None;
    for section in elf::sections(elf)? {
        let Section { name, addr, offset, size, .. } = &section;
        let (addr, offset, size) = (*addr, *offset, *size);
        if !section.allocated() || size == 0 {
            continue;
        }
        let (region, what) = match name.as_str() {
            ".vector_table" | ".text" | ".rodata" => (flash, "flash"),
            ".data" | ".bss" | ".uninit" => (ram, "RAM"),
            _ if name.starts_with(".ARM") => (flash, "flash"),
            _ => continue,
        };
        if !inside(region, addr, size) {
            return Err(format!("section {name} at {addr:#010x}..{:#010x} is outside {what}", u64::from(addr) + u64::from(size)));
        }
        if name == ".vector_table" {
            vectors = Some((addr, offset));
        }
    }
    let (addr, offset) = vectors.ok_or("no .vector_table section")?;
    if addr != flash.0 {
        return Err(format!("the vector table is at {addr:#010x}, not at the start of flash {:#010x}", flash.0));
    }
    let (sp, reset) = (elf::field(elf, offset)?, elf::field(elf, offset + 4)?);
    if !(sp > ram.0 && u64::from(sp) <= u64::from(ram.0) + u64::from(ram.1)) {
        return Err(format!("initial stack pointer {sp:#010x} is outside RAM"));
    }
    if reset & 1 != 1 || reset & !1 != entry & !1 || !inside(flash, entry & !1, 2) {
        return Err(format!("reset vector {reset:#010x} is not the Thumb entry point {entry:#010x} in flash"));
    }
    Ok(())
}

/// What a flash programmer writes: the loadable segments (PT_LOAD with file data) of a
/// little-endian ELF32, placed at their physical (load) addresses from the lowest one, gaps
/// filled with 0xFF (erased flash).
pub fn raw_binary(elf: &[u8]) -> std::result::Result<Vec<u8>, String> {
    elf::check_header(elf)?;
    let bad = || "truncated ELF header".to_string();
    let (phoff, phentsize, phnum) = (elf::field(elf, 28)? as usize, usize::from(elf::u16_at(elf, 42).ok_or_else(bad)?), elf::u16_at(elf, 44).ok_or_else(bad)?);
    let mut segments = Vec::new();
    for i in 0..usize::from(phnum) {
        let ph = phoff + i * phentsize;
        let field = |n: usize| elf::u32_at(elf, ph + 4 * n).ok_or_else(|| format!("truncated program header {i}"));
        let (kind, offset, paddr, filesz) = (field(0)?, field(1)? as usize, field(3)?, field(4)? as usize);
        if kind == 1 && filesz > 0 {
            let data = elf.get(offset..offset + filesz).ok_or_else(|| format!("segment {i} outside the file"))?;
            segments.push((paddr, data));
        }
    }
    let start = segments.iter().map(|s| s.0).min().ok_or("no loadable segment")?;
    let end = segments.iter().map(|(a, d)| *a as usize + d.len()).max().unwrap_or(start as usize);
    let mut bin = vec![0xFF; end - start as usize];
    for (addr, data) in segments {
        let at = (addr - start) as usize;
        bin[at..at + data.len()].copy_from_slice(data);
    }
    Ok(bin)
}

#[cfg(test)]
mod tests {

    #![allow(clippy::unwrap_used)]
    use super::raw_binary;

    #[test]
    fn linker_overflow_is_read_from_lld_output() {
        let err = "  = note: rust-lld: error: section '.rodata' will not fit in region 'FLASH': overflowed by 572 bytes\n          rust-lld: error: section '.gnu.sgstubs' will not fit in region 'FLASH': overflowed by 576 bytes\n          rust-lld: error: section '.bss' will not fit in region 'RAM': overflowed by 1124 bytes\n          rust-lld: error: section '.uninit' will not fit in region 'RAM': overflowed by 1124 bytes\n";
        assert_eq!(super::overflow(err), [("FLASH".to_string(), 576), ("RAM".to_string(), 1124)]);
        assert_eq!(super::overflow(&err[..err.find(".bss").unwrap()]), [("FLASH".to_string(), 576)]);
        assert!(super::overflow("error[E0308]: mismatched types").is_empty());
    }

    /// An ELF32 header and `segments` as PT_LOAD program headers, data after them.
    fn elf(segments: &[(u32, &[u8])]) -> Vec<u8> {
        let mut f = vec![0x7F, b'E', b'L', b'F', 1, 1, 1];
        f.resize(52, 0);
        f[28..32].copy_from_slice(&52u32.to_le_bytes());
        f[42..44].copy_from_slice(&32u16.to_le_bytes());
        f[44..46].copy_from_slice(&(segments.len() as u16).to_le_bytes());
        let mut data_at = 52 + 32 * segments.len();
        let mut data = Vec::new();
        for (paddr, bytes) in segments {
            for v in [1, data_at as u32, *paddr, *paddr, bytes.len() as u32, bytes.len() as u32, 5, 4] {
                f.extend_from_slice(&v.to_le_bytes());
            }
            data.extend_from_slice(bytes);
            data_at += bytes.len();
        }
        f.extend_from_slice(&data);
        f
    }

    /// Every image `cargo xtask dist` built (the suite builds them before), on every board:
    /// the QEMU lm3s6965, the STM32F042K6, the STM32F091RC and the STM32F072CB.
    #[test]
    fn every_built_image_fits_its_chips_memory_map() {
        for board in super::BOARDS {
            for device in board.devices {
                let elf = super::built_elf(board, device);
                let Ok(bytes) = std::fs::read(&elf) else {
                    panic!("{} is missing: run `cargo xtask dist` first", elf.display());
                };
                super::check_memory_map(&bytes, board.flash, board.ram).unwrap();
                // The same image against a chip whose flash is elsewhere, or whose RAM is smaller.
                let elsewhere = (board.flash.0 ^ 0x0800_0000, board.flash.1);
                assert!(super::check_memory_map(&bytes, elsewhere, board.ram).is_err(), "{device} on {}", board.name);
                assert!(super::check_memory_map(&bytes, board.flash, (0x2000_0000, 1024)).is_err(), "{device} on {}", board.name);
            }
        }
    }

    #[test]
    fn flash_arguments_and_boards() {
        let args = |s: &str| s.split_whitespace().map(String::from).collect::<Vec<_>>();
        let parsed = super::flash_args(&args("--device co401memory1 --board stm32f0 --chip STM32F042K6Tx")).unwrap();
        assert_eq!((parsed.device.as_str(), parsed.board.as_str(), parsed.chip.as_deref()), ("co401memory1", "stm32f0", Some("STM32F042K6Tx")));
        assert!(super::flash_args(&args("--device co401memory1")).unwrap_err().contains("--board"));
        assert!(super::flash_args(&args("--device")).unwrap_err().contains("needs a value"));
        assert!(super::chip_of("qemu", "co401memory1").unwrap_err().contains("QEMU"));
        assert_eq!(super::chip_of("stm32f0", "co401memory1"), Ok("STM32F042K6Tx"));
        assert_eq!(super::chip_of("stm32f0", "co401gw1"), Ok("STM32F042C6Tx"));
        assert_eq!(super::chip_of("stm32f091", "canopenia"), Ok("STM32F091RCTx"));
        assert_eq!(super::chip_of("stm32f072", "co401gw1"), Ok("STM32F072CBTx"));
        let nope = super::chip_of("nope", "co401gw1").unwrap_err();
        assert!(nope.contains("stm32f0, stm32f091"), "{nope}");
        assert!(super::chip_of("nope", "co401gw1").unwrap_err().contains("--chip"));
    }

    #[test]
    fn segments_land_at_their_load_addresses_with_erased_gaps() {
        let bin = raw_binary(&elf(&[(0x0800_0004, &[3, 4]), (0x0800_0000, &[1, 2])])).unwrap();
        assert_eq!(bin, [1, 2, 0xFF, 0xFF, 3, 4]);
        assert!(raw_binary(b"not an elf").is_err());
    }
}

/// What `cargo xtask flash` was asked.
#[derive(Debug, PartialEq, Eq)]
pub struct FlashArgs {
    pub device: String,
    pub board: String,
    pub chip: Option<String>,
}

/// Parses `--device D --board B [--chip C]`.
pub fn flash_args(args: &[String]) -> std::result::Result<FlashArgs, String> {
    let mut it = args.iter();
    let (mut device, mut board, mut chip) = (None, None, None);
    while let Some(flag) = it.next() {
        let slot = match flag.as_str() {
            "--device" => &mut device,
            "--board" => &mut board,
            "--chip" => &mut chip,
            other => return Err(format!("unknown argument `{other}`; usage: cargo xtask flash --device <d> --board <b> [--chip <c>]")),
        };
        *slot = Some(it.next().ok_or_else(|| format!("{flag} needs a value"))?.clone());
    }
    let device = device.ok_or("--device is required (e.g. --device co401memory1)")?;
    let board = board.ok_or("--board is required (e.g. --board stm32f0)")?;
    Ok(FlashArgs { device, board, chip })
}

/// The probe-rs chip name of a board (and device: the stm32f0 crate has two packages of the
/// STM32F042) that is flashed, or why it is not.
pub fn chip_of(board: &str, device: &str) -> std::result::Result<&'static str, String> {
    match board {
        "qemu" => Err("the qemu board's images run in QEMU, not on a probe: see \"Running an image in QEMU\" in README.md".into()),
        // CO401GW1's board has the 48-pin package (PINS-co401gw1.md), CO401Memory1's the 32-pin.
        "stm32f0" if device == "co401gw1" => Ok("STM32F042C6Tx"),
        "stm32f0" => Ok("STM32F042K6Tx"),
        "stm32f091" => Ok("STM32F091RCTx"),
        "stm32f072" => Ok("STM32F072CBTx"),
        other => {
            let known: Vec<&str> = BOARDS.iter().map(|b| b.name).collect();
            Err(format!("no board `{other}` to flash (boards: {}); pass --chip to flash an image of your own board", known.join(", ")))
        }
    }
}

/// `cargo xtask flash`: writes an image with `probe-rs download`.
pub fn flash(args: &[String]) -> Result {
    let FlashArgs { device, board, chip } = flash_args(args)?;
    let chip = match chip {
        Some(c) => c,
        None => chip_of(&board, &device)?.to_string(),
    };
    let elf = root().join("target/dist/images").join(format!("{device}-{board}.elf"));
    if !elf.exists() {
        build()?;
    }
    if !elf.exists() {
        return Err(format!("no image {} after `cargo xtask dist`: is `{device}` built for board `{board}`?", elf.display()));
    }
    if std::process::Command::new("probe-rs").arg("--version").output().is_err() {
        return Err(
            "probe-rs is not installed. Install it with `cargo install probe-rs-tools --locked` (about 8 minutes on a 2-core machine), then run this again."
                .into(),
        );
    }
    run(std::process::Command::new("probe-rs").args(["download", "--chip", &chip]).arg(&elf))?;
    run(std::process::Command::new("probe-rs").args(["reset", "--chip", &chip]))
}
