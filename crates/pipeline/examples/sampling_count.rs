//! The clip_sampling benchmark's two 40-joint clips, sampled a fixed number of times at 60 Hz as plain
//! f32 keys or compressed, for instruction counts under `valgrind --tool=callgrind` (repeatable on a
//! shared machine). Figures are in docs/performance.md ("Clip compression").
//!
//! `cargo build --release -p sinew-pipeline --example sampling_count`, then
//! `valgrind --tool=callgrind target/release/examples/sampling_count plain|compressed|none [FRAMES]`.

#![allow(clippy::unwrap_used)] // set-up on known-good data

#[path = "../benches/sampling_rig/mod.rs"]
mod sampling_rig;

use sampling_rig::{clip, skeleton};
use sinew_core::{ClipBinding, Sampler, Transform};
use sinew_pipeline::compress::{compress_clip, CompressOptions};
use std::hint::black_box;

fn main() {
    let mut args = std::env::args().skip(1);
    let which = args.next().unwrap_or_else(|| "plain".into());
    let frames: usize = args.next().map_or(10_000, |a| a.parse().unwrap());
    let s = skeleton();
    let plain = [clip("a", &s, 0.0), clip("b", &s, 1.0)];
    let compressed = plain
        .clone()
        .map(|p| compress_clip(&p, Some(&s), &CompressOptions::default()).0);
    let clips = if which == "compressed" {
        &compressed
    } else {
        &plain
    };
    let bindings = clips.clone().map(|c| ClipBinding::new(&c, &s));
    let mut samplers = [Sampler::new(), Sampler::new()];
    let mut out = vec![Transform::IDENTITY; s.len()];
    let mut t = 0.0f32;
    if which != "none" {
        for _ in 0..frames {
            t = (t + 1.0 / 60.0) % 1.0;
            for i in 0..2 {
                samplers[i]
                    .sample(&clips[i], &bindings[i], &s, black_box(t), &mut out)
                    .unwrap();
            }
            black_box(&out);
        }
    }
}
