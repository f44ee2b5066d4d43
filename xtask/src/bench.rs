//! `cargo xtask bench`: instruction counts of the devices' code on a Cortex-M3 under QEMU,
//! their stack peaks, the criterion benchmarks and the size report, into
//! `target/bench/report.md`.
//!
//! Each bench image of `firmware/boards/qemu` ([`BENCHES`]) runs its scenarios between the
//! marker functions `bench_begin` and `bench_end` and checks every answer; the TCG plugin
//! `bench/insn-count` counts the instructions executed from the first instruction of
//! `bench_begin` up to the first one of `bench_end`. Scenario 0 is empty, so its count is the
//! markers' own cost (the rest of `bench_begin` and the call of `bench_end`): the net figures
//! subtract it, so they are the instructions of the module's code and the image's loop that
//! hands it the input and collects the answer frames.

use crate::{Result, cargo, root, run, setup};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant, SystemTime};

const BOARD_DIR: &str = "firmware/boards/qemu";
const TARGET: &str = "thumbv7m-none-eabi";
/// A bench image and the device it measures.
pub struct Bench {
    pub image: &'static str,
    /// The device (and the prefix of its image names in `dist`).
    pub device: &'static str,
    title: &'static str,
    /// It runs with QEMU's SD card: a blank card image it formats itself ([`card_args`]).
    card: bool,
}

pub const BENCHES: &[Bench] = &[
    Bench { image: "bench-memory1", device: "co401memory1", title: "CO401Memory1", card: false },
    Bench { image: "bench-gw1", device: "co401gw1", title: "CO401GW1", card: false },
    // Not a device: the manager of coforge-stack, which CANopenIA runs.
    Bench { image: "bench-manager", device: "manager", title: "coforge-stack manager (127 nodes monitored, 31 scans cached)", card: false },
    Bench { image: "bench-canopenia", device: "canopenia", title: "CANopenIA (remote access, 8 scans cached)", card: false },
    // Not an image of its own: CANopenIA's start with a loaded configuration file.
    Bench { image: "bench-canopenia-config", device: "canopenia-config", title: "CANopenIA with the vendor's CiA 401 file loaded", card: false },
    Bench { image: "bench-cr3101", device: "cr3101", title: "CR3101 (QEMU's SD card, FAT16)", card: true },
];
/// The blank card a bench image with `card` gets: QEMU's SD card needs a power of two.
const CARD_BYTES: u64 = 16 << 20;
/// A run takes well under a second; this only stops a hung image.
const QEMU_TIMEOUT: Duration = Duration::from_secs(120);
/// The aims: instructions per expedited SDO request and per RPDO.
const AIMS: &[(&str, u64)] = &[("sdo-expedited", 800), ("rpdo", 400)];
/// Criterion's defaults (3 s warm-up, 5 s measurement per benchmark) take about 4 minutes for
/// the ~30 benchmarks here; these settings take under 2 and keep the means within a few %.
const CRITERION_ARGS: &[&str] = &["--warm-up-time", "1", "--measurement-time", "2"];

fn out_dir() -> PathBuf {
    root().join("target/bench")
}

/// Builds the bench images and returns their ELFs, in [`BENCHES`] order.
fn build_images() -> Result<Vec<PathBuf>> {
    let dir = root().join(BOARD_DIR);
    let mut cmd = cargo();
    cmd.args(["build", "--quiet", "--release", "--target", TARGET]);
    for b in BENCHES {
        cmd.args(["--bin", b.image]);
    }
    run(cmd.current_dir(&dir))?;
    Ok(BENCHES.iter().map(|b| dir.join("target").join(TARGET).join("release").join(b.image)).collect())
}

/// Builds the plugin into `target/bench/libinsn_count.so`.
fn build_plugin() -> Result<PathBuf> {
    let so = out_dir().join("libinsn_count.so");
    std::fs::create_dir_all(out_dir()).map_err(|e| format!("cannot create {}: {e}", out_dir().display()))?;
    let source = root().join("bench/insn-count/insn_count.c");
    run(Command::new("gcc").args(["-shared", "-fPIC", "-O2", "-Wall", "-Wextra", "-Werror", "-o"]).arg(&so).arg(&source))
        .map_err(|e| format!("{e} (gcc builds the QEMU plugin; install it with `apt-get install gcc`)"))?;
    Ok(so)
}

/// What a QEMU run printed, and how it ended.
struct QemuRun {
    code: Option<i32>,
    stdout: String,
    stderr: String,
}

