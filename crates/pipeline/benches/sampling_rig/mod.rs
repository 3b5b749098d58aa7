//! The 40-joint skeleton and two clips shared by the clip_sampling benchmark and the
//! instruction-count example (`examples/sampling_count.rs`), so both measure the same work.

#![allow(clippy::unwrap_used)] // set-up on known-good data

use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Clip, Curve, JointDesc, Skeleton, TrackCurves, Transform};

/// 40 joints: a spine of 8, two arms and two legs of 8 joints each, about 72 units tall.
pub fn skeleton() -> Skeleton {
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
pub fn clip(name: &str, s: &Skeleton, phase: f32) -> Clip {
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
