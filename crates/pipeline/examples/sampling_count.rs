//! The clip_sampling benchmark's two 40-joint clips, sampled a fixed number of times at 60 Hz as plain
//! f32 keys or compressed, for instruction counts under `valgrind --tool=callgrind` (repeatable on a
//! shared machine). Figures are in docs/performance.md ("Clip compression").
//!
//! `cargo build --release -p sinew-pipeline --example sampling_count`, then
//! `valgrind --tool=callgrind target/release/examples/sampling_count plain|compressed|none [FRAMES]`.

#![allow(clippy::unwrap_used)] // set-up on known-good data

use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Clip, ClipBinding, Curve, JointDesc, Sampler, Skeleton, TrackCurves, Transform};
use sinew_pipeline::compress::{compress_clip, CompressOptions};
use std::hint::black_box;

/// 40 joints: a spine of 8, two arms and two legs of 8 joints each, about 72 units tall.
fn skeleton() -> Skeleton {
    let mut joints = Vec::new();
    let mut add = |name: String, parent: Option<String>, t: Vec3| {
        joints.push(JointDesc {
            name,
            parent,
            bind_local: Transform::from_translation(t),
            inverse_bind: None,
        })
    };
    add("j0".into(), None, Vec3::new(0.0, 40.0, 0.0));
    for i in 1..8 {
        add(format!("j{i}"), Some(format!("j{}", i - 1)), Vec3::Y * 4.0);
    }
    for (limb, (parent, dir)) in [
        ("j7", Vec3::X),
        ("j7", -Vec3::X),
        ("j0", -Vec3::Y),
        ("j0", -Vec3::Y),
    ]
    .into_iter()
    .enumerate()
    {
        for i in 0..8 {
            let p = if i == 0 {
                parent.to_string()
            } else {
                format!("l{limb}_{}", i - 1)
            };
            add(
                format!("l{limb}_{i}"),
                Some(p),
                dir * 4.0 + Vec3::X * limb as f32 * 0.1,
            );
        }
    }
    Skeleton::from_unordered(joints).unwrap().0
}

/// A 1 s clip at 30 Hz animating the translation and rotation of every joint.
fn clip(name: &str, s: &Skeleton, phase: f32) -> Clip {
    let times: Vec<f32> = (0..31).map(|k| k as f32 / 30.0).collect();
    let tracks = s
        .names()
        .iter()
        .enumerate()
        .map(|(j, n)| {
            let bind = s.bind_local()[j];
            let angle = |t: f32| (t * std::f32::consts::TAU + phase + j as f32).sin() * 0.4;
            TrackCurves {
                joint: n.clone(),
                translation: Curve::new(
                    times.clone(),
                    times
                        .iter()
                        .map(|&t| bind.translation + Vec3::splat(angle(t) * 0.5))
                        .collect(),
                ),
                rotation: Curve::new(
                    times.clone(),
                    times
                        .iter()
                        .map(|&t| {
                            Quat::from_rotation_z(angle(t)) * Quat::from_rotation_x(angle(t + 0.3))
                        })
                        .collect(),
                ),
                ..Default::default()
            }
        })
        .collect();
    Clip::from_curves(name, 1.0, 30.0, false, false, tracks).unwrap()
}

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
