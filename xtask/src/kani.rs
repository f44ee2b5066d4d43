//! `cargo xtask kani [--fast | --all | --list] [--filter PART] [--budget-minutes N]`: the Kani harnesses
//! (`verification/`'s and those the generator emits in each device crate), two at a time, each with a time limit, as a table (result, time, peak
//! memory); and what `cargo xtask test` runs: the fast set, when this machine has Kani.
//!
//! Kani is not on any registry this project's machines reach, so a machine may lack it. Then
//! nothing fails and nothing passes silently: the run says how many harnesses Kani did not
//! run, and that their properties ran as exhaustive and random tests.

use crate::{Result, root};
use std::os::unix::process::CommandExt as _;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The Kani version the harnesses were verified with here (`.github/workflows/kani.yml` pins
/// the same).
pub const KANI_VERSION: &str = "0.63.0";

/// Harnesses that verify within a few minutes on a 2-core machine: every push runs them.
/// The rest (the other mirrored-bank harnesses and the generated ones) run nightly or on
/// demand. The write-pieces partition is pure arithmetic (41 s).
pub const FAST: &[&str] = &[
    "harnesses::mirrored_banks::banks_write_pieces_partition_any_range",
    "harnesses::crc_table_step_equals_bitwise",
    "harnesses::crc_equals_reference_up_to_4_bytes",
    "harnesses::crc_detects_bursts_up_to_16_bits_in_4_bytes",
    "harnesses::sum32_update_step",
    "harnesses::nibble_round_trip",
    "harnesses::length_byte_round_trip_up_to_8_bytes",
    "harnesses::start_crc_round_trip_up_to_6_bytes",
    "harnesses::decoders_are_total_for_8_bytes",
    "harnesses::resync_after_4_bytes_of_garbage",
    "harnesses::nmt_commands_address_only_this_node",
    "harnesses::sdo_first_request_answers_validly",
];

/// Harnesses run without Kani's assertion reachability checks (`--no-assertion-reach-checks`).
/// Those checks only add an UNREACHABLE status to an assertion no input reaches (the verdict
/// is the same: Kani counts such an assertion as holding), but CBMC spends a solver round on
/// them, and for the mirrored-bank harnesses those rounds were most of the time and memory.
/// For the generated dictionary write harnesses they were six rounds and 1,545 of 2,675 s of
/// solver time (CANopenIA; CO401GW1's `digital` then VERIFIED in one round, 27 min). The same
/// assertions are reached by the exhaustive and random tests of the same properties.
const WITHOUT_REACH_CHECKS: &[&str] = &["harnesses::mirrored_banks::", "/dictionary_proofs::write_"];

/// Harnesses whose CBMC and SAT solver need about 10 GB or more together (measured on the
/// 24 GB machine: two of them side by side ran it out of memory): run with no other harness
/// beside them. The other mirrored-bank harnesses build their banks with `in_state` or mount
/// agreeing banks and peak at 3.5 to 6.5 GB for CBMC and under 2 GB for kissat (stops 36 and
/// 37, verification/README.md), the block and format parts of the recovery cut at 1.5 and
/// 7.7 GB (stop 42), so they run two at a time.
const ALONE: &[&str] = &[
    "harnesses::mirrored_banks::banks_double_corruption_",
    "harnesses::mirrored_banks::banks_single_corruption_",
    "harnesses::emcy_register",
    "/dictionary_proofs::",
    "canopenia/serial::proofs::decoder_total",
];

/// Longest a single harness may run in `--all` (the issue's limit for the bank harnesses).
const ALL_LIMIT: Duration = Duration::from_secs(30 * 60);
/// Longest a generated dictionary write harness may run in `--all`: they took 16 to 34 min
/// on this machine beside another run (CR3101's `logging` 34 min 14 s, verification/README.md),
/// and the 30 minutes above are the bank harnesses' limit, not theirs.
const DICTIONARY_WRITE_LIMIT: Duration = Duration::from_secs(45 * 60);
/// Longest a fast harness may run before it counts as a failure.
const FAST_LIMIT: Duration = Duration::from_secs(10 * 60);
/// What `cargo xtask test` gives the fast set, unless `KANI_BUDGET_MINUTES` says otherwise.
const CI_BUDGET_MINUTES: u64 = 20;

/// How a harness ended.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Outcome {
    Verified,
    Failed,
    /// Stopped at its time limit.
    Timeout,
    /// Not started: the budget was spent.
    NotRun,
    /// Kani itself failed (no verification result).
    Error(String),
}

