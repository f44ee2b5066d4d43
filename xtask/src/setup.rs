//! Installs what the build and the tests need, saying what and why before doing it.

use crate::{Result, root, run};
use std::path::PathBuf;
use std::process::Command;

/// The targets `rust-toolchain.toml` lists, so that one file stays the source of truth.
fn toolchain_list(key: &str) -> Vec<String> {
    let text = std::fs::read_to_string(root().join("rust-toolchain.toml")).unwrap_or_default();
    text.lines()
        .find_map(|l| l.trim().strip_prefix(key).and_then(|r| r.trim().strip_prefix('=')))
        .map(|list| list.trim().trim_matches(['[', ']']).split(',').map(|t| t.trim().trim_matches('"').to_string()).filter(|t| !t.is_empty()).collect())
        .unwrap_or_default()
}

fn output(cmd: &mut Command) -> Option<String> {
    cmd.output().ok().filter(|o| o.status.success()).map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
}

pub fn rust_targets() -> Result {
    let installed = output(Command::new("rustup").args(["target", "list", "--installed"]).current_dir(root()))
        .ok_or("rustup is needed to manage targets (https://rustup.rs)")?;
    for target in toolchain_list("targets") {
        if !installed.lines().any(|l| l.trim() == target) {
            println!("xtask: installing Rust target {target} (listed in rust-toolchain.toml, missing here)");
            run(Command::new("rustup").args(["target", "add", &target]))?;
        }
    }
    Ok(())
}

pub fn rust_components() -> Result {
    let installed = output(Command::new("rustup").args(["component", "list", "--installed"]).current_dir(root())).unwrap_or_default();
    for component in toolchain_list("components") {
        if !installed.lines().any(|l| l.trim().starts_with(&format!("{component}-")) || l.trim() == component) {
            println!("xtask: installing Rust component {component} (listed in rust-toolchain.toml, missing here)");
            run(Command::new("rustup").args(["component", "add", &component]))?;
        }
    }
    Ok(())
}

fn apt_install(packages: &[&str], why: &str) -> Result {
    println!("xtask: installing Debian packages {} ({why})", packages.join(" "));
    let sudo = output(Command::new("id").arg("-u")).is_some_and(|u| u.trim() != "0");
    let apt = |args: &[&str]| {
        let mut c = if sudo { Command::new("sudo") } else { Command::new("apt-get") };
        if sudo {
            c.arg("apt-get");
        }
        c.args(args).env("DEBIAN_FRONTEND", "noninteractive");
        c
    };
    run(&mut apt(&["update", "-q"]))?;
    let mut install = apt(&["install", "-y", "-q"]);
    install.args(packages);
    run(&mut install)
}

/// Free space on the file system that holds `target/`, from `df` (std has no portable call).
fn free_gib() -> Option<f64> {
    available_gib(&output(Command::new("df").args(["-Pk"]).arg(root()))?)
}

/// The "Available" column of `df -Pk` (POSIX format: a header, then one line), in GiB.
fn available_gib(df: &str) -> Option<f64> {
    let kib: f64 = df.lines().nth(1)?.split_whitespace().nth(3)?.parse().ok()?;
    Some(kib / (1024.0 * 1024.0))
}

/// Says how much disk the run has before it starts: a full test run from a clean clone
/// writes about `needed_gib` GiB (build directories, card images, fuzz corpora), and a disk
/// that fills up surfaces as a linker "Bus error" minutes in, not as a clear message.
pub fn disk_space(needed_gib: f64) {
    match free_gib() {
        Some(free) if free < needed_gib => println!(
            "xtask: warning: {free:.1} GiB free for {}; a run from a clean clone writes about {needed_gib:.0} GiB and may fail with \"No space left on device\" (builds already in target/ need less)",
            root().display()
        ),
        Some(free) => println!("xtask: {free:.1} GiB free for the build (a clean clone needs about {needed_gib:.0} GiB)"),
        None => println!("xtask: could not read the free disk space (`df` missing); a clean clone needs about {needed_gib:.0} GiB"),
    }
}

