// trybuild builds this file in target/tests/trybuild/coforge-macros/, so the spec path is
// relative to that directory (four levels below the workspace root).
coforge_macros::device!("../../../../codegen/spec/tests/fixtures/invalid/od-duplicate.yaml");

fn main() {}
