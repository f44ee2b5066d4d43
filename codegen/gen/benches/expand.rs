//! What `device!` costs a build: load, validate and generate each spec (the aim for the
//! largest spec is under 150 ms).

use criterion::{Criterion, criterion_group, criterion_main};
use std::path::Path;

fn expand(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut group = c.benchmark_group("expand");
    group.sample_size(20);
    for name in ["co401memory1", "co401gw1", "cr3101", "canopenia"] {
        let spec = format!("spec/{name}.yaml");
        group.bench_function(name, |b| b.iter(|| coforge_codegen::expand(&spec, &root, &coforge_codegen::Options::default()).map(|t| t.is_empty())));
    }
    group.finish();
}

criterion_group!(benches, expand);
criterion_main!(benches);