/// valgrind, whose callgrind counts the x86-64 instructions of the manager benchmark.
pub fn valgrind() -> Result {
    if output(Command::new("valgrind").arg("--version")).is_none() {
        apt_install(&["valgrind"], "callgrind counts host instructions for `cargo xtask bench`")?;
    }
    Ok(())
}

/// `qemu-system-arm`, which runs the Cortex-M3 images in the end-to-end tests.
pub fn qemu() -> Result {
    if output(Command::new("qemu-system-arm").arg("--version")).is_none() {
        apt_install(&["qemu-system-arm"], "QEMU runs the lm3s6965evb firmware images in the end-to-end tests")?;
    }
    Ok(())
}

/// mtools and dosfstools, the tools a PC reads a card with: the CR3101 card tests check what
/// the firmware wrote with `mcopy`/`mdir` and `fsck.fat`.
pub fn card_tools() -> Result {
    if output(Command::new("sh").args(["-c", "command -v mdir && command -v mcopy && command -v fsck.fat"])).is_none() {
        apt_install(&["mtools", "dosfstools"], "mtools and fsck.fat read and check the CR3101 card images the tests write")?;
    }
    Ok(())
}

/// `.venv` with the Python test peers from `tests/python/requirements.txt`.
pub fn python_venv() -> Result<PathBuf> {
    let venv = root().join(".venv");
    let python = venv.join("bin/python");
    if !python.exists() {
        if output(Command::new("python3").arg("--version")).is_none() {
            apt_install(&["python3", "python3-venv"], "Python runs the interoperability tests")?;
        }
        println!("xtask: creating Python venv {} for the test peers", venv.display());
        if run(Command::new("python3").args(["-m", "venv"]).arg(&venv)).is_err() {
            apt_install(&["python3-venv"], "the venv module is missing")?;
            run(Command::new("python3").args(["-m", "venv", "--clear"]).arg(&venv))?;
        }
    }
    let requirements = root().join("tests/python/requirements.txt");
    let wanted = std::fs::read_to_string(&requirements).map_err(|e| format!("cannot read {}: {e}", requirements.display()))?;
    let stamp = venv.join(".coforge-requirements");
    if std::fs::read_to_string(&stamp).ok().as_deref() != Some(wanted.as_str()) {
        let names: Vec<&str> = wanted.lines().filter(|l| !l.trim().is_empty() && !l.starts_with('#')).collect();
        println!("xtask: installing Python test peers into .venv: {}", names.join(" "));
        run(Command::new(&python).args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "-r"]).arg(&requirements))?;
        std::fs::write(&stamp, &wanted).map_err(|e| format!("cannot write {}: {e}", stamp.display()))?;
    }
    Ok(python)
}

/// A nightly toolchain and cargo-fuzz, which the fuzz runs need (libFuzzer, sanitizers).
pub fn fuzz_tools() -> Result {
    let toolchains = output(Command::new("rustup").args(["toolchain", "list"])).unwrap_or_default();
    if !toolchains.lines().any(|l| l.starts_with("nightly")) {
        println!("xtask: installing the nightly Rust toolchain (cargo fuzz builds with libFuzzer and sanitizers)");
        run(Command::new("rustup").args(["toolchain", "install", "nightly", "--profile", "minimal"]))?;
    }
    if output(Command::new("cargo").args(["fuzz", "--version"])).is_none() {
        println!("xtask: installing cargo-fuzz from crates.io (runs the fuzz targets in verification/fuzz)");
        run(Command::new("cargo").args(["install", "cargo-fuzz", "--locked"]))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_space_is_read_from_posix_df_output() {
        let df = "Filesystem     1024-blocks      Used Available Capacity Mounted on\n/dev/vda        263174212 40123456  56623104      42% /\n";
        assert_eq!(available_gib(df), Some(54.0));
        assert_eq!(available_gib("Filesystem 1024-blocks Used Available Capacity Mounted on\n"), None);
        assert_eq!(available_gib("header\n/dev/vda 1 2 lots 4% /\n"), None);
    }
}
