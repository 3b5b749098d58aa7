//! Import speed of the glTF importer on CesiumMan and Fox from the shared corpus.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use sinew_import::{gltf, ImportOptions};

fn no_resolve(_: &str) -> std::io::Result<Vec<u8>> {
    Err(std::io::Error::other("no external files"))
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("gltf_import");
    for name in ["CesiumMan.glb", "Fox.glb"] {
        let Some(bytes) = sinew_testdata::read_corpus(&format!("gltf/{name}")) else {
            return;
        };
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_function(name, |b| {
            b.iter(|| {
                gltf::import(name, &bytes, &no_resolve, &ImportOptions::default())
                    .map(|s| s.meshes.len())
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
