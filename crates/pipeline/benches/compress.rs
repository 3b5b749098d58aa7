//! The clip encoder on one thread, per clip, at the peers' setting (0.001 units at 0.1 units) and
//! each effort: the committed biped fixture's walk (no corpus needed) and, when the corpus is there,
//! CesiumMan, Fox's Walk, ninja and the CMU walk. Run: `cargo bench -p sinew-pipeline --bench
//! compress -- --warm-up-time 1 --measurement-time 5`. docs/performance.md compares these clips with
//! ACL's compressor in whole-process runs (`examples/compress_time.rs`).
#![allow(clippy::unwrap_used)]

use criterion::{criterion_group, criterion_main, Criterion};
use sinew_pipeline::compile::compile;
use sinew_pipeline::compress::{compress_clip, CompressOptions, Effort};
use std::path::PathBuf;

fn benches(c: &mut Criterion) {
    let fixture = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/biped.gltf");
    let mut inputs = vec![("biped", fixture, "walk")];
    for (label, file, clip) in [
        ("CesiumMan", "gltf/CesiumMan.glb", "animation0"),
        ("Fox", "gltf/Fox.glb", "Walk"),
        ("ninja", "ms3d/ninja.ms3d", "ninja"),
        ("cmu_walk", "bvh/cmu_walk_crlf.bvh", "cmu_walk_crlf"),
    ] {
        if let Some(p) = sinew_testdata::corpus_file(file).filter(|p| p.exists()) {
            inputs.push((label, p, clip));
        }
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut g = c.benchmark_group("compress one clip, one thread, 0.001 @ 0.1");
    g.sample_size(10);
    for (label, path, name) in inputs {
        let scene = sinew_import::import_path(&path, &Default::default()).unwrap();
        let asset = compile(&scene).unwrap();
        let clip = asset.clips.iter().find(|c| c.name() == name).unwrap();
        for effort in [Effort::Fast, Effort::Default] {
            let options = CompressOptions {
                effort,
                ..CompressOptions::peers()
            };
            g.bench_function(format!("{label} {name} ({effort:?})"), |b| {
                b.iter(|| pool.install(|| compress_clip(clip, asset.skeleton.as_ref(), &options)))
            });
        }
    }
    g.finish();
}

criterion_group!(group, benches);
criterion_main!(group);