/// Runs the image in QEMU with semihosting (its exit code is the image's), `extra` after the
/// kernel, killing it after [`QEMU_TIMEOUT`].
fn qemu(elf: &Path, extra: &[String]) -> Result<QemuRun> {
    setup::qemu()?;
    let mut cmd = Command::new("qemu-system-arm");
    cmd.args(["-machine", "lm3s6965evb", "-nographic", "-monitor", "none", "-semihosting-config", "enable=on,target=native", "-kernel"])
        .arg(elf)
        .args(extra)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    println!("xtask: $ qemu-system-arm ... -kernel {} {}", elf.display(), extra.join(" "));
    let mut child = cmd.spawn().map_err(|e| format!("cannot start qemu-system-arm: {e}"))?;
    let reader = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut text = String::new();
            if let Some(mut p) = pipe {
                let _ = p.read_to_string(&mut text);
            }
            text
        })
    };
    let out = reader(child.stdout.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    let err = reader(child.stderr.take().map(|p| Box::new(p) as Box<dyn Read + Send>));
    let started = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().map_err(|e| format!("waiting for qemu-system-arm: {e}"))? {
            break status;
        }
        if started.elapsed() > QEMU_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("qemu-system-arm did not finish within {} s: the bench image hangs", QEMU_TIMEOUT.as_secs()));
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Ok(QemuRun { code: status.code(), stdout: out.join().unwrap_or_default(), stderr: err.join().unwrap_or_default() })
}

/// QEMU's arguments for `bench`'s card, if it has one: a new blank (all zeros, sparse) card
/// image in `target/bench`.
fn card_args(bench: &Bench) -> Result<Vec<String>> {
    if !bench.card {
        return Ok(Vec::new());
    }
    std::fs::create_dir_all(out_dir()).map_err(|e| format!("cannot create {}: {e}", out_dir().display()))?;
    let card = out_dir().join(format!("{}-card.img", bench.image));
    let file = std::fs::File::create(&card).map_err(|e| format!("cannot create {}: {e}", card.display()))?;
    file.set_len(CARD_BYTES).map_err(|e| format!("cannot size {}: {e}", card.display()))?;
    Ok(vec!["-drive".into(), format!("if=sd,format=raw,file={}", card.display())])
}

/// Fails unless the image exited through semihosting with code 0.
fn check_exit(r: &QemuRun) -> Result {
    if r.code == Some(0) {
        return Ok(());
    }
    Err(format!("the bench image failed (exit code {:?}):\n{}{}", r.code, r.stdout, r.stderr))
}

/// `cargo xtask test`'s self-test: each bench image, without the plugin, must check every
/// answer and exit with code 0. Returns the deepest stack use each measured (device, bytes).
pub fn selftest() -> Result<Vec<(&'static str, u64)>> {
    let mut peaks = Vec::new();
    for (bench, elf) in BENCHES.iter().zip(build_images()?) {
        let r = qemu(&elf, &card_args(bench)?)?;
        check_exit(&r)?;
        let scenarios = r.stdout.lines().filter(|l| l.starts_with("bench ")).count();
        let peak = r
            .stdout
            .lines()
            .filter_map(|l| l.strip_prefix("stack-peak-bytes: ").or_else(|| l.strip_prefix("stack-peak-setup-bytes: ")))
            .filter_map(|n| n.trim().parse::<u64>().ok())
            .max()
            .ok_or_else(|| format!("{} reported no stack peak", bench.image))?;
        println!("xtask: {} self-test passed: {scenarios} scenarios, every answer as expected; stack peak {peak} bytes", bench.image);
        peaks.push((bench.device, peak));
    }
    Ok(peaks)
}

/// One measured scenario.
#[derive(Debug, PartialEq, Eq)]
struct Scenario {
    name: String,
    raw: u64,
}

/// What the image and the plugin printed: scenarios by id, the stack peaks.
#[derive(Debug, Default, PartialEq, Eq)]
struct Counts {
    scenarios: Vec<Scenario>,
    stack_peak: Option<u64>,
    stack_peak_setup: Option<u64>,
}

