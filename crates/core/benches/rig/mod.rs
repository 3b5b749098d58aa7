//! The 40-joint Biped rig and clips shared by the runtime benchmark and the instruction-count example
//! (`examples/frame_count.rs`), so both measure the same work.

#![allow(dead_code)] // each user takes what it needs

use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Clip, Curve, JointDesc, Skeleton, TrackCurves, Transform};

/// A 3ds Max Biped-like skeleton of 40 joints.
pub fn biped() -> Skeleton {
    let mut joints: Vec<(String, Option<String>, Vec3)> = Vec::new();
    let mut add = |name: &str, parent: Option<&str>, offset: Vec3| {
        joints.push((name.into(), parent.map(Into::into), offset));
    };
    add("Bip01", None, Vec3::new(0.0, 40.0, 0.0));
    add("Bip01 Pelvis", Some("Bip01"), Vec3::ZERO);
    add(
        "Bip01 Spine",
        Some("Bip01 Pelvis"),
        Vec3::new(0.0, 4.0, 0.0),
    );
    add(
        "Bip01 Spine1",
        Some("Bip01 Spine"),
        Vec3::new(0.0, 5.0, 0.0),
    );
    add(
        "Bip01 Spine2",
        Some("Bip01 Spine1"),
        Vec3::new(0.0, 5.0, 0.0),
    );
    add(
        "Bip01 Spine3",
        Some("Bip01 Spine2"),
        Vec3::new(0.0, 5.0, 0.0),
    );
    add("Bip01 Neck", Some("Bip01 Spine3"), Vec3::new(0.0, 6.0, 0.0));
    add("Bip01 Head", Some("Bip01 Neck"), Vec3::new(0.0, 3.0, 0.0));
    for (side, s) in [("L", 1.0f32), ("R", -1.0)] {
        let p = |n: &str| format!("Bip01 {side} {n}");
        add(
            &p("Clavicle"),
            Some("Bip01 Neck"),
            Vec3::new(s * 2.0, -1.0, 0.0),
        );
        add(
            &p("UpperArm"),
            Some(&p("Clavicle")),
            Vec3::new(s * 5.0, 0.0, 0.0),
        );
        add(
            &p("Forearm"),
            Some(&p("UpperArm")),
            Vec3::new(s * 10.0, 0.0, 0.0),
        );
        add(
            &p("Hand"),
            Some(&p("Forearm")),
            Vec3::new(s * 9.0, 0.0, 0.0),
        );
        for f in 0..3 {
            let base = p(&format!("Finger{f}"));
            add(
                &base,
                Some(&p("Hand")),
                Vec3::new(s * 3.0, 0.0, f as f32 - 1.0),
            );
            add(
                &format!("{base}1"),
                Some(&base),
                Vec3::new(s * 1.5, 0.0, 0.0),
            );
        }
    }
    for (side, s) in [("L", 1.0f32), ("R", -1.0)] {
        let p = |n: &str| format!("Bip01 {side} {n}");
        add(
            &p("Thigh"),
            Some("Bip01 Pelvis"),
            Vec3::new(s * 4.0, -2.0, 0.0),
        );
        add(&p("Calf"), Some(&p("Thigh")), Vec3::new(0.0, -17.0, 0.0));
        add(&p("Foot"), Some(&p("Calf")), Vec3::new(0.0, -17.0, 0.0));
        add(&p("Toe0"), Some(&p("Foot")), Vec3::new(0.0, -3.0, 4.0));
        add(&p("Toe01"), Some(&p("Toe0")), Vec3::new(0.0, 0.0, 1.5));
        add(&p("Toe02"), Some(&p("Toe01")), Vec3::new(0.0, 0.0, 1.0));
    }
    assert_eq!(joints.len(), 40);
    let descs = joints
        .into_iter()
        .map(|(name, parent, t)| JointDesc {
            name,
            parent,
            bind_local: Transform::from_translation(t),
            inverse_bind: None,
        })
        .collect();
    Skeleton::from_unordered(descs).unwrap().0
}

/// A looping 1 s clip at 30 Hz (30 keys) animating translation and rotation of every joint.
pub fn clip(name: &str, skeleton: &Skeleton, phase: f32) -> Clip {
    clip_with(name, skeleton, phase, true)
}

/// As [`clip`], but translation is animated on the root only (the other joints keep their bind
/// translation): how a Biped or motion-capture clip is usually keyed.
pub fn clip_rotations(name: &str, skeleton: &Skeleton, phase: f32) -> Clip {
    clip_with(name, skeleton, phase, false)
}

fn clip_with(name: &str, skeleton: &Skeleton, phase: f32, all_translations: bool) -> Clip {
    let times: Vec<f32> = (0..30).map(|k| k as f32 / 30.0).collect();
    let tracks = skeleton
        .names()
        .iter()
        .enumerate()
        .map(|(j, n)| {
            let bind = skeleton.bind_local()[j];
            let angle = |t: f32| (t * std::f32::consts::TAU + phase + j as f32).sin() * 0.4;
            TrackCurves {
                joint: n.clone(),
                translation: if all_translations || j == 0 {
                    Curve::new(
                        times.clone(),
                        times
                            .iter()
                            .map(|&t| bind.translation + Vec3::Y * angle(t) * 0.1)
                            .collect(),
                    )
                } else {
                    Curve::default()
                },
                rotation: Curve::new(
                    times.clone(),
                    times
                        .iter()
                        .map(|&t| Quat::from_rotation_x(angle(t)) * Quat::from_rotation_z(0.1))
                        .collect(),
                ),
                scale: Curve::default(),
            }
        })
        .collect();
    Clip::from_curves(name, 1.0, 30.0, true, false, tracks).unwrap()
}

pub fn upper_body_mask(skeleton: &Skeleton) -> Vec<f32> {
    let mut mask = vec![0.0; skeleton.len()];
    let spine = skeleton.find("Bip01 Spine").unwrap();
    for j in skeleton.subtree(spine) {
        mask[j as usize] = 1.0;
    }
    mask
}

/// xorshift32, for repeatable pseudo-random inputs.
/// The skinning benchmark's vertices: four influences each.
pub struct SkinInput {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub joints: Vec<[u16; 4]>,
    pub weights: Vec<[f32; 4]>,
}

/// `count` random vertices over `joints` joints, from a fixed seed; weights sum to one and the first
/// is never zero.
pub fn skin_input(joints: usize, count: usize) -> SkinInput {
    let mut rng = Rng(0x1234_5678);
    let mut input = SkinInput {
        positions: Vec::with_capacity(count),
        normals: Vec::with_capacity(count),
        joints: Vec::with_capacity(count),
        weights: Vec::with_capacity(count),
    };
    for _ in 0..count {
        input
            .positions
            .push(Vec3::new(rng.unit(), rng.unit(), rng.unit()) * 100.0 - 50.0);
        input
            .normals
            .push((Vec3::new(rng.unit(), rng.unit(), rng.unit()) - 0.5).normalize_or(Vec3::Y));
        let base = (rng.next() % joints as u32) as u16;
        input
            .joints
            .push([0, 1, 2, 3].map(|k| ((base as usize + k) % joints) as u16));
        let w = [rng.unit() + 0.1, rng.unit(), rng.unit(), rng.unit()];
        let s: f32 = w.iter().sum();
        input.weights.push(w.map(|x| x / s));
    }
    input
}

pub struct Rng(pub u32);
impl Rng {
    pub fn next(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        self.0
    }
    pub fn unit(&mut self) -> f32 {
        (self.next() >> 8) as f32 / (1u32 << 24) as f32
    }
}
