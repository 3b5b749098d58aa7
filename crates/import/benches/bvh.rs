//! BVH import throughput (MB/s) on corpus files.
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use sinew_import::{bvh, ImportOptions};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("bvh_import");
    g.sample_size(10);
    for rel in [
        "bvh/cmu_01_01.bvh",
        "bvh/Boxing_Toes.bvh",
        "bvh/cmu_walk_crlf.bvh",
    ] {
        let Some(bytes) = sinew_testdata::read_corpus(rel) else {
            return;
        };
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_function(rel, |b| {
            b.iter(|| {
                bvh::import(
                    rel,
                    black_box(&bytes),
                    &|_| Err(std::io::Error::other("no")),
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
