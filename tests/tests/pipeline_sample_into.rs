//! Sampling and skinning into callers' buffers (`pose::matrices_into`, `pose::trs_into`,
//! `bake::skin_into`, what the Python package's `Asset.sample` and `Asset.skin` call) on corpus
//! characters: the bits of `pose::sample` (`inspect --pose`) and of `bake::bake`, local transforms
//! that compose into the model ones, and refusals that name what is wrong.
#![allow(clippy::unwrap_used)]

use sinew_core::format::{self, Asset};
use sinew_core::glam::Mat4;
use sinew_core::Clip;
use sinew_pipeline::bake::{self, BakeError, BakeRequest};
use sinew_pipeline::pose::{self, PoseRequest, PoseTimes, Space};
use std::sync::Arc;

/// Import -> compile -> write -> read: exactly what the runtime loads.
fn load(rel: &str) -> Option<Asset> {
    let path = sinew_testdata::corpus_file(rel)?;
    let scene = sinew_import::import_path(&path, &Default::default()).unwrap();
    let bytes = sinew_pipeline::compile::compile_to_bytes(&scene).unwrap();
    Some(format::read(&bytes).unwrap())
}

fn bake_times(clip: &Clip, fps: Option<f32>) -> Vec<f32> {
    let range = PoseTimes::Range {
        start: 0.0,
        end: clip.duration(),
        fps,
    };
    pose::times(clip, range).unwrap().0
}

