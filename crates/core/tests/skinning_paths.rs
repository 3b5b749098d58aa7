//! Skinning's AVX kernel (two vertices per register) against the portable per-vertex code, and the
//! `BlendedMatrix` normals against an independent reference.
//!
//! The AVX path must give the same bits as the portable one (which is what runs on CPUs without
//! AVX) for every vertex count (pairs, an odd last vertex), for zero, mirrored and degenerate
//! normals, and on a bad joint index (the same error, the same vertices written before it).

#![allow(clippy::unwrap_used)]

use sinew_core::glam::{Mat4, Quat, Vec3, Vec4};
use sinew_core::{set_baseline_only, skin, skin_with, NormalTransform, SkinError};

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
}

struct Input {
    palette: Vec<Mat4>,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    joints: Vec<[u16; 4]>,
    weights: Vec<[f32; 4]>,
}

fn input(rng: &mut Rng, vertices: usize) -> Input {
    let mut palette: Vec<Mat4> = (0..9)
        .map(|_| {
            Mat4::from_scale_rotation_translation(
                Vec3::ONE + rng.vec3() * 0.6,
                Quat::from_xyzw(rng.next(), rng.next(), rng.next(), rng.next()).normalize(),
                rng.vec3() * 20.0,
            )
        })
        .collect();
    // A mirror, a degenerate (flat) matrix and a zero matrix.
    palette.push(Mat4::from_scale(Vec3::new(-1.0, 2.0, 0.5)));
    palette.push(Mat4::from_scale(Vec3::new(1.0, 1.0, 0.0)));
    palette.push(Mat4::ZERO);
    let joint = |rng: &mut Rng| ((rng.next() + 1.0) * 0.5 * palette.len() as f32) as u16 % 12;
    let mut rng2 = Rng(rng.0 ^ 0x55aa);
    let joints = (0..vertices)
        .map(|_| [0; 4].map(|_| joint(&mut rng2)))
        .collect();
    Input {
        positions: (0..vertices).map(|_| rng.vec3() * 50.0).collect(),
        normals: (0..vertices)
            .map(|v| {
                if v % 5 == 3 {
                    Vec3::ZERO
                } else {
                    rng.vec3().normalize_or(Vec3::Y)
                }
            })
            .collect(),
        joints,
        weights: (0..vertices)
            .map(|v| {
                let w = [0; 4].map(|_| (rng.next() + 1.0) * 0.5);
                if v % 7 == 2 {
                    [1.0, 0.0, 0.0, 0.0]
                } else {
                    w
                }
            })
            .collect(),
        palette,
    }
}

type Run = (Result<(), SkinError>, Vec<u32>, Vec<u32>);

fn run(i: &Input, mode: NormalTransform, with_normals: bool, baseline: bool) -> Run {
    let n = i.positions.len();
    let mut p = vec![Vec3::splat(7.0); n];
    let mut nn = vec![Vec3::splat(7.0); if with_normals { n } else { 0 }];
    set_baseline_only(baseline);
    let r = skin_with(
        mode,
        &i.palette,
        &i.positions,
        if with_normals { &i.normals } else { &[] },
        &i.joints,
        &i.weights,
        &mut p,
        &mut nn,
    );
    set_baseline_only(false);
    let bits = |v: &[Vec3]| -> Vec<u32> {
        v.iter()
            .flat_map(|v| v.to_array())
            .map(f32::to_bits)
            .collect()
    };
    (r, bits(&p), bits(&nn))
}

// One test: `set_baseline_only` is process-wide.
#[test]
fn avx_and_portable_skinning_give_the_same_bits() {
    let mut rng = Rng(0x2545_f491);
    for vertices in (0..12).chain([301, 1000]) {
        let mut i = input(&mut rng, vertices);
        for mode in [NormalTransform::Cofactor, NormalTransform::BlendedMatrix] {
            for with_normals in [true, false] {
                let fast = run(&i, mode, with_normals, false);
                assert_eq!(
                    fast,
                    run(&i, mode, with_normals, true),
                    "{vertices} {mode:?}"
                );
                assert_eq!(fast.0, Ok(()));
            }
        }
        // A bad joint index at every position of a short mesh, and in the middle of a long one.
        let bad: Vec<usize> = if vertices < 12 {
            (0..vertices).collect()
        } else {
            vec![0, 1, 150, vertices - 2, vertices - 1]
        };
        for v in bad {
            let keep = i.joints[v];
            i.joints[v][v % 4] = 12;
            for mode in [NormalTransform::Cofactor, NormalTransform::BlendedMatrix] {
                let fast = run(&i, mode, true, false);
                assert_eq!(fast, run(&i, mode, true, true), "{vertices} bad at {v}");
                assert_eq!(
                    fast.0,
                    Err(SkinError::JointIndex {
                        vertex: v,
                        joint: 12,
                        palette: 12
                    })
                );
                // Every vertex before the bad one is written.
                assert!(fast.1[..3 * v].iter().all(|&b| b != 7f32.to_bits()));
            }
            i.joints[v] = keep;
        }
    }
}

#[test]
fn blended_matrix_normals_are_the_blended_matrix_times_the_normal() {
    let mut rng = Rng(0x1234_5679);
    let i = input(&mut rng, 257);
    let n = i.positions.len();
    let (mut p, mut nn) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
    skin_with(
        NormalTransform::BlendedMatrix,
        &i.palette,
        &i.positions,
        &i.normals,
        &i.joints,
        &i.weights,
        &mut p,
        &mut nn,
    )
    .unwrap();
    let (mut p_cof, mut n_cof) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
    skin(
        &i.palette,
        &i.positions,
        &i.normals,
        &i.joints,
        &i.weights,
        &mut p_cof,
        &mut n_cof,
    )
    .unwrap();
    // Positions do not depend on the normal treatment.
    assert_eq!(p, p_cof);
    for v in 0..n {
        // Reference: the blended matrix summed with glam's Mat4 arithmetic, applied to the normal.
        let m = (0..4).fold(Mat4::ZERO, |m, k| {
            m + i.palette[i.joints[v][k] as usize] * i.weights[v][k]
        });
        let want = m.transform_vector3(i.normals[v]);
        let err = (nn[v] - want).length();
        assert!(
            err <= 1e-5 * (1.0 + want.length()),
            "{v}: {} vs {want}",
            nn[v]
        );
        // Rigid and uniformly scaled palettes give the cofactor's direction; here (non-uniform
        // scales) the two differ, but both are finite.
        assert!(nn[v].is_finite() && Vec4::from((n_cof[v], 0.0)).is_finite());
    }
}