struct Run {
    name: String,
    outcome: Outcome,
    secs: f64,
    peak_kb: Option<u64>,
}

/// Whether `cargo kani` runs here.
pub fn installed() -> bool {
    Command::new("cargo").args(["kani", "--version"]).stdout(Stdio::null()).stderr(Stdio::null()).status().is_ok_and(|s| s.success())
}

/// The device crates whose generated code holds Kani harnesses (`serial::proofs`: one per
/// serial command and one for the decoder; `dictionary_proofs`: a write and a read harness
/// per mode), with their specs. A harness of theirs is named `<crate>/<path>`; a name without
/// a crate is one of `verification/`.
const DEVICE_CRATES: &[(&str, &str)] =
    &[("co401memory1", "spec/co401memory1.yaml"), ("co401gw1", "spec/co401gw1.yaml"), ("cr3101", "spec/cr3101.yaml"), ("canopenia", "spec/canopenia.yaml")];

/// The dictionary harnesses the generator emits per mode (codegen/gen/src/dictionary_proofs.rs).
const DICTIONARY_HARNESSES_PER_MODE: usize = 2;

/// The crate directory and the harness path Kani knows of a harness name.
fn locate(name: &str) -> (PathBuf, &str) {
    match name.split_once('/') {
        Some((krate, path)) => (root().join("firmware/devices").join(krate), path),
        None => (root().join("verification"), name),
    }
}

/// The hand-written harnesses of `verification/src`, by counting their `#[kani::proof]`
/// attributes (what the workflow checks too).
fn handwritten_count() -> usize {
    let dir = root().join("verification/src");
    std::fs::read_dir(&dir)
        .map(|entries| entries.filter_map(|e| std::fs::read_to_string(e.ok()?.path()).ok()).map(|text| text.matches("#[kani::proof]").count()).sum())
        .unwrap_or(0)
}

/// The harnesses the generator emits for `spec`: one per serial command and one for the
/// decoder, and the dictionary's per mode.
fn generated_count(spec: &str) -> Result<usize> {
    let text = std::fs::read_to_string(root().join(spec)).map_err(|e| format!("cannot read {spec}: {e}"))?;
    let device = coforge_spec::load_str(spec, &text).into_device().ok_or(format!("{spec} does not load: run `coforge check {spec}`"))?;
    let modes = device.modes.len().max(1);
    Ok(device.serial.map_or(0, |s| s.commands.len() + 1) + DICTIONARY_HARNESSES_PER_MODE * modes)
}

/// Every harness, hand-written and generated.
fn harness_count() -> usize {
    handwritten_count() + DEVICE_CRATES.iter().filter_map(|(_, spec)| generated_count(spec).ok()).sum::<usize>()
}

/// Every harness's name, from `cargo kani list` in each crate; fails when a crate's list
/// does not hold what its sources say (a harness Kani does not see is never run).
fn all_harnesses() -> Result<Vec<String>> {
    let mut names = list(&root().join("verification"))?;
    if names.len() != handwritten_count() {
        return Err(format!("Kani lists {} harnesses in verification/, its sources have {} `#[kani::proof]`", names.len(), handwritten_count()));
    }
    for (krate, spec) in DEVICE_CRATES {
        let found = list(&root().join("firmware/devices").join(krate))?;
        let expected = generated_count(spec)?;
        if found.len() != expected {
            return Err(format!("Kani lists {} harnesses in {krate}, the generator emits {expected} for {spec}", found.len()));
        }
        names.extend(found.into_iter().map(|n| format!("{krate}/{n}")));
    }
    Ok(names)
}

/// The harnesses Kani lists in the crate at `dir`.
fn list(dir: &std::path::Path) -> Result<Vec<String>> {
    let mut cmd = Command::new("cargo");
    cmd.args(["kani", "list", "--format", "json"]).current_dir(dir);
    crate::run(with_incremental(&mut cmd))?;
    let file = dir.join("kani-list.json");
    let text = std::fs::read_to_string(&file).map_err(|e| format!("cannot read {}: {e}", file.display()))?;
    harness_names(&text)
}