/// Reads `bench <id> <name>` and `stack-peak[-setup]-bytes: N` (the image, stdout) and
/// `scenario <n>: <count> instructions` (the plugin, stderr).
fn parse(stdout: &str, stderr: &str) -> std::result::Result<Counts, String> {
    let mut names = Vec::new();
    let mut c = Counts::default();
    for line in stdout.lines() {
        if let Some(rest) = line.strip_prefix("bench ")
            && let Some((id, name)) = rest.split_once(' ')
            && let Ok(id) = id.parse::<usize>()
        {
            names.push((id, name.to_string()));
        } else if let Some(n) = line.strip_prefix("stack-peak-bytes: ") {
            c.stack_peak = n.trim().parse().ok();
        } else if let Some(n) = line.strip_prefix("stack-peak-setup-bytes: ") {
            c.stack_peak_setup = n.trim().parse().ok();
        }
    }
    let mut counts = Vec::new();
    for line in stderr.lines() {
        if let Some(rest) = line.strip_prefix("scenario ")
            && let Some((id, count)) = rest.split_once(": ")
            && let (Ok(id), Some(Ok(count))) = (id.parse::<usize>(), count.strip_suffix(" instructions").map(str::parse::<u64>))
        {
            counts.push((id, count));
        }
    }
    if counts.is_empty() {
        return Err("the plugin printed no counts (is `-d plugin` given?)".into());
    }
    if counts.len() != names.len() {
        return Err(format!("{} scenario names from the image but {} counts from the plugin", names.len(), counts.len()));
    }
    for (i, ((id, name), (n, raw))) in names.into_iter().zip(counts).enumerate() {
        if id != i || n != i {
            return Err(format!("scenario ids out of order at {i}"));
        }
        c.scenarios.push(Scenario { name, raw });
    }
    Ok(c)
}

/// The marker overhead (scenario 0, empty) taken off each count.
fn net(c: &Counts, s: &Scenario) -> u64 {
    s.raw.saturating_sub(c.scenarios.first().map_or(0, |s| s.raw))
}

fn aim(name: &str) -> Option<u64> {
    AIMS.iter().find(|(prefix, _)| name.starts_with(prefix)).map(|&(_, n)| n)
}

/// The instruction table (Markdown).
fn instruction_table(c: &Counts) -> String {
    let mut t = String::from("| # | Scenario | Instructions | Aim | |\n|---:|---|---:|---:|---|\n");
    for (i, s) in c.scenarios.iter().enumerate().skip(1) {
        let n = net(c, s);
        let (aim, verdict) = match aim(&s.name) {
            Some(a) if n <= a => (format!("≤ {a}"), "within"),
            Some(a) => (format!("≤ {a}"), "**over**"),
            None => ("—".to_string(), ""),
        };
        t.push_str(&format!("| {i} | {} | {n} | {aim} | {verdict} |\n", s.name));
    }
    let peak = |p: Option<u64>| p.map_or("?".to_string(), |p| p.to_string());
    t.push_str(&format!(
        "\nMarker overhead subtracted: {} instructions (scenario 0, empty). Stack peak: {} bytes in the scenarios, {} bytes in construction and setup (from the top of RAM, `main`'s frame included).\n",
        c.scenarios.first().map_or(0, |s| s.raw),
        peak(c.stack_peak),
        peak(c.stack_peak_setup)
    ));
    t
}

/// Directories holding `benches/*.rs` files that use criterion, with their package names.
fn criterion_benches() -> Vec<(String, String)> {
    let mut found = Vec::new();
    for dir in ["codegen/spec", "codegen/gen", "cli", "firmware/sim", "firmware/stack", "verification"] {
        let crate_dir = root().join(dir);
        let Ok(manifest) = std::fs::read_to_string(crate_dir.join("Cargo.toml")) else { continue };
        let Some(package) = manifest.lines().find_map(|l| l.strip_prefix("name = ").map(|n| n.trim_matches('"').to_string())) else { continue };
        let Ok(entries) = std::fs::read_dir(crate_dir.join("benches")) else { continue };
        let mut names: Vec<String> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "rs"))
            .filter(|p| std::fs::read_to_string(p).is_ok_and(|t| t.contains("criterion_main!")))
            .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
            .collect();
        names.sort();
        found.extend(names.into_iter().map(|n| (package.clone(), n)));
    }
    found
}

/// Runs the criterion benches (in one cargo invocation: one build of their dependencies);
/// returns (benchmark id, mean in ns) of each one this run wrote.
fn criterion() -> Result<Vec<(String, f64)>> {
    let started = SystemTime::now();
    let mut cmd = cargo();
    cmd.args(["bench", "--quiet"]);
    for (package, bench) in criterion_benches() {
        cmd.args(["-p", &package, "--bench", &bench]);
    }
    run(cmd.arg("--").args(CRITERION_ARGS))?;
    let mut found = Vec::new();
    collect_estimates(&root().join("target/criterion"), started, &mut found);
    found.sort_by(|a, b| a.0.cmp(&b.0));
    Ok(found)
}

