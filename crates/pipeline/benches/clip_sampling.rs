//! Sampling a compressed clip vs the same clip as plain f32 keys, on a 40-joint skeleton (two clips per
//! iteration, as in sinew-core's `runtime` bench), and the core benchmark's animator frame (two masked
//! layers, local-to-model and palette) with either. Lives in sinew-pipeline because the encoder does.
//! Figures are in docs/performance.md ("Clip compression").
//!
//! `cargo bench -p sinew-pipeline --bench clip_sampling -- --warm-up-time 1 --measurement-time 3`

#![allow(clippy::unwrap_used)] // benchmark set-up on known-good data

use criterion::{criterion_group, criterion_main, Criterion};
mod sampling_rig;

use sampling_rig::{clip, skeleton};
use sinew_core::glam::Mat4;
use sinew_core::{Animator, ClipBinding, Sampler, Transform};
use sinew_pipeline::compress::{compress_clip, CompressOptions};
use std::hint::black_box;
use std::sync::Arc;

fn sampling(c: &mut Criterion) {
    let s = skeleton();
    let plain = [clip("a", &s, 0.0), clip("b", &s, 1.0)];
    let compressed = plain.clone().map(|p| {
        let (c, r) = compress_clip(&p, Some(&s), &CompressOptions::default());
        eprintln!(
            "{}: {} -> {} bytes, max error {}",
            r.clip, r.plain_bytes, r.compressed_bytes, r.max_error
        );
        assert!(c.is_compressed());
        c
    });
    let mut g = c.benchmark_group("clip_sampling");
    // The last row runs the portable decode (no AVX2), as on a CPU without it.
    for (label, clips, baseline_only) in [
        ("plain_two_clips_40_joints", &plain, false),
        ("compressed_two_clips_40_joints", &compressed, false),
        ("compressed_two_clips_40_joints_baseline", &compressed, true),
    ] {
        sinew_core::set_baseline_only(baseline_only);
        let bindings = clips.clone().map(|c| ClipBinding::new(&c, &s));
        let mut samplers = [Sampler::new(), Sampler::new()];
        let mut out = vec![Transform::IDENTITY; s.len()];
        let mut t = 0.0f32;
        g.bench_function(label, |b| {
            b.iter(|| {
                t = (t + 1.0 / 60.0) % 1.0;
                for i in 0..2 {
                    samplers[i]
                        .sample(&clips[i], &bindings[i], &s, black_box(t), &mut out)
                        .unwrap();
                }
                black_box(&out);
            })
        });
        sinew_core::set_baseline_only(false);
    }
    // The core benchmark's frame on this rig: the two clips in an animator, one on the spine and
    // arms, the other on the legs (complementary masks), then local-to-model and the palette.
    let n = s.len();
    let upper: Vec<f32> = (0..n)
        .map(|j| {
            if s.names()[j].starts_with("l2") || s.names()[j].starts_with("l3") {
                0.0
            } else {
                1.0
            }
        })
        .collect();
    let lower: Vec<f32> = upper.iter().map(|m| 1.0 - m).collect();
    for (label, clips) in [
        ("plain_animator_frame_40_joints", &plain),
        ("compressed_animator_frame_40_joints", &compressed),
    ] {
        let mut anim = Animator::new(Arc::new(s.clone()));
        let a = anim.add_clip(Arc::new(clips[0].with_looping(true)));
        let b = anim.add_clip(Arc::new(clips[1].with_looping(true)));
        anim.set_mask(a, Some(upper.clone())).unwrap();
        anim.set_mask(b, Some(lower.clone())).unwrap();
        anim.play(a).unwrap();
        anim.activate(b).unwrap();
        let mut models = vec![Mat4::IDENTITY; n];
        let mut palette = vec![Mat4::IDENTITY; n];
        g.bench_function(label, |bench| {
            bench.iter(|| {
                anim.update(black_box(1.0 / 60.0));
                anim.evaluate_palette(&mut models, &mut palette).unwrap();
                black_box(&palette);
            })
        });
    }
    g.finish();
}

criterion_group!(benches, sampling);
criterion_main!(benches);
