//! The lm3s6965's memory map for cortex-m-rt's link.x: 256 KiB of flash, 64 KiB of SRAM.
//! (Written to OUT_DIR: a `memory.x` in the crate root would shadow it.)

fn main() {
    let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    let memory = "MEMORY\n{\n  FLASH : ORIGIN = 0x00000000, LENGTH = 256K\n  RAM : ORIGIN = 0x20000000, LENGTH = 64K\n}\n";
    if std::fs::write(out.join("memory.x"), memory).is_err() {
        println!("cargo:warning=cannot write memory.x");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=build.rs");
    if std::env::var("TARGET").is_ok_and(|t| t.starts_with("thumb")) {
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
    }
}
