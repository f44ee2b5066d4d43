//! `cargo xtask dist`: check every spec and build every output into `target/dist/`.
//! `cargo xtask test`: install what the test suite needs, then run all of it.
//!
//! Both say what they install before they install it.
#![forbid(unsafe_code)]

mod bench;
mod elf;
mod images;
mod kani;
mod setup;
mod size;
mod symbols;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("dist") => dist(),
        Some("test") => test(),
        Some("size") => setup::rust_targets().and_then(|()| match args.get(1).map(String::as_str) {
            Some("--symbols") => symbols::report(args.get(2..).unwrap_or_default()),
            _ => size::report(),
        }),
        Some("flash") => images::flash(args.get(1..).unwrap_or_default()),
        Some("bench") => bench::main(args.get(1..).unwrap_or_default()),
        Some("kani") => kani::main(args.get(1..).unwrap_or_default()),
        _ => {
            eprintln!(
                "usage: cargo xtask <dist|test|size|flash|bench|kani>\n  dist   check every spec; write EDS files, docs and firmware images into target/dist/\n  test   install missing tools, then run the whole test suite\n  size   flash and RAM of each device's generated code on a Cortex-M0\n         --symbols <device | image.elf> [count]: its largest symbols and flash per module\n  flash  --device <d> --board <b> [--chip <c>]: write an image with probe-rs\n  bench  [--selftest | --instructions | --callgrind]: instruction counts, stack peaks, criterion, sizes\n  kani   [--fast | --all | --list] [--filter PART] [--budget-minutes N]: the Kani harnesses (hand-written and generated), two at a time, as a table"
            );
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: error: {e}");
            ExitCode::FAILURE
        }
    }
}

pub type Result<T = ()> = std::result::Result<T, String>;

/// Firmware crates that must build for `thumbv6m-none-eabi` (Cortex-M0, no atomics).
const NO_STD_CRATES: &[&str] = &["coforge-types", "coforge-link", "coforge-stack", "co401memory1", "co401gw1", "cr3101", "canopenia"];

pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").canonicalize().unwrap_or_else(|_| PathBuf::from(".."))
}

fn specs() -> Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("spec"))
        .map_err(|e| format!("cannot list spec/: {e}"))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .collect();
    v.sort();
    Ok(v)
}

/// Runs a command in the repository root, echoing it; fails on a non-zero exit.
pub fn run(cmd: &mut Command) -> Result {
    let shown = format!("{} {}", cmd.get_program().to_string_lossy(), cmd.get_args().map(|a| a.to_string_lossy()).collect::<Vec<_>>().join(" "));
    println!("xtask: $ {shown}");
    if cmd.get_current_dir().is_none() {
        cmd.current_dir(root());
    }
    let status = cmd.status().map_err(|e| format!("cannot start `{shown}`: {e}"))?;
    if status.success() { Ok(()) } else { Err(format!("`{shown}` failed ({status})")) }
}

fn write(path: &Path, text: &str) -> Result {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

fn dist() -> Result {
    setup::rust_targets()?;
    let out = root().join("target/dist");
    let mut index = String::from("# coforge devices\n\n| Device | Spec | EDS | Objects | Errata |\n|---|---|---|---|---|\n");
    let mut failed = 0;
    for path in specs()? {
        let rel = path.strip_prefix(root()).unwrap_or(&path).display().to_string();
        let loaded = coforge_spec::load_str(&rel, &std::fs::read_to_string(&path).map_err(|e| format!("cannot read {rel}: {e}"))?);
        if !loaded.diagnostics.items.is_empty() {
            eprintln!("{}", loaded.render_diagnostics());
        }
        let Some(device) = loaded.device() else {
            failed += 1;
            continue;
        };
        let mut eds_files = Vec::new();
        for mode in device.mode_names() {
            let name = coforge_spec::eds::file_name(device, mode);
            let text = coforge_spec::eds::export(device, mode).map_err(|e| e.to_string())?;
            write(&out.join("eds").join(&name), &text)?;
            eds_files.push(format!("[{name}](../eds/{name})"));
        }
        let doc = format!("{}.md", device.identity.ident);
        write(&out.join("docs").join(&doc), &coforge_spec::docs::markdown(device))?;
        index.push_str(&format!(
            "| [{}]({doc}) | `{rel}` | {} | {} | {} |\n",
            device.identity.name,
            eds_files.join(", "),
            device.objects.len(),
            device.errata.len()
        ));
        println!("xtask: {rel}: {} EDS file(s), docs/{doc}", eds_files.len());
    }
    if failed > 0 {
        return Err(format!("{failed} spec(s) have errors"));
    }
    write(&out.join("docs/index.md"), &index)?;
    images::build()?;
    println!("xtask: dist written to {}", out.display());
    Ok(())
}

fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
}