/// Walks criterion's output for each benchmark's `new/estimates.json` written since `since`
/// (older ones belong to benchmarks this run did not run).
fn collect_estimates(dir: &Path, since: SystemTime, found: &mut Vec<(String, f64)>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for path in entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| p.is_dir()) {
        let estimates = path.join("new/estimates.json");
        if !estimates.exists() {
            collect_estimates(&path, since, found);
            continue;
        }
        if !std::fs::metadata(&estimates).and_then(|m| m.modified()).is_ok_and(|t| t >= since) {
            continue;
        }
        let id = std::fs::read_to_string(path.join("new/benchmark.json")).ok().and_then(|t| json_string(&t, "full_id"));
        let mean = std::fs::read_to_string(&estimates).ok().and_then(|t| mean_point_estimate(&t));
        if let (Some(id), Some(mean)) = (id, mean) {
            found.push((id, mean));
        }
    }
}

/// The string value of `"key":"..."` in criterion's JSON (no escapes in benchmark ids here).
fn json_string(text: &str, key: &str) -> Option<String> {
    let rest = text.split_once(&format!("\"{key}\":"))?.1.trim_start().strip_prefix('"')?;
    Some(rest.split_once('"')?.0.to_string())
}

/// `mean.point_estimate` of criterion's `estimates.json`, in nanoseconds.
fn mean_point_estimate(text: &str) -> Option<f64> {
    let mean = text.split_once("\"mean\":")?.1;
    let value = mean.split_once("\"point_estimate\":")?.1;
    let end = value.find([',', '}']).unwrap_or(value.len());
    value.get(..end)?.trim().parse().ok()
}

fn human_time(ns: f64) -> String {
    match ns {
        n if n < 1e3 => format!("{n:.1} ns"),
        n if n < 1e6 => format!("{:.2} µs", n / 1e3),
        n if n < 1e9 => format!("{:.2} ms", n / 1e6),
        n => format!("{:.2} s", n / 1e9),
    }
}

/// `cargo xtask bench [--selftest | --instructions | --callgrind]`: the whole report, only the
/// self-test, only the Cortex-M3 instruction counts, or only the x86-64 manager figure.
pub fn main(args: &[String]) -> Result {
    match args {
        [] => report(),
        [flag] if flag == "--selftest" => selftest().map(|_| ()),
        [flag] if flag == "--instructions" => instructions().map(|table| println!("{table}")),
        [flag] if flag == "--callgrind" => callgrind_manager_upload().map(|n| println!("manager expedited SDO upload on x86-64: {n} instructions")),
        _ => Err("usage: cargo xtask bench [--selftest | --instructions | --callgrind]".into()),
    }
}

/// The instruction counts per scenario of every bench image, as Markdown: a heading and a
/// table per device.
fn instructions() -> Result<String> {
    setup::rust_targets()?;
    let plugin = build_plugin()?;
    let mut md = String::new();
    for (bench, elf) in BENCHES.iter().zip(build_images()?) {
        let bytes = std::fs::read(&elf).map_err(|e| format!("cannot read {}: {e}", elf.display()))?;
        let marker = |name: &str| crate::elf::symbol(&bytes, name).map_err(|e| format!("{}: {e}", elf.display()));
        let (begin, end) = (marker("bench_begin")?, marker("bench_end")?);
        let plugin_arg = format!("{},begin={begin:#x},end={end:#x}", plugin.display());
        let mut args = card_args(bench)?;
        args.extend(["-d".into(), "plugin".into(), "-plugin".into(), plugin_arg]);
        let r = qemu(&elf, &args)?;
        check_exit(&r)?;
        let counts = parse(&r.stdout, &r.stderr).map_err(|e| format!("{}: {e}", bench.image))?;
        md.push_str(&format!(
            "## {} on a Cortex-M3 (QEMU lm3s6965evb, instructions executed)\n\nImage `{}` ({TARGET}, release profile of `{BOARD_DIR}`), counted by the TCG plugin `bench/insn-count`: \
             one input handed to the device and `poll` until it is quiet, every answer checked.\n\n",
            bench.title, bench.image
        ));
        md.push_str(&instruction_table(&counts));
        md.push('\n');
    }
    Ok(md)
}

/// Uploads `firmware/stack/examples/manager_upload.rs` runs (its `UPLOADS`).
const MANAGER_UPLOADS: u64 = 1000;

