//! How long a spec takes to load, validate and export. The `device!` proc-macro pays the
//! load + validate cost on every firmware build, so it is tracked here.

use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::path::PathBuf;

fn spec(name: &str) -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../spec").join(name);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn load_and_validate(c: &mut Criterion) {
    let mut group = c.benchmark_group("load_and_validate");
    for name in ["co401memory1.yaml", "co401gw1.yaml", "cr3101.yaml", "canopenia.yaml"] {
        let text = spec(name);
        group.bench_function(name, |b| b.iter(|| coforge_spec::load_str(name, black_box(&text)).into_device().is_some()));
    }
    group.finish();
}

fn export(c: &mut Criterion) {
    let text = spec("co401memory1.yaml");
    let device = coforge_spec::load_str("co401memory1.yaml", &text).into_device().expect("spec loads");
    c.bench_function("eds_export/co401memory1", |b| b.iter(|| coforge_spec::eds::export(black_box(&device), None)));
    c.bench_function("docs/co401memory1", |b| b.iter(|| coforge_spec::docs::markdown(black_box(&device))));
}

criterion_group!(benches, load_and_validate, export);
criterion_main!(benches);
