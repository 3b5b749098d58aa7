//! Bake throughput on CesiumMan (3273 vertices, 49 frames): skinning all frames, and encoding each
//! cache format. Run: `cargo bench -p sinew-pipeline --bench bake -- --warm-up-time 1 --measurement-time 3`.
#![allow(clippy::unwrap_used)]

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use sinew_core::format;
use sinew_pipeline::bake::{self, BakeRequest};
use sinew_pipeline::cache::vat::VatEncoding;
use sinew_pipeline::verify::{self, CacheFormat, CacheOptions, NormalsPlacement};

fn benches(c: &mut Criterion) {
    let Some(path) = sinew_testdata::corpus_file("gltf/CesiumMan.glb") else {
        return;
    };
    let scene = sinew_import::import_path(&path, &Default::default()).unwrap();
    let asset = format::read(&sinew_pipeline::compile::compile_to_bytes(&scene).unwrap()).unwrap();
    let req = BakeRequest::default();
    let baked = bake::bake(&asset, &req).unwrap();
    let vf = (baked.frames.vertex_count * baked.frames.frame_count) as u64;

    let mut g = c.benchmark_group("bake CesiumMan");
    g.throughput(Throughput::Elements(vf));
    g.bench_function("skin all frames (vertex-frames)", |b| {
        b.iter(|| bake::bake(&asset, &req).unwrap())
    });
    for (name, opts) in [
        (
            "pc2",
            CacheOptions {
                format: CacheFormat::Pc2,
                ..Default::default()
            },
        ),
        (
            "mdd",
            CacheOptions {
                format: CacheFormat::Mdd,
                ..Default::default()
            },
        ),
        ("exr offset-f16 + normals file", CacheOptions::default()),
        (
            "exr absolute-f32, no normals",
            CacheOptions {
                encoding: VatEncoding::AbsoluteF32,
                normals: NormalsPlacement::None,
                ..Default::default()
            },
        ),
    ] {
        let enc = verify::encode(&baked, &req, &opts, "m", "n").unwrap();
        let bytes = enc.cache.len() + enc.normals.as_ref().map_or(0, Vec::len);
        g.throughput(Throughput::Bytes(bytes as u64));
        g.bench_function(format!("encode {name} (bytes written)"), |b| {
            b.iter(|| verify::encode(&baked, &req, &opts, "m", "n").unwrap())
        });
    }
    g.finish();
}

criterion_group!(group, benches);
criterion_main!(group);