/// The harness names in the output of `cargo kani list --format json`.
fn harness_names(text: &str) -> Result<Vec<String>> {
    let list: serde_json::Value = serde_json::from_str(text).map_err(|e| format!("kani-list.json: {e}"))?;
    // `"standard-harnesses": {"<file>": ["harnesses::a", ...], ...}`.
    let files = list.get("standard-harnesses").and_then(serde_json::Value::as_object).ok_or("kani-list.json has no standard-harnesses")?;
    Ok(files.values().filter_map(serde_json::Value::as_array).flatten().filter_map(|n| n.as_str().map(str::to_string)).collect())
}

/// `cargo xtask test`'s Kani step.
pub fn ci() -> Result {
    if !installed() {
        println!(
            "xtask: Kani not installed: {} harnesses not run by Kani; their properties ran as exhaustive/random tests (see verification/README.md)",
            harness_count()
        );
        return Ok(());
    }
    let minutes = std::env::var("KANI_BUDGET_MINUTES").ok().and_then(|m| m.parse().ok()).unwrap_or(CI_BUDGET_MINUTES);
    let names: Vec<String> = FAST.iter().map(|s| s.to_string()).collect();
    let runs = run_all(&names, |_| FAST_LIMIT, Duration::from_secs(minutes * 60))?;
    report(&runs, harness_count())
}

/// How long harness `name` may run in `--all`.
fn all_limit(name: &str) -> Duration {
    if name.contains("/dictionary_proofs::write_") { DICTIONARY_WRITE_LIMIT } else { ALL_LIMIT }
}

/// Shard `k` of `n` (1-based) of `names`: every `n`-th harness from the `k`-th, so that each
/// shard gets a share of every kind (the list is grouped by crate and module). The nightly
/// workflow runs the shards as parallel jobs: all harnesses in one job take longer than a
/// GitHub job may run.
fn shard(names: Vec<String>, k: usize, n: usize) -> Vec<String> {
    names.into_iter().enumerate().filter(|(i, _)| i % n == k - 1).map(|(_, name)| name).collect()
}

/// `K/N` with `1 <= K <= N`.
fn parse_shard(text: &str) -> Result<(usize, usize)> {
    let bad = || format!("--shard takes K/N with 1 <= K <= N, not `{text}`");
    let (k, n) = text.split_once('/').ok_or_else(bad)?;
    let (k, n): (usize, usize) = (k.parse().map_err(|_| bad())?, n.parse().map_err(|_| bad())?);
    if k == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}

/// `cargo xtask kani [--fast | --all | --list] [--filter PART] [--shard K/N] [--budget-minutes N]`.
pub fn main(args: &[String]) -> Result {
    if !installed() {
        return Err(format!("Kani is not installed: `cargo kani --version` fails (the harnesses were verified with Kani {KANI_VERSION})"));
    }
    let mut all = false;
    let mut filter: Option<String> = None;
    let mut part: Option<(usize, usize)> = None;
    let mut budget = Duration::from_secs(24 * 3600);
    let mut rest = args.iter();
    while let Some(arg) = rest.next() {
        match arg.as_str() {
            "--all" => all = true,
            "--fast" => all = false,
            "--list" => {
                let names = all_harnesses()?;
                names.iter().for_each(|n| println!("{n}"));
                println!("xtask: {} harnesses: {} hand-written, {} generated", names.len(), handwritten_count(), names.len() - handwritten_count());
                return Ok(());
            }
            "--filter" => filter = Some(rest.next().ok_or("--filter takes a part of a harness name")?.clone()),
            "--shard" => part = Some(parse_shard(rest.next().ok_or("--shard takes K/N")?)?),
            "--budget-minutes" => {
                let m: u64 = rest.next().and_then(|m| m.parse().ok()).ok_or("--budget-minutes takes a number")?;
                budget = Duration::from_secs(m * 60);
            }
            other => {
                return Err(format!(
                    "unknown argument `{other}`; usage: cargo xtask kani [--fast | --all | --list] [--filter PART] [--shard K/N] [--budget-minutes N]"
                ));
            }
        }
    }
    let mut names: Vec<String> = if all { all_harnesses()? } else { FAST.iter().map(|s| s.to_string()).collect() };
    if let Some(part) = &filter {
        names.retain(|n| n.contains(part.as_str()));
        if names.is_empty() {
            return Err(format!("no harness name contains `{part}` (`cargo xtask kani --list` lists them)"));
        }
    }
    if let Some((k, n)) = part {
        names = shard(names, k, n);
        println!("xtask: shard {k} of {n}: {} harnesses", names.len());
    }
    let runs = run_all(&names, if all { all_limit } else { |_: &str| FAST_LIMIT }, budget)?;
    report(&runs, harness_count())
}

