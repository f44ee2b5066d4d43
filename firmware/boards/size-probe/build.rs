//! Puts the linker script for a 64 KiB-flash Cortex-M0 where cortex-m-rt's link.x finds it.
//! (A `memory.x` in the crate root would shadow this one; the file is written to OUT_DIR.)

fn main() {
    let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    let memory = "MEMORY\n{\n  FLASH : ORIGIN = 0x08000000, LENGTH = 64K\n  RAM : ORIGIN = 0x20000000, LENGTH = 8K\n}\n";
    if std::fs::write(out.join("memory.x"), memory).is_err() {
        println!("cargo:warning=cannot write memory.x");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=build.rs");
    if std::env::var("TARGET").is_ok_and(|t| t.starts_with("thumb")) {
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
    }
}
