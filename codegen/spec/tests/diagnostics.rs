//! One fixture per validation rule: each breaks its rule, and its rendered diagnostics
//! (with `file:line:col` and snippet) are compared with a golden `.stderr` file.

mod common;

use coforge_spec::{Severity, load_str, validate::RULES};
use common::{crate_dir, files, golden};

/// Rules reported while loading and normalising, before the validation passes.
const LOAD_RULES: &[&str] = &["yaml", "spec-format", "spec-value", "spec-expr", "spec-structure", "spec-mode", "spec-repeat"];

fn all_rule_ids() -> Vec<&'static str> {
    LOAD_RULES.iter().copied().chain(RULES.iter().map(|r| r.id)).collect()
}

/// `od-default-range-limits` exercises `od-default-range`: the longest rule id that prefixes the name.
fn rule_of(stem: &str) -> Option<&'static str> {
    all_rule_ids().into_iter().filter(|id| stem == *id || stem.starts_with(&format!("{id}-"))).max_by_key(|id| id.len())
}

#[test]
fn every_invalid_fixture_reports_its_rule_and_matches_its_golden_output() {
    let dir = crate_dir().join("tests/fixtures/invalid");
    let fixtures = files(&dir, "yaml");
    assert!(fixtures.len() >= RULES.len(), "expected at least one fixture per rule, found {}", fixtures.len());
    let mut failures = Vec::new();
    for path in fixtures {
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or_default().to_string();
        let Some(rule) = rule_of(&stem) else {
            failures.push(format!("{stem}: the file name does not start with a rule id"));
            continue;
        };
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        let loaded = load_str(&format!("fixtures/invalid/{stem}.yaml"), &text);
        if !loaded.diagnostics.items.iter().any(|d| d.rule == rule && d.severity == Severity::Error) {
            failures.push(format!("{stem}: expected an error from `{rule}`, got:\n{}", loaded.render_diagnostics()));
            continue;
        }
        let rendered = loaded.render_diagnostics();
        assert!(rendered.contains(&format!("--> fixtures/invalid/{stem}.yaml:")), "{stem}: diagnostics must carry file:line:col\n{rendered}");
        if let Some(diff) = golden(&path.with_extension("stderr"), &rendered) {
            failures.push(diff);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn every_rule_has_a_fixture() {
    let dir = crate_dir().join("tests/fixtures/invalid");
    let stems: Vec<String> = files(&dir, "yaml").iter().filter_map(|p| p.file_stem()?.to_str().map(String::from)).collect();
    let missing: Vec<&str> = all_rule_ids().into_iter().filter(|id| !stems.iter().any(|s| rule_of(s) == Some(id))).collect();
    assert!(missing.is_empty(), "rules without a fixture: {missing:?}");
}

#[test]
fn rule_ids_are_unique_and_documented() {
    let ids = all_rule_ids();
    let mut sorted = ids.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(sorted.len(), ids.len(), "duplicate rule id");
    let readme = std::fs::read_to_string(crate_dir().join("../../spec/README.md")).unwrap_or_default();
    let undocumented: Vec<&str> = ids.into_iter().filter(|id| !readme.contains(&format!("`{id}`"))).collect();
    assert!(undocumented.is_empty(), "rules missing from spec/README.md: {undocumented:?}");
}

#[test]
fn the_valid_fixture_has_no_diagnostics() {
    let text = std::fs::read_to_string(crate_dir().join("tests/fixtures/valid/minimal.yaml")).unwrap_or_default();
    let loaded = load_str("minimal.yaml", &text);
    assert!(loaded.diagnostics.items.is_empty(), "{}", loaded.render_diagnostics());
    let device = loaded.device().expect("loads");
    // Templates expanded: 2 blocks with 5 entries each; PDO objects generated.
    assert_eq!(device.objects.iter().filter(|o| (0x5000..=0x5001).contains(&o.index)).map(|o| o.entries.len()).sum::<usize>(), 10);
    assert!(device.objects.iter().any(|o| o.index == 0x1A01 && o.generated));
}