/// Prints the table; fails unless every harness that ran was verified.
fn report(runs: &[Run], total: usize) -> Result {
    println!("| harness | Kani result | time | peak memory |\n|---|---|---:|---:|");
    for r in runs {
        let outcome = match &r.outcome {
            Outcome::Verified => "VERIFIED".to_string(),
            Outcome::Failed => "**FAILED**".to_string(),
            Outcome::Timeout => "**timeout**".to_string(),
            Outcome::NotRun => "not run (budget spent)".to_string(),
            Outcome::Error(e) => format!("**error**: {e}"),
        };
        let mem = r.peak_kb.map_or("—".to_string(), |kb| format!("{} MB", kb / 1024));
        println!("| `{}` | {outcome} | {:.1} s | {mem} |", r.name, r.secs);
    }
    let verified = runs.iter().filter(|r| r.outcome == Outcome::Verified).count();
    let not_run = runs.iter().filter(|r| r.outcome == Outcome::NotRun).count();
    println!(
        "xtask: Kani {KANI_VERSION}: {verified} of {} harnesses run here VERIFIED, {not_run} not run for the budget; {} of the {total} harnesses are in the slow set (`cargo xtask kani --all`)",
        runs.len(),
        total.saturating_sub(FAST.len())
    );
    let bad: Vec<&str> = runs.iter().filter(|r| !matches!(r.outcome, Outcome::Verified | Outcome::NotRun)).map(|r| r.name.as_str()).collect();
    if bad.is_empty() { Ok(()) } else { Err(format!("Kani did not verify: {}", bad.join(", "))) }
}

/// A running harness.
struct Job {
    name: String,
    child: Child,
    started: Instant,
    log: PathBuf,
    time_file: PathBuf,
}

