//! The animator's four-joint block path (sampling, blending and local-to-model on blocks) against the
//! per-joint functions (`Sampler::sample_layer` and `Sampler::sample`, `BlendBuffers`,
//! `apply_additive`, `local_to_model_and_palette`): the same bits, frame after frame, with masks,
//! partial and excess weights, cross-fades and additive layers.

#![allow(clippy::unwrap_used)] // helpers of tests

use sinew_core::glam::{Mat4, Quat, Vec3};
use sinew_core::{
    apply_additive, local_to_model_and_palette, Animator, BlendBuffers, Clip, ClipBinding, ClipId,
    Curve, JointDesc, Layer, Sampler, Skeleton, TrackCurves, Transform,
};
use std::sync::Arc;

/// xorshift32 in [-1, 1).
struct Rng(u32);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        (self.0 >> 8) as f32 / (1u32 << 23) as f32 - 1.0
    }
    fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
    fn quat(&mut self) -> Quat {
        Quat::from_xyzw(self.next(), self.next(), self.next(), self.next()).normalize()
    }
}

/// 14 joints in a random tree, with rotated, scaled bind poses.
fn skeleton(rng: &mut Rng) -> Skeleton {
    let joints = (0..14)
        .map(|i| JointDesc {
            name: format!("j{i}"),
            parent: (i > 0).then(|| format!("j{}", ((rng.next() + 1.0) * 0.5 * i as f32) as usize)),
            bind_local: Transform::new(rng.vec3(), rng.quat(), Vec3::ONE + rng.vec3() * 0.3),
            inverse_bind: None,
        })
        .collect();
    Skeleton::from_unordered(joints).unwrap().0
}

/// A clip over `joints` (some names unknown to the skeleton), with a mix of animated, constant and
/// missing channels and keys at uneven times.
fn clip(
    rng: &mut Rng,
    name: &str,
    joints: &[&str],
    looping: bool,
    additive: bool,
    pattern: usize,
) -> Arc<Clip> {
    let times: Vec<f32> = (0..9)
        .map(|k| k as f32 * 0.11 + (k % 3) as f32 * 0.01)
        .collect();
    let tracks = joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let mut t = TrackCurves {
                joint: (*j).into(),
                ..Default::default()
            };
            // Pattern 4: every track animates translation and rotation (whole blocks load by
            // transposition, and the last track's run ends the frame).
            let kind = if pattern % 5 == 4 {
                0
            } else {
                (i + pattern) % 4
            };
            match kind {
                0 => {
                    t.rotation =
                        Curve::new(times.clone(), times.iter().map(|_| rng.quat()).collect());
                    t.translation =
                        Curve::new(times.clone(), times.iter().map(|_| rng.vec3()).collect());
                }
                1 => {
                    t.rotation =
                        Curve::new(times.clone(), times.iter().map(|_| rng.quat()).collect());
                    t.scale = Curve::new(vec![0.0], vec![Vec3::splat(1.5)]);
                }
                2 => {
                    t.translation = Curve::new(vec![0.0], vec![rng.vec3()]);
                    t.scale = Curve::new(
                        times.clone(),
                        times.iter().map(|_| Vec3::ONE + rng.vec3() * 0.2).collect(),
                    );
                }
                _ => {
                    t.rotation = Curve::new(vec![0.0], vec![rng.quat()]);
                }
            }
            t
        })
        .collect();
    Arc::new(Clip::from_curves(name, 1.0, 9.0, looping, additive, tracks).unwrap())
}

fn bits(ts: &[Transform]) -> Vec<u32> {
    ts.iter()
        .flat_map(|t| {
            let mut v = t.translation.to_array().to_vec();
            v.extend(t.rotation.to_array());
            v.extend(t.scale.to_array());
            v
        })
        .map(f32::to_bits)
        .collect()
}

fn mat_bits(m: &[Mat4]) -> Vec<u32> {
    m.iter()
        .flat_map(|m| m.to_cols_array())
        .map(f32::to_bits)
        .collect()
}

