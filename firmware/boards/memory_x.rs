// Shared by the board crates' build scripts (`include!`d: each board is its own workspace).

/// Writes cortex-m-rt's `memory.x` for a chip to OUT_DIR and links with `link.x`. (A `memory.x`
/// in the crate root would shadow this one.)
fn write_memory_x(flash_origin: u32, flash_kib: u32, ram_kib: u32) {
    let out = std::path::PathBuf::from(std::env::var_os("OUT_DIR").unwrap_or_default());
    let memory = format!("MEMORY\n{{\n  FLASH : ORIGIN = {flash_origin:#010X}, LENGTH = {flash_kib}K\n  RAM : ORIGIN = 0x20000000, LENGTH = {ram_kib}K\n}}\n");
    if std::fs::write(out.join("memory.x"), memory).is_err() {
        println!("cargo:warning=cannot write memory.x");
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../memory_x.rs");
    if std::env::var("TARGET").is_ok_and(|t| t.starts_with("thumb")) {
        println!("cargo:rustc-link-arg-bins=-Tlink.x");
    }
}
