//! Prints the clip compression table of docs/performance.md: every animated clip of the corpus files
//! named below, compressed at the peers' settings (0.001 units at 0.1 units) or, with `--default`, at
//! sinew's default settings.
//!
//! `cargo run --release -p sinew-pipeline --example compression_table [-- --default]`

#![allow(clippy::unwrap_used)]

use sinew_pipeline::compile::compile;
use sinew_pipeline::compress::{compress_clip, CompressOptions};

fn main() {
    let default = std::env::args().any(|a| a == "--default");
    let options = if default {
        CompressOptions::default()
    } else {
        CompressOptions::peers()
    };
    println!("| file | clip | joints x keys | raw (B) | plain .sinew (B) | sinew (B) | ratio | max error | p99 error | B / joint / key | kept keys |");
    println!("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for file in [
        "gltf/CesiumMan.glb",
        "gltf/Fox.glb",
        "gltf/RiggedFigure.glb",
        "gltf/RiggedSimple.glb",
        "gltf/SimpleSkin.gltf",
        "gltf/magnum/animation.glb",
        "bvh/cmu_01_01.bvh",
        "bvh/cmu_walk_crlf.bvh",
        "bvh/pfnn_hierarchy_crlf.bvh",
    ] {
        let Some(path) = sinew_testdata::corpus_file(file) else {
            eprintln!("{file}: corpus not found");
            continue;
        };
        let scene = match sinew_import::import_path(&path, &Default::default()) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{file}: {e}");
                continue;
            }
        };
        let asset = compile(&scene).unwrap();
        for clip in &asset.clips {
            let (_, r) = compress_clip(clip, asset.skeleton.as_ref(), &options);
            println!(
                "| {file} | {} | {} x {} | {} | {} | {} | {:.1}:1 | {:.6} | {:.6} | {:.2} | {} |",
                r.clip,
                r.animated_joints,
                r.samples,
                r.raw_bytes,
                r.plain_bytes,
                r.compressed_bytes,
                r.ratio,
                r.max_error,
                r.p99_error,
                r.bytes_per_joint_sample,
                r.kept_keys
            );
        }
    }
}