/// Runs `names` two at a time (each worker with a target directory of its own: two `cargo
/// kani` in one directory race on its goto files), each within its `limit`, none started after
/// `budget` has passed; a harness that [`runs_alone`] has the machine to itself.
fn run_all(names: &[String], limit: fn(&str) -> Duration, budget: Duration) -> Result<Vec<Run>> {
    let out = root().join("target/kani-runs");
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let began = Instant::now();
    let mut queue = names.iter().peekable();
    let mut workers: [Option<Job>; 2] = [None, None];
    let mut runs = Vec::new();
    loop {
        for slot in workers.iter_mut() {
            let Some(job) = slot else { continue };
            let done = job.child.try_wait().map_err(|e| e.to_string())?.is_some();
            if !done && job.started.elapsed() < limit(&job.name) {
                continue;
            }
            if !done {
                // The whole group: cargo, kani and the cbmc underneath.
                let _ = Command::new("kill").args(["-KILL", "--", &format!("-{}", job.child.id())]).status();
                let _ = job.child.wait();
            }
            runs.push(finish(job, done));
            *slot = None;
        }
        for w in 0..workers.len() {
            let Some(name) = queue.peek().copied() else { break };
            if began.elapsed() >= budget {
                runs.push(Run { name: name.clone(), outcome: Outcome::NotRun, secs: 0.0, peak_kb: None });
                queue.next();
                continue;
            }
            let busy: Vec<&Job> = workers.iter().flatten().collect();
            if workers[w].is_some() || (!busy.is_empty() && (runs_alone(name) || busy.iter().any(|j| runs_alone(&j.name)))) {
                continue;
            }
            queue.next();
            workers[w] = Some(start(name, w, &out)?);
        }
        if workers.iter().all(Option::is_none) && queue.peek().is_none() {
            break;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    // In the order asked.
    runs.sort_by_key(|r| names.iter().position(|n| *n == r.name));
    Ok(runs)
}

/// Kani's compile of a crate with incremental compilation on (cargo's default for the dev
/// profile), whatever the caller's environment says: with `CARGO_INCREMENTAL=0`, which
/// `.ci/run` sets, Kani 0.63's compiler panics on `MirroredBanks::settle` ("Found
/// uninitialized bytes", in the codegen of a constant), and every harness of the crate fails
/// to compile (stop 38: the fast set in a clean-clone `.ci/run`).
fn with_incremental(cmd: &mut Command) -> &mut Command {
    cmd.env("CARGO_INCREMENTAL", "1")
}

/// Whether `name` runs without reachability checks: see [`WITHOUT_REACH_CHECKS`].
fn without_reach_checks(name: &str) -> bool {
    WITHOUT_REACH_CHECKS.iter().any(|part| name.contains(part))
}

/// Whether `name` needs the machine to itself: see [`ALONE`].
fn runs_alone(name: &str) -> bool {
    ALONE.iter().any(|part| name.contains(part))
}

/// Starts `cargo kani` on harness `name` in worker `w`'s target directory, its output and peak
/// memory into `out`.
fn start(name: &str, w: usize, out: &std::path::Path) -> Result<Job> {
    let safe = name.replace("::", "-").replace('/', "-");
    let log = out.join(format!("{safe}.log"));
    let time_file = out.join(format!("{safe}.time"));
    let time = std::path::Path::new("/usr/bin/time").exists();
    let mut cmd = if time { Command::new("/usr/bin/time") } else { Command::new("cargo") };
    if time {
        cmd.args(["-f", "%M", "-o"]).arg(&time_file).arg("cargo");
    }
    let (dir, path) = locate(name);
    cmd.args(["kani", "--harness", path, "--exact", "--target-dir"]).arg(root().join(format!("target/kani-w{w}"))).current_dir(dir).process_group(0);
    with_incremental(&mut cmd);
    if without_reach_checks(name) {
        cmd.arg("--no-assertion-reach-checks");
    }
    let file = std::fs::File::create(&log).map_err(|e| format!("cannot create {}: {e}", log.display()))?;
    let err = file.try_clone().map_err(|e| e.to_string())?;
    let child = cmd.stdout(file).stderr(err).spawn().map_err(|e| format!("cannot run cargo kani: {e}"))?;
    println!("xtask: kani {name}");
    Ok(Job { name: name.to_string(), child, started: Instant::now(), log, time_file })
}

fn finish(job: &Job, done: bool) -> Run {
    let secs = job.started.elapsed().as_secs_f64();
    let log = std::fs::read_to_string(&job.log).unwrap_or_default();
    let peak_kb = std::fs::read_to_string(&job.time_file).ok().and_then(|t| t.lines().last()?.trim().parse().ok());
    let outcome = if !done {
        Outcome::Timeout
    } else if log.contains("VERIFICATION:- SUCCESSFUL") {
        Outcome::Verified
    } else if log.contains("VERIFICATION:- FAILED") {
        Outcome::Failed
    } else {
        let last = log.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("no output").trim().to_string();
        Outcome::Error(format!("{last} (log: {})", job.log.display()))
    };
    Run { name: job.name.clone(), outcome, secs, peak_kb }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harness_names_come_from_kanis_list() {
        let json = r#"{"kani-version":"0.63.0","standard-harnesses":{"verification/src/harnesses.rs":["harnesses::a","harnesses::m::b"],"x.rs":["c"]},"totals":{"standard-harnesses":3}}"#;
        assert_eq!(harness_names(json), Ok(vec!["harnesses::a".to_string(), "harnesses::m::b".to_string(), "c".to_string()]));
        assert!(harness_names("{}").is_err());
        assert!(FAST.iter().all(|h| h.starts_with("harnesses::")));
    }

    #[test]
    fn shards_split_the_list_without_loss_or_overlap() {
        let names: Vec<String> = (0..10).map(|i| format!("h{i}")).collect();
        let shards: Vec<Vec<String>> = (1..=4).map(|k| shard(names.clone(), k, 4)).collect();
        assert_eq!(shards[0], ["h0", "h4", "h8"]);
        assert_eq!(shards[3], ["h3", "h7"]);
        let mut all: Vec<String> = shards.concat();
        all.sort();
        let mut expected = names.clone();
        expected.sort();
        assert_eq!(all, expected);
        assert_eq!(parse_shard("2/4"), Ok((2, 4)));
        for bad in ["0/4", "5/4", "2", "a/4", "2/"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn dictionary_write_harnesses_get_longer_than_the_bank_harnesses() {
        assert_eq!(all_limit("harnesses::mirrored_banks::banks_format_cut_of_settled_banks"), ALL_LIMIT);
        assert_eq!(all_limit("cr3101/dictionary_proofs::write_keeps_the_rules_logging"), DICTIONARY_WRITE_LIMIT);
        assert_eq!(all_limit("cr3101/dictionary_proofs::read_keeps_the_rules_logging"), ALL_LIMIT);
        assert!(DICTIONARY_WRITE_LIMIT > ALL_LIMIT);
    }

    #[test]
    fn the_memory_hungry_harnesses_run_alone_and_the_fast_set_in_pairs() {
        assert!(runs_alone("harnesses::mirrored_banks::banks_double_corruption_of_block_0_found_by_a_read_is_lost"));
        assert!(!runs_alone("harnesses::mirrored_banks::banks_recovery_cut_of_block_0_for_any_contents"));
        assert!(!runs_alone("harnesses::mirrored_banks::banks_write_cut_of_2_bytes_at_1_leaves_old_or_new"));
        assert!(!runs_alone("harnesses::mirrored_banks::banks_format_cut_at_any_byte"));
        assert!(runs_alone("cr3101/dictionary_proofs::read_keeps_the_rules_logging"));
        assert!(runs_alone("canopenia/serial::proofs::decoder_total"));
        assert!(!runs_alone("co401gw1/serial::proofs::decoder_total"));
        assert!(FAST.iter().all(|h| !runs_alone(h)));
    }

    #[test]
    fn the_bank_and_dictionary_write_harnesses_run_without_reach_checks() {
        assert!(without_reach_checks("harnesses::mirrored_banks::banks_format_cut_at_any_byte"));
        assert!(without_reach_checks("cr3101/dictionary_proofs::write_keeps_the_rules_logging"));
        assert!(!without_reach_checks("cr3101/dictionary_proofs::read_keeps_the_rules_logging"));
        assert!(!without_reach_checks("harnesses::crc_table_step_equals_bitwise"));
    }

    #[test]
    fn kani_compiles_incrementally_even_when_the_caller_turned_it_off() {
        let mut cmd = Command::new("cargo");
        cmd.env("CARGO_INCREMENTAL", "0");
        let envs: Vec<_> = with_incremental(&mut cmd).get_envs().collect();
        assert_eq!(envs, [(std::ffi::OsStr::new("CARGO_INCREMENTAL"), Some(std::ffi::OsStr::new("1")))]);
    }

    #[test]
    fn a_generated_harness_runs_in_its_device_crate() {
        let (dir, path) = locate("co401gw1/serial::proofs::decoder_total");
        assert_eq!((dir, path), (root().join("firmware/devices/co401gw1"), "serial::proofs::decoder_total"));
        let (dir, path) = locate("harnesses::nibble_round_trip");
        assert_eq!((dir, path), (root().join("verification"), "harnesses::nibble_round_trip"));
    }

    #[test]
    fn the_generator_emits_a_harness_per_command_and_one_per_decoder_and_two_per_mode() {
        // CO401Memory1 has 14 serial commands and 1 mode, CO401GW1 16 and 3, CR3101 none and
        // 2, CANopenIA 9 and 1 (`coforge check`, `coforge info`).
        let counts: Vec<usize> = DEVICE_CRATES.iter().map(|(_, spec)| generated_count(spec).expect("spec loads")).collect();
        assert_eq!(counts, [15 + 2, 17 + 6, 4, 10 + 2]);
        assert_eq!(harness_count(), handwritten_count() + 56);
    }
}