/// What the animator should produce, from the per-joint functions and its public state.
fn reference(
    anim: &Animator,
    ids: &[ClipId],
    masks: &[Option<Vec<f32>>],
    samplers: &mut [Sampler],
) -> Vec<Transform> {
    let skeleton = anim.skeleton().clone();
    let n = skeleton.len();
    let mut poses = vec![skeleton.bind_local().to_vec(); ids.len()];
    let mut buffers = BlendBuffers::new(n);
    let mut out = vec![Transform::IDENTITY; n];
    buffers.reset();
    let mut additive = Vec::new();
    for (k, &id) in ids.iter().enumerate() {
        let clip = anim.clip(id).unwrap();
        let w = anim.effective_weight(id).unwrap();
        if !anim.is_active(id).unwrap() || w.is_nan() || w <= 0.0 {
            continue;
        }
        let binding = ClipBinding::new(clip, &skeleton);
        let t = anim.time(id).unwrap();
        // Normal layers enter the blend with their rotations as interpolated; additive layers as
        // sampled (normalised).
        if clip.additive() {
            samplers[k].sample(clip, &binding, &skeleton, t, &mut poses[k])
        } else {
            samplers[k].sample_layer(clip, &binding, &skeleton, t, &mut poses[k])
        }
        .unwrap();
        if clip.additive() {
            additive.push((k, binding, w));
            continue;
        }
        let mut layer = Layer::new(&poses[k], binding.driven()).with_weight(w);
        if let Some(m) = &masks[k] {
            layer = layer.with_mask(m);
        }
        buffers.accumulate(&layer).unwrap();
    }
    buffers.resolve(skeleton.bind_local(), &mut out).unwrap();
    for (k, binding, w) in &additive {
        let mut layer = Layer::new(&poses[*k], binding.driven()).with_weight(*w);
        if let Some(m) = &masks[*k] {
            layer = layer.with_mask(m);
        }
        apply_additive(&mut out, &layer).unwrap();
    }
    out
}

#[test]
fn block_path_matches_the_per_joint_functions_bit_for_bit() {
    for seed in [1u32, 0xdead_beef, 0x1234_5678, 6, 7, 4, 9] {
        let mut rng = Rng(seed);
        let skeleton = Arc::new(skeleton(&mut rng));
        let names: Vec<String> = skeleton.names().to_vec();
        let all: Vec<&str> = names.iter().map(String::as_str).collect();
        let upper: Vec<&str> = all[5..].iter().copied().chain(["not-a-joint"]).collect();
        // The channel patterns rotate so that every kind of track ends a frame somewhere.
        let p = seed as usize % 5;
        let walk = clip(&mut rng, "walk", &all, true, false, p);
        let run = clip(&mut rng, "run", &all[1..], false, false, p + 1);
        let wave = clip(&mut rng, "wave", &upper, true, false, p + 2);
        let lean = clip(&mut rng, "lean", &all[2..9], true, true, p + 3);
        let mut anim = Animator::new(skeleton.clone());
        let ids = [
            anim.add_clip(walk),
            anim.add_clip(run),
            anim.add_clip(wave),
            anim.add_clip(lean),
        ];
        let n = skeleton.len();
        // Fractional, zero and above-one mask values.
        let wave_mask: Vec<f32> = (0..n).map(|j| [0.0, 0.3, 1.0, 0.7, 1.6][j % 5]).collect();
        let lean_mask: Vec<f32> = (0..n).map(|j| if j % 3 == 0 { 0.0 } else { 0.5 }).collect();
        let masks = [None, None, Some(wave_mask.clone()), Some(lean_mask.clone())];
        anim.set_mask(ids[2], Some(wave_mask)).unwrap();
        anim.set_mask(ids[3], Some(lean_mask)).unwrap();
        anim.play(ids[0]).unwrap();
        anim.enqueue(ids[1], 0.4).unwrap();
        anim.fade_to(ids[2], 0.8, 0.3).unwrap();
        anim.activate(ids[3]).unwrap();
        anim.set_weight(ids[3], 0.6).unwrap();
        anim.set_weight(ids[0], 0.45).unwrap();
        let mut samplers = vec![Sampler::new(); ids.len()];
        let mut got = vec![Transform::IDENTITY; n];
        let (mut models, mut palette) = (vec![Mat4::ZERO; n], vec![Mat4::ZERO; n]);
        let (mut want_models, mut want_palette) = (vec![Mat4::ZERO; n], vec![Mat4::ZERO; n]);
        for frame in 0..150 {
            anim.update(1.0 / 47.0);
            if frame == 60 {
                anim.deactivate(ids[3]).unwrap();
            }
            if frame == 90 {
                anim.set_weight(ids[1], 1.7).unwrap();
            }
            let want = reference(&anim, &ids, &masks, &mut samplers);
            anim.evaluate(&mut got).unwrap();
            assert_eq!(bits(&got), bits(&want), "seed {seed} frame {frame}");
            anim.evaluate_palette(&mut models, &mut palette).unwrap();
            local_to_model_and_palette(
                skeleton.parents(),
                &want,
                skeleton.inverse_bind(),
                &mut want_models,
                &mut want_palette,
            )
            .unwrap();
            assert_eq!(mat_bits(&models), mat_bits(&want_models), "frame {frame}");
            assert_eq!(mat_bits(&palette), mat_bits(&want_palette), "frame {frame}");
        }
    }
}
