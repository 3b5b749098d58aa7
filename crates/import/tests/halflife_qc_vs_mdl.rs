//! A QC compiled by sinew against the MDL studiomdl compiled from it: same skeleton, meshes and clips.
//!
//! The corpus holds the compiled models (`mdl/*.mdl`) but not their sources, which are published
//! separately (GPL-3.0, github.com/malortie/assimp-hl1-mdl-importer-tests-sources, `models/`). Point
//! `SINEW_HL_SOURCES` at a checkout's `models` folder to run this comparison; without it the test says
//! so and passes, under CI too (the sources are not part of the shared corpus).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use sinew_core::glam::Quat;
use sinew_import::{import_path, ImportOptions};
use sinew_scene::Scene;
use std::path::PathBuf;

fn sources() -> Option<PathBuf> {
    let dir = PathBuf::from(std::env::var_os("SINEW_HL_SOURCES")?);
    dir.is_dir().then_some(dir)
}

struct Figures {
    bind: f32,
    position: f32,
    normal_deg: f32,
    uv: f32,
    pose_t: f32,
    pose_deg: f32,
}

/// The angle between two rotations in degrees, from the chord between the quaternions (exact near
/// zero, where `acos` of the dot product is not).
fn angle_deg(a: Quat, b: Quat) -> f32 {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    (4.0 * ((a - b).length() / 2.0).min(1.0).asin()).to_degrees()
}

fn compare(qc: &Scene, mdl: &Scene) -> Figures {
    let (sq, sm) = (
        qc.skeleton.as_ref().unwrap(),
        mdl.skeleton.as_ref().unwrap(),
    );
    assert_eq!(sq.names(), sm.names());
    assert_eq!(sq.parents(), sm.parents());
    let mut bind = 0f32;
    for (a, b) in sq.bind_local().iter().zip(sm.bind_local()) {
        bind = bind.max((a.translation - b.translation).length());
        bind = bind.max(angle_deg(a.rotation, b.rotation));
    }
    assert_eq!(qc.meshes.len(), mdl.meshes.len());
    let (mut position, mut normal, mut uv) = (0f32, 0f32, 0f32);
    for (a, b) in qc.meshes.iter().zip(&mdl.meshes) {
        assert_eq!(a.name, b.name);
        let (ga, gb) = (&a.geometry, &b.geometry);
        assert_eq!(ga.indices.len(), gb.indices.len(), "{}", a.name);
        assert_eq!(ga.positions.len(), gb.positions.len(), "{}", a.name);
        // Triangles are matched by their corner positions (strips reorder them).
        let tri = |g: &sinew_core::Lod, t: usize| -> [usize; 3] {
            [0, 1, 2].map(|k| g.indices[3 * t + k] as usize)
        };
        for t in 0..ga.indices.len() / 3 {
            let ca = tri(ga, t);
            let best = (0..gb.indices.len() / 3)
                .flat_map(|u| (0..3).map(move |r| (u, r)))
                .map(|(u, r)| {
                    let cb = tri(gb, u);
                    let d = (0..3)
                        .map(|k| (ga.positions[ca[k]] - gb.positions[cb[(k + r) % 3]]).length())
                        .fold(0f32, f32::max);
                    (d, u, r)
                })
                .min_by(|x, y| x.0.total_cmp(&y.0))
                .unwrap();
            position = position.max(best.0);
            let cb = tri(gb, best.1);
            for k in 0..3 {
                let (i, j) = (ca[k], cb[(k + best.2) % 3]);
                normal = normal.max(
                    (2.0 * ((ga.normals[i] - gb.normals[j]).length() / 2.0)
                        .min(1.0)
                        .asin())
                    .to_degrees(),
                );
                uv = uv.max((ga.uvs[i] - gb.uvs[j]).abs().max_element());
            }
        }
    }
    assert_eq!(
        qc.clips.iter().map(|c| &c.name).collect::<Vec<_>>(),
        mdl.clips.iter().map(|c| &c.name).collect::<Vec<_>>()
    );
    let (mut pose_t, mut pose_deg) = (0f32, 0f32);
    for (a, b) in qc.clips.iter().zip(&mdl.clips) {
        for (ta, tb) in a.tracks.iter().zip(&b.tracks) {
            assert_eq!(ta.joint, tb.joint);
            for (x, y) in ta.translation.values.iter().zip(&tb.translation.values) {
                pose_t = pose_t.max((*x - *y).length());
            }
            for (x, y) in ta.rotation.values.iter().zip(&tb.rotation.values) {
                pose_deg = pose_deg.max(angle_deg(*x, *y));
            }
        }
    }
    Figures {
        bind,
        position,
        normal_deg: normal,
        uv,
        pose_t,
        pose_deg,
    }
}

#[test]
fn qc_sources_compile_to_what_their_mdl_holds() {
    let Some(src) = sources() else {
        eprintln!(
            "SINEW_HL_SOURCES is not set: the QC/MDL comparison is skipped (see the file's head)"
        );
        return;
    };
    let Some(corpus) = sinew_testdata::corpus() else {
        return;
    };
    for name in ["man", "chrome_sphere", "alpha_test", "sequence_transitions"] {
        let qc = import_path(
            &src.join(name).join(format!("{name}.qc")),
            &ImportOptions::default(),
        )
        .unwrap();
        let mdl = import_path(
            &corpus.join("mdl").join(format!("{name}.mdl")),
            &ImportOptions::default(),
        )
        .unwrap();
        let f = compare(&qc, &mdl);
        eprintln!(
            "{name}: bind {:.2e}, vertices {:.2e}, normals {:.3} deg, uv {:.4}, pose translation {:.2e}, rotation {:.2e} deg",
            f.bind, f.position, f.normal_deg, f.uv, f.pose_t, f.pose_deg
        );
        assert!(f.bind < 1e-5, "{name}");
        assert!(f.position < 1e-4, "{name}");
        assert!(f.pose_t < 1e-4 && f.pose_deg < 1e-3, "{name}");
    }
}
