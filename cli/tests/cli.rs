//! The `coforge` binary as a user runs it: exit codes, messages, files written.

use std::path::PathBuf;
use std::process::{Command, Output};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn coforge(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_coforge")).args(args).current_dir(repo()).output().expect("coforge runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A path for `name` in a scratch directory of its own, removed when the returned guard drops.
fn scratch(name: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::Builder::new().prefix("coforge-cli-").tempdir().expect("temp dir");
    let path = dir.path().join(name);
    (dir, path)
}

#[test]
fn check_passes_on_the_four_specs() {
    let o = coforge(&["check", "spec/canopenia.yaml", "spec/co401gw1.yaml", "spec/co401memory1.yaml", "spec/cr3101.yaml"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(out.lines().filter(|l| l.contains(": ok (")).count(), 4, "{out}");
}

#[test]
fn yaml_errors_are_reported_cleanly_with_a_position() {
    for (fixture, needle) in [("yaml-syntax", "mismatched bracket"), ("yaml-unknown-key", "unknown field `acess`")] {
        let path = format!("codegen/spec/tests/fixtures/invalid/{fixture}.yaml");
        let o = coforge(&["check", &path]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{fixture}: exit 1\n{err}");
        assert!(err.contains("error[yaml]") && err.contains(needle), "{fixture}: {err}");
        assert!(err.contains(&format!("--> {path}:")), "{fixture}: file:line:col\n{err}");
        assert!(!err.contains("panicked") && !err.contains("backtrace"), "{fixture}: no panic\n{err}");
    }
}

#[test]
fn a_missing_file_is_an_error_not_a_panic() {
    let o = coforge(&["check", "spec/does-not-exist.yaml"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("cannot read spec/does-not-exist.yaml"), "{}", stderr(&o));
}

#[test]
fn eds_needs_a_mode_for_devices_with_modes_and_writes_the_file() {
    let o = coforge(&["eds", "spec/co401gw1.yaml"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("choose one with --mode"), "{}", stderr(&o));
    let (_dir, out) = scratch("gw1.eds");
    let o = coforge(&["eds", "spec/co401gw1.yaml", "--mode", "mixed", "-o", out.to_str().unwrap_or_default()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let eds = std::fs::read_to_string(&out).unwrap_or_default();
    assert!(eds.starts_with("[FileInfo]") && eds.contains("[1018sub1]") && eds.contains("VendorNumber=0x58"), "{eds}");
}

#[test]
fn docs_render_the_object_dictionary() {
    let o = coforge(&["docs", "spec/co401memory1.yaml"]);
    assert!(o.status.success());
    let md = String::from_utf8_lossy(&o.stdout);
    assert!(md.contains("## Object dictionary") && md.contains("| 503F |") && md.contains("## Errata"), "{md}");
}

#[test]
fn fmt_check_reports_and_fmt_repairs_layout() {
    let original = std::fs::read_to_string(repo().join("spec/cr3101.yaml")).unwrap_or_default();
    let (_dir, messy) = scratch("messy.yaml");
    // Same data, different layout: no blank lines between sections, extra spaces after dashes.
    let lines: Vec<&str> = original.lines().collect();
    let messy_text: Vec<String> = lines
        .iter()
        .enumerate()
        .filter(|(i, l)| !(l.is_empty() && lines.get(i + 1).is_some_and(|n| !n.starts_with(' '))))
        .map(|(_, l)| l.replacen("- { ", "-   {  ", 1))
        .collect();
    std::fs::write(&messy, messy_text.join("\n") + "\n").expect("write");
    let path = messy.to_str().unwrap_or_default();
    let o = coforge(&["fmt", "--check", path]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("first difference at line"), "{}", stderr(&o));
    assert!(coforge(&["fmt", path]).status.success());
    assert_eq!(std::fs::read_to_string(&messy).unwrap_or_default(), original);
    assert!(coforge(&["fmt", "--check", "spec/cr3101.yaml"]).status.success());
}

#[test]
fn decode_names_the_command_and_its_fields() {
    let o = coforge(&["decode", "codegen/spec/tests/fixtures/valid/minimal.yaml", "21 03 18 10 01"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // Without --from the frame fits a request and an (empty) answer.
    assert_eq!(
        String::from_utf8_lossy(&o.stdout),
        "read_request (host_to_device, request): index=0x1018 sub=0x1\nread_answer (device_to_host, response): data=[] index=0x1018 sub=0x1\n"
    );
    let o = coforge(&["decode", "codegen/spec/tests/fixtures/valid/minimal.yaml", "--from", "device", "31", "01", "00"]);
    assert_eq!(String::from_utf8_lossy(&o.stdout), "write_tpdo_ack (device_to_host, ack): pdo=0x1 status=0x0\n");
    let o = coforge(&["decode", "codegen/spec/tests/fixtures/valid/minimal.yaml", "21 05 18"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("DataLen says 5 data bytes but 1 follow"), "{}", stderr(&o));
}

#[test]
fn beds_reproduces_the_vendors_file_from_its_eds() {
    let (_dir, out) = scratch("io.bin");
    let eds = "tests/vendor-data/canopenia/CiA401_IO_Node3.eds";
    // The vendor's tool ran on 02-11-2015; the stamp is not in the EDS, so it is given.
    let ident = "'CiA401_IO_Node3' 02-11-2015 12:43PM by ESAcademy";
    let o = coforge(&[
        "beds",
        "--from-eds",
        eds,
        "--vendor-conventions",
        "--node-id",
        "3",
        "--autostart",
        "--ident",
        ident,
        "-o",
        out.to_str().expect("utf-8 path"),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let ours = std::fs::read(&out).expect("written");
    let theirs = std::fs::read(repo().join("tests/vendor-data/canopenia/CiA401_IO_Node3.bin")).expect("vendor file");
    assert!(ours == theirs, "{} bytes against {}", ours.len(), theirs.len());
    assert!(stderr(&o).contains("96 SDO replies, 108 + 4 image entries (233 bytes), 4 RPDOs, 4 TPDOs"), "{}", stderr(&o));
}

#[test]
fn beds_exports_a_spec_and_explains_bad_arguments() {
    let (_dir, out) = scratch("ia.bin");
    let o = coforge(&["beds", "spec/canopenia.yaml", "--node-id", "5", "--bitrate", "250", "-o", out.to_str().expect("utf-8 path")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let bytes = std::fs::read(&out).expect("written");
    let file = coforge_beds::BinaryEds::parse(&bytes).expect("valid");
    assert_eq!((file.header().node_id, file.header().bitrate_kbit), (5, 250));
    assert!(file.header().ident.starts_with(b"'canopenia' coforge "));
    let cases: [(&[&str], &str); 3] = [
        (&["beds", "spec/co401gw1.yaml", "-o", "x.bin"], "choose one with --mode (mixed, digital, digital_alt)"),
        (&["beds", "spec/canopenia.yaml", "--node-id", "0", "-o", "x.bin"], "0 is not in 1..=127"),
        (&["beds", "spec/canopenia.yaml", "--bitrate", "100", "-o", "x.bin"], "invalid value '100'"),
    ];
    for (args, needle) in cases {
        let o = coforge(args);
        assert!(!o.status.success() && stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
    }
}
