//! The generated code of every spec is kept as an insta snapshot: any change to generation
//! shows up as a reviewable diff (`cargo insta review`, or `INSTA_UPDATE=always`).

use coforge_codegen::{Options, expand, generate, pretty};
use std::path::{Path, PathBuf};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn generated_code_of_every_spec() {
    for name in ["canopenia", "co401gw1", "co401memory1", "cr3101"] {
        let path = repo().join(format!("spec/{name}.yaml"));
        let device = coforge_spec::load_file(&path).into_device().unwrap_or_else(|| panic!("{name} loads"));
        let code = pretty(generate(&device, &Options::default())).unwrap_or_else(|e| panic!("{name}: {e}"));
        insta::assert_snapshot!(name, code);
    }
}

#[test]
fn the_node_section_becomes_node_config() {
    let path = repo().join("codegen/spec/tests/fixtures/valid/minimal.yaml");
    let device = coforge_spec::load_file(&path).into_device().expect("the fixture loads");
    let code = pretty(generate(&device, &Options::default())).expect("generates");
    let start = code.find("pub const fn node_config").expect("node_config");
    let body = &code[start..start + code[start..].find("\n}").expect("its end")];
    for field in [
        "restart_time_object: Some(0x2000)",
        "rpdo_deadlines: false",
        "listed_emergencies_only: true",
        "tpdo_on_write: false",
        "remapping_object: Some(0x2004)",
    ] {
        assert!(body.contains(field), "{field} in\n{body}");
    }
}

#[test]
fn an_invalid_spec_expands_to_its_diagnostics() {
    let spec = "codegen/spec/tests/fixtures/invalid/od-duplicate.yaml";
    let err = expand(spec, &repo(), &Options::default()).err().unwrap_or_default();
    assert!(err.contains("error[od-duplicate]"), "{err}");
    assert!(err.contains(&format!("--> {spec}:")), "names the YAML file, line and column: {err}");
    let missing = expand("spec/none.yaml", &repo(), &Options::default()).err().unwrap_or_default();
    assert!(missing.contains("cannot read spec"), "{missing}");
}

#[test]
fn expansion_tracks_the_spec_file() {
    let tokens = expand("spec/canopenia.yaml", &repo(), &Options::default()).map(|t| t.to_string()).unwrap_or_default();
    assert!(tokens.contains("include_bytes !"), "{}", &tokens[..200.min(tokens.len())]);
    assert!(tokens.contains("canopenia.yaml"));
}
