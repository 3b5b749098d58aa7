//! Half-Life import throughput (MB/s) on corpus files: MDL with its texture companion, and SMD.
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use sinew_import::{import_bytes, Format, ImportOptions};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("halflife_import");
    g.sample_size(20);
    let Some(dir) = sinew_testdata::corpus() else {
        return;
    };
    for (rel, format) in [
        ("mdl/man.mdl", Format::Mdl),
        ("mdl/alpha_test.mdl", Format::Mdl),
        ("mdl/chrome_sphere.mdl", Format::Mdl),
        ("smd/WusonSMD.smd", Format::Smd),
        ("smd/holy_grailref.smd", Format::Smd),
    ] {
        let path = dir.join(rel);
        let bytes = std::fs::read(&path).unwrap();
        let resolve = sinew_import::beside(&path);
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_function(rel, |b| {
            b.iter(|| {
                import_bytes(
                    format,
                    rel,
                    black_box(&bytes),
                    &resolve,
                    &ImportOptions::default(),
                )
                .unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
