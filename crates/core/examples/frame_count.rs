//! Runs one step of the runtime benchmark's character frame (40-joint Biped, two clips, masks) a fixed
//! number of times, for instruction counts under `valgrind --tool=callgrind`, which are repeatable on a
//! shared machine where timings are not. Figures are in docs/performance.md.
//!
//! `cargo build --release -p sinew-core --example frame_count`, then
//! `valgrind --tool=callgrind target/release/examples/frame_count STEP [ITERATIONS]` with STEP one of
//! `frame`, `sample`, `blend`, `palette`, `skin`, `none` (set-up only, to subtract).

#![allow(clippy::unwrap_used)] // set-up on known-good data

#[path = "../benches/rig/mod.rs"]
mod rig;

use sinew_core::glam::{Mat4, Vec3};
use sinew_core::{
    local_to_model_and_palette, skin, Animator, BlendBuffers, ClipBinding, Layer, Sampler,
    Transform,
};
use std::hint::black_box;
use std::sync::Arc;

fn main() {
    let mut args = std::env::args().skip(1);
    let step = args.next().unwrap_or_else(|| "frame".into());
    let iterations: usize = args.next().map_or(10_000, |a| a.parse().unwrap());
    let skeleton = Arc::new(rig::biped());
    let n = skeleton.len();
    let walk = Arc::new(rig::clip("walk", &skeleton, 0.0));
    let wave = Arc::new(rig::clip("wave", &skeleton, 1.0));
    let upper = rig::upper_body_mask(&skeleton);
    let lower: Vec<f32> = upper.iter().map(|m| 1.0 - m).collect();
    let mut anim = Animator::new(skeleton.clone());
    let a = anim.add_clip(walk.clone());
    let b = anim.add_clip(wave.clone());
    anim.set_mask(a, Some(lower.clone())).unwrap();
    anim.set_mask(b, Some(upper.clone())).unwrap();
    anim.play(a).unwrap();
    anim.activate(b).unwrap();
    let mut locals = vec![Transform::IDENTITY; n];
    let mut models = vec![Mat4::IDENTITY; n];
    let mut palette = vec![Mat4::IDENTITY; n];
    let bind_a = ClipBinding::new(&walk, &skeleton);
    let bind_b = ClipBinding::new(&wave, &skeleton);
    let (mut sa, mut sb) = (Sampler::new(), Sampler::new());
    let mut pose_a = skeleton.bind_local().to_vec();
    let mut pose_b = skeleton.bind_local().to_vec();
    let mut buffers = BlendBuffers::new(n);
    anim.evaluate(&mut locals).unwrap();

    // 10 000 vertices for the skinning step.
    let vertices = 10_000;
    let rig::SkinInput {
        positions,
        normals,
        joints,
        weights,
    } = rig::skin_input(n, vertices);
    let mut out_p = vec![Vec3::ZERO; vertices];
    let mut out_n = vec![Vec3::ZERO; vertices];
    local_to_model_and_palette(
        skeleton.parents(),
        &locals,
        skeleton.inverse_bind(),
        &mut models,
        &mut palette,
    )
    .unwrap();

    let mut t = 0.0f32;
    for _ in 0..iterations {
        match step.as_str() {
            "frame" => {
                anim.update(black_box(1.0 / 60.0));
                anim.evaluate_palette(&mut models, &mut palette).unwrap();
            }
            "sample" => {
                t += 1.0 / 60.0;
                sa.sample(&walk, &bind_a, &skeleton, t, &mut pose_a)
                    .unwrap();
                sb.sample(&wave, &bind_b, &skeleton, t, &mut pose_b)
                    .unwrap();
            }
            "blend" => buffers
                .blend(
                    skeleton.bind_local(),
                    &[
                        Layer::new(&pose_a, bind_a.driven()).with_mask(&lower),
                        Layer::new(&pose_b, bind_b.driven()).with_mask(&upper),
                    ],
                    &[],
                    &mut locals,
                )
                .unwrap(),
            "palette" => local_to_model_and_palette(
                skeleton.parents(),
                black_box(&locals),
                skeleton.inverse_bind(),
                &mut models,
                &mut palette,
            )
            .unwrap(),
            "skin" => skin(
                &palette, &positions, &normals, &joints, &weights, &mut out_p, &mut out_n,
            )
            .unwrap(),
            _ => {}
        }
        black_box((&locals, &palette, &pose_a, &pose_b, &out_p));
    }
}
