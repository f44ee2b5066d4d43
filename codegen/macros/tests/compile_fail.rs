//! A bad spec fails the build with coforge's diagnostic, naming the YAML file, line and column.

#[test]
fn invalid_specs_become_compile_errors() {
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/ui/*.rs");
}