/// What a clean clone's `cargo xtask test` writes at its peak: 8.5 GiB measured with
/// `CARGO_INCREMENTAL=0`, as `.ci/run` sets it (README, "The two commands").
const TEST_DISK_GIB: f64 = 9.0;

fn test() -> Result {
    setup::disk_space(TEST_DISK_GIB);
    setup::rust_targets()?;
    setup::rust_components()?;
    let python = setup::python_venv()?;
    setup::card_tools()?;

    println!("xtask: [1/8] formatting and lints");
    run(cargo().args(["fmt", "--all", "--check"]))?;
    run(cargo().args(["clippy", "--quiet", "--workspace", "--all-targets", "--", "-D", "warnings"]))?;

    println!("xtask: [2/8] main outputs build (cargo xtask dist; the image tests read its images)");
    dist()?;

    println!("xtask: [3/8] Rust tests, and the no_std crates for the smallest target");
    run(cargo().args(["test", "--workspace"]))?;
    for krate in NO_STD_CRATES {
        run(cargo().args(["build", "--quiet", "--release", "-p", krate, "--target", "thumbv6m-none-eabi"]))?;
    }

    println!("xtask: [4/8] specs: check and canonical formatting");
    run(cargo().args(["build", "--quiet", "-p", "coforge"]))?;
    let coforge = root().join("target/debug/coforge");
    let spec_args: Vec<PathBuf> = specs()?;
    run(Command::new(&coforge).arg("check").args(&spec_args))?;
    run(Command::new(&coforge).args(["fmt", "--check"]).args(&spec_args))?;

    println!("xtask: [5/8] interoperability tests with python-canopen, against the simulator and the QEMU image");
    setup::qemu()?;
    // The raw binary `dist` wrote: the tests run exactly what would be flashed.
    let qemu_image = root().join("target/dist/images/co401memory1-qemu.bin");
    let gw1_qemu_image = root().join("target/dist/images/co401gw1-qemu.bin");
    let ia_qemu_image = root().join("target/dist/images/canopenia-qemu.bin");
    let cr3101_qemu_image = root().join("target/dist/images/cr3101-qemu.bin");
    // CR3101's card layer alone on QEMU's SD card (a fixture; the device's image is in dist).
    let qemu_board = root().join("firmware/boards/qemu");
    run(cargo().args(["build", "--quiet", "--release", "--target", "thumbv7m-none-eabi", "--bin", "cr3101-card"]).current_dir(&qemu_board))?;
    let card_qemu_image = qemu_board.join("target/thumbv7m-none-eabi/release/cr3101-card");
    let status = Command::new(&python)
        .args(["-m", "pytest", "-q", "tests/python"])
        .env("COFORGE_BIN", &coforge)
        .env("COFORGE_QEMU_IMAGE", &qemu_image)
        .env("COFORGE_GW1_QEMU_IMAGE", &gw1_qemu_image)
        .env("COFORGE_IA_QEMU_IMAGE", &ia_qemu_image)
        .env("COFORGE_CR3101_QEMU_IMAGE", &cr3101_qemu_image)
        .env("COFORGE_CARD_QEMU_IMAGE", &card_qemu_image)
        .current_dir(root())
        .status()
        .map_err(|e| format!("cannot run pytest: {e}"))?;
    match status.code() {
        Some(0) => {}
        // pytest's "no tests collected" must not pass as a green run.
        Some(5) => return Err("pytest collected no tests in tests/python".into()),
        _ => return Err(format!("pytest failed ({status})")),
    }
    println!("xtask: [6/8] short fuzz runs of every streaming decoder (cargo fuzz)");
    fuzz()?;

    println!("xtask: [7/8] Kani proofs of the fast harnesses, if this machine has Kani");
    kani::ci()?;

    println!("xtask: [8/8] size of the generated code on a Cortex-M0");
    size::report()?;

    println!("xtask: all tests passed");
    Ok(())
}

/// The fuzz targets in `verification/fuzz` (one per streaming decoder).
const FUZZ_TARGETS: &[&str] =
    &["nibble_decoder", "length_byte_decoder", "start_crc_decoder", "node_frames", "gw1_inputs", "manager_inputs", "canopenia_inputs", "canopenia_config_file"];

/// Runs each fuzz target for `FUZZ_SECONDS` (default 20) seconds; a crash fails the run.
fn fuzz() -> Result {
    setup::fuzz_tools()?;
    let seconds = std::env::var("FUZZ_SECONDS").unwrap_or_else(|_| "20".into());
    for target in FUZZ_TARGETS {
        run(Command::new("cargo")
            .args(["+nightly", "fuzz", "run", target, "--", &format!("-max_total_time={seconds}")])
            .current_dir(root().join("verification/fuzz")))?;
    }
    Ok(())
}