/// A matrix from 16 floats written row by row.
fn from_rows(m: &[f32]) -> Mat4 {
    Mat4::from_cols_slice(m).transpose()
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn matrices_are_the_bits_of_inspect_pose_and_locals_compose_into_them() {
    for (rel, fps) in [
        ("gltf/CesiumMan.glb", Some(24.0)),
        ("gltf/Fox.glb", None),
        ("bvh/cmu_walk_crlf.bvh", None),
        ("mdl/man.mdl", Some(50.0)),
    ] {
        let Some(asset) = load(rel) else {
            return;
        };
        let skeleton = Arc::new(asset.skeleton.clone().unwrap());
        let n = skeleton.len();
        for c in &asset.clips {
            let times = bake_times(c, fps);
            let clip = Arc::new(c.clone());
            let mut model = vec![f32::NAN; times.len() * n * 16];
            pose::matrices_into(&skeleton, &clip, &times, Space::Model, &mut model).unwrap();
            let req = PoseRequest {
                clip: c.name().to_string(),
                times: PoseTimes::Range {
                    start: 0.0,
                    end: c.duration(),
                    fps,
                },
            };
            let poses = pose::sample(&asset, &req).unwrap();
            assert_eq!(poses.frames.len(), times.len());
            let (mut t, mut r, mut s) = (
                vec![0.0; times.len() * n * 3],
                vec![0.0; times.len() * n * 4],
                vec![0.0; times.len() * n * 3],
            );
            pose::trs_into(
                &skeleton,
                &clip,
                &times,
                Space::Model,
                &mut t,
                &mut r,
                &mut s,
            )
            .unwrap();
            for (f, frame) in poses.frames.iter().enumerate() {
                assert_eq!(frame.time.to_bits(), times[f].to_bits());
                for (j, p) in frame.joints.iter().enumerate() {
                    let k = (f * n + j) * 16;
                    let m = from_rows(&model[k..k + 16]);
                    assert_eq!(
                        bits(&m.to_cols_array()),
                        bits(&p.matrix.to_cols_array()),
                        "{rel} {} frame {f} joint {j}",
                        c.name()
                    );
                    let q = f * n + j;
                    assert_eq!(bits(&t[q * 3..q * 3 + 3]), bits(&p.translation.to_array()));
                    assert_eq!(bits(&r[q * 4..q * 4 + 4]), bits(&p.rotation.to_array()));
                    assert_eq!(bits(&s[q * 3..q * 3 + 3]), bits(&p.scale.to_array()));
                }
            }
            let mut local = vec![f32::NAN; model.len()];
            pose::matrices_into(&skeleton, &clip, &times, Space::Local, &mut local).unwrap();
            pose::trs_into(
                &skeleton,
                &clip,
                &times,
                Space::Local,
                &mut t,
                &mut r,
                &mut s,
            )
            .unwrap();
            for f in 0..times.len() {
                for j in 0..n {
                    let k = (f * n + j) * 16;
                    let l = from_rows(&local[k..k + 16]);
                    let m = from_rows(&model[k..k + 16]);
                    // The local translation is the local matrix's column 3.
                    let q = f * n + j;
                    assert_eq!(
                        bits(&t[q * 3..q * 3 + 3]),
                        bits(&l.w_axis.truncate().to_array())
                    );
                    match skeleton.parents()[j] {
                        // A root's local matrix is its model matrix: the same formulas.
                        None => assert_eq!(l, m, "{rel} root {j}"),
                        Some(p) => {
                            let k = (f * n + p as usize) * 16;
                            let composed = from_rows(&model[k..k + 16]) * l;
                            let scale = m.w_axis.truncate().length().max(1.0);
                            assert!(
                                composed.abs_diff_eq(m, 2e-5 * scale),
                                "{rel} {} frame {f} joint {j}",
                                c.name()
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn skinned_positions_are_the_bits_of_bake() {
    for (rel, fps) in [("gltf/CesiumMan.glb", Some(30.0)), ("mdl/man.mdl", None)] {
        let Some(asset) = load(rel) else {
            return;
        };
        let skeleton = Arc::new(asset.skeleton.clone().unwrap());
        for c in &asset.clips {
            let baked = bake::bake(
                &asset,
                &BakeRequest {
                    clips: vec![c.name().to_string()],
                    fps,
                    // Mesh 0 alone (the default is the model's body, two meshes of man.mdl).
                    meshes: vec![0],
                    ..BakeRequest::default()
                },
            )
            .unwrap();
            let times = bake_times(c, fps);
            assert_eq!(times.len(), baked.frames.frame_count);
            let nv = baked.frames.vertex_count;
            let mut out = vec![f32::NAN; times.len() * nv * 3];
            let clip = Arc::new(c.clone());
            bake::skin_into(&skeleton, &clip, &asset.meshes[0], 0, &times, &mut out).unwrap();
            let want: Vec<f32> = baked
                .frames
                .positions
                .iter()
                .flat_map(|p| p.to_array())
                .collect();
            assert_eq!(bits(&out), bits(&want), "{rel} {}", c.name());
        }
    }
}

#[test]
fn bad_times_buffers_and_meshes_are_refused() {
    let Some(asset) = load("mdl/man.mdl") else {
        return;
    };
    let skeleton = Arc::new(asset.skeleton.clone().unwrap());
    let walk = Arc::new(asset.clips[pose::find_clip(&asset, "walk").unwrap()].clone());
    let d = walk.duration();
    assert!(pose::check_times(&walk, &[0.0, d / 2.0, d]).is_ok());
    let e = pose::check_times(&walk, &[0.0, d + 0.01, -1.0]).unwrap_err();
    assert!(
        matches!(e, BakeError::TimeOutOfRange { index: 1, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("outside clip \"walk\""), "{e}");
    let e = pose::check_times(&walk, &[0.0, f32::NAN]).unwrap_err();
    assert!(
        matches!(e, BakeError::NonFiniteTime { index: 1, .. }),
        "{e}"
    );
    let e = pose::find_clip(&asset, "run").unwrap_err();
    assert!(e.to_string().contains("reference, walk"), "{e}");

    let n = skeleton.len();
    let mut short = vec![0.0; 2 * n * 16 - 1];
    let e =
        pose::matrices_into(&skeleton, &walk, &[0.0, 0.1], Space::Model, &mut short).unwrap_err();
    assert!(
        matches!(e, BakeError::BufferLength { expected, got, .. } if expected == 2 * n * 16 && got == expected - 1),
        "{e}"
    );
    let mut out = vec![0.0; n * 16];
    let e = pose::matrices_into(&skeleton, &walk, &[f32::INFINITY], Space::Local, &mut out)
        .unwrap_err();
    assert!(
        matches!(e, BakeError::NonFiniteTime { index: 0, .. }),
        "{e}"
    );
    // Outside the clip, the runtime's rule: a looping clip wraps around.
    let mut a = vec![0.0; n * 16];
    let mut b = vec![0.0; n * 16];
    pose::matrices_into(&skeleton, &walk, &[d * 0.25], Space::Model, &mut a).unwrap();
    pose::matrices_into(&skeleton, &walk, &[d * 1.25], Space::Model, &mut b).unwrap();
    assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-4));

    let mesh = &asset.meshes[0];
    let nv = mesh.lods[0].vertex_count();
    let e = bake::skin_into(&skeleton, &walk, mesh, 1, &[0.0], &mut vec![0.0; nv * 3]).unwrap_err();
    assert!(matches!(e, BakeError::NoLod { lod: 1, .. }), "{e}");
    let e = bake::skin_into(
        &skeleton,
        &walk,
        mesh,
        0,
        &[0.0],
        &mut vec![0.0; nv * 3 + 3],
    )
    .unwrap_err();
    assert!(matches!(e, BakeError::BufferLength { .. }), "{e}");
    let mut static_mesh = mesh.clone();
    static_mesh.lods[0].joints.clear();
    static_mesh.lods[0].weights.clear();
    let e = bake::skin_into(
        &skeleton,
        &walk,
        &static_mesh,
        0,
        &[0.0],
        &mut vec![0.0; nv * 3],
    )
    .unwrap_err();
    assert!(matches!(e, BakeError::NotSkinned(_)), "{e}");
}