/// x86-64 instructions per expedited SDO upload through the manager (request queued to
/// result taken), counted by callgrind with collection on only inside `upload_once`.
fn callgrind_manager_upload() -> Result<u64> {
    setup::valgrind()?;
    run(cargo().args(["build", "--quiet", "--release", "-p", "coforge-stack", "--example", "manager_upload"]).current_dir(root()))?;
    let out = out_dir().join("callgrind.manager_upload");
    std::fs::create_dir_all(out_dir()).map_err(|e| format!("cannot create {}: {e}", out_dir().display()))?;
    let result = Command::new("valgrind")
        .args(["--tool=callgrind", "--toggle-collect=manager_upload::upload_once"])
        .arg(format!("--callgrind-out-file={}", out.display()))
        .arg(root().join("target/release/examples/manager_upload"))
        .output()
        .map_err(|e| format!("cannot run valgrind: {e}"))?;
    if !result.status.success() {
        return Err(format!("valgrind failed: {}", String::from_utf8_lossy(&result.stderr)));
    }
    let stderr = String::from_utf8_lossy(&result.stderr);
    let refs = stderr
        .lines()
        .find_map(|l| l.split_once("I   refs:").map(|(_, n)| n.trim().replace(',', "")))
        .and_then(|n| n.parse::<u64>().ok())
        .ok_or_else(|| format!("callgrind printed no instruction total:\n{stderr}"))?;
    Ok(refs / MANAGER_UPLOADS)
}

/// Instruction counts, criterion figures and the size report into `target/bench/report.md`.
pub fn report() -> Result {
    let mut table = instructions()?;
    let per_upload = callgrind_manager_upload()?;
    table.push_str(&format!(
        "## coforge-stack manager on x86-64 (callgrind)\n\n`firmware/stack/examples/manager_upload.rs`, release: {per_upload} instructions per expedited SDO upload, request queued to result taken ({MANAGER_UPLOADS} uploads, collection only inside `upload_once`).\n\n"
    ));

    println!("xtask: criterion benchmarks ({})", CRITERION_ARGS.join(" "));
    let estimates = criterion()?;
    println!("xtask: size report");
    let size = crate::size::table()?;

    let mut md = String::from("# coforge benchmarks\n\n");
    md.push_str(&table);
    md.push_str(&format!("\n## Criterion (host, mean per iteration, `{}`)\n\n| Benchmark | Mean |\n|---|---:|\n", CRITERION_ARGS.join(" ")));
    for (id, ns) in &estimates {
        md.push_str(&format!("| {id} | {} |\n", human_time(*ns)));
    }
    md.push_str(&format!("\n## Size (`cargo xtask size`)\n\n```text\n{}\n```\n", size.trim_end()));
    let path = out_dir().join("report.md");
    crate::write(&path, &md)?;
    println!("\n{table}");
    println!("xtask: report written to {}", path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn image_and_plugin_output_pair_up_by_id() {
        let out = "stack-peak-setup-bytes: 100\nbench 0 calibration (empty)\nbench 1 sdo-expedited-upload 1018.1\nbench 2 rpdo1 x\nstack-peak-bytes: 200\n";
        let err = "Timer with period zero, disabling\nscenario 0: 7 instructions\nscenario 1: 507 instructions\nscenario 2: 1007 instructions\n";
        let c = parse(out, err).unwrap();
        assert_eq!((c.stack_peak, c.stack_peak_setup), (Some(200), Some(100)));
        assert_eq!(c.scenarios.len(), 3);
        assert_eq!(net(&c, &c.scenarios[1]), 500);
        let table = instruction_table(&c);
        assert!(table.contains("| 1 | sdo-expedited-upload 1018.1 | 500 | ≤ 800 | within |"), "{table}");
        assert!(table.contains("| 2 | rpdo1 x | 1000 | ≤ 400 | **over** |"), "{table}");
        assert!(parse(out, "scenario 0: 7 instructions\n").is_err());
        assert!(parse(out, "").is_err());
    }

    #[test]
    fn criterion_json_fields() {
        let estimates = r#"{"mean":{"confidence_interval":{"confidence_level":0.95,"lower_bound":1.0,"upper_bound":3.0},"point_estimate":2.5,"standard_error":0.1},"median":{"point_estimate":9.0}}"#;
        assert_eq!(mean_point_estimate(estimates), Some(2.5));
        assert_eq!(json_string(r#"{"group_id":"od","full_id":"od/co401gw1/read_1018_1","x":1}"#, "full_id").as_deref(), Some("od/co401gw1/read_1018_1"));
    }
}
