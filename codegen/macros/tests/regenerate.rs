//! Editing a spec regenerates the code: a scratch crate using `device!` is built, its spec is
//! changed, and the rebuilt program prints the new value.

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().expect("repo root")
}

fn run(dir: &Path) -> String {
    let out = Command::new(env!("CARGO"))
        .args(["run", "--quiet", "--offline"])
        .current_dir(dir)
        .env("CARGO_TARGET_DIR", dir.join("target"))
        .output()
        .expect("cargo runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

#[test]
fn editing_the_spec_rebuilds_the_generated_code() {
    let root = repo();
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("regenerate");
    std::fs::create_dir_all(dir.join("src")).expect("scratch dir");
    let path = |p: &str| root.join(p).display().to_string();
    let manifest = format!(
        "[package]\nname = \"regenerate\"\nversion = \"0.0.0\"\nedition = \"2024\"\npublish = false\n\n[dependencies]\ncoforge-macros = {{ path = {:?} }}\ncoforge-stack = {{ path = {:?} }}\ncoforge-link = {{ path = {:?} }}\n\n[workspace]\n",
        path("codegen/macros"),
        path("firmware/stack"),
        path("firmware/link")
    );
    std::fs::write(dir.join("Cargo.toml"), manifest).expect("manifest");
    // The main lock file pins the same dependency versions, so the offline build resolves.
    std::fs::copy(root.join("Cargo.lock"), dir.join("Cargo.lock")).expect("lock file");
    std::fs::write(dir.join("src/main.rs"), "coforge_macros::device!(\"spec.yaml\");\n\nfn main() {\n    println!(\"{:#06x}\", VENDOR_ID);\n}\n")
        .expect("main");
    let spec = std::fs::read_to_string(root.join("codegen/spec/tests/fixtures/valid/minimal.yaml")).expect("fixture");
    std::fs::write(dir.join("spec.yaml"), &spec).expect("spec");
    assert_eq!(run(&dir), "0x1234");
    // The vendor ID lives in `device` and in 1018.1 (the spec check keeps them equal).
    std::fs::write(dir.join("spec.yaml"), spec.replace("0x1234", "0x4321")).expect("edited spec");
    assert_eq!(run(&dir), "0x4321", "the edited spec was picked up without touching any Rust file");
}
