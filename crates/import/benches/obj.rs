//! OBJ import throughput (MB/s) on corpus files.
#![allow(missing_docs, clippy::unwrap_used)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use sinew_import::{obj, ImportOptions};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("obj_import");
    for rel in ["obj/spot.obj", "obj/regr01.obj", "obj/spider.obj"] {
        let Some(bytes) = sinew_testdata::read_corpus(rel) else {
            return;
        };
        let dir = sinew_testdata::corpus().unwrap().join("obj");
        let resolve = move |name: &str| std::fs::read(dir.join(name));
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_function(rel, |b| {
            b.iter(|| {
                obj::import(rel, black_box(&bytes), &resolve, &ImportOptions::default()).unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
