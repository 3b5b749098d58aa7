//! MS3D import throughput (MB/s) on corpus files: `cargo bench -p sinew-import --bench ms3d`.
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use sinew_import::{ms3d, ImportOptions};

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("ms3d_import");
    for file in ["ninja.ms3d", "Wuson.ms3d", "cross.ms3d"] {
        let Some(bytes) = sinew_testdata::read_corpus(&format!("ms3d/{file}")) else {
            return;
        };
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_function(file, |b| {
            b.iter(|| {
                ms3d::import(file, &bytes, &|_| unreachable!(), &ImportOptions::default()).unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
