//! LOD generation on a synthetic skinned tube (always) and, once importers exist, corpus meshes.
#![allow(clippy::unwrap_used)]

use sinew_core::glam::{Quat, Vec2, Vec3};
use sinew_core::{JointDesc, Lod, Skeleton, Submesh, Transform};
use sinew_pipeline::lod::{build_lods, generate_lods, LodOptions};
use sinew_scene::{Mesh, Scene, SourceFormat};
use sinew_testdata::geometry::*;

/// A tube along +Y, 40 rings of 32 vertices, two joints (lower half / upper half, blended in the middle),
/// two submeshes (rings 0-19 "a", 20-39 "b") that share no vertices but meet at equal positions.
fn tube() -> (Scene, usize) {
    let rings = 40;
    let around = 32;
    let mut lod = Lod::default();
    let mut submeshes = Vec::new();
    for half in 0..2 {
        let base = lod.positions.len() as u32;
        let first_ring = half * (rings / 2);
        // Each half also repeats the ring where the halves meet, so the border is shared by position.
        let last_ring = first_ring + rings / 2;
        for r in first_ring..=last_ring {
            let y = r as f32 / rings as f32 * 10.0;
            for k in 0..around {
                let a = k as f32 / around as f32 * std::f32::consts::TAU;
                lod.positions.push(Vec3::new(a.cos(), y, a.sin()));
                lod.normals.push(Vec3::new(a.cos(), 0.0, a.sin()));
                lod.uvs.push(Vec2::new(k as f32 / around as f32, y / 10.0));
                let upper = ((y - 4.0) / 2.0).clamp(0.0, 1.0);
                lod.joints.push([0, 1, 0, 0]);
                lod.weights.push([1.0 - upper, upper, 0.0, 0.0]);
            }
        }
        let first_index = lod.indices.len() as u32;
        for r in 0..(last_ring - first_ring) as u32 {
            for k in 0..around as u32 {
                let a = base + r * around as u32 + k;
                let b = base + r * around as u32 + (k + 1) % around as u32;
                let c = a + around as u32;
                let d = b + around as u32;
                lod.indices.extend([a, c, b, b, c, d]);
            }
        }
        submeshes.push(Submesh {
            first_index,
            index_count: lod.indices.len() as u32 - first_index,
            material: ["a", "b"][half].into(),
        });
    }
    lod.submeshes = submeshes;
    let tris = lod.triangle_count();
    let (skeleton, _) = Skeleton::from_unordered(vec![
        JointDesc {
            name: "lower".into(),
            parent: None,
            bind_local: Transform::IDENTITY,
            inverse_bind: None,
        },
        JointDesc {
            name: "upper".into(),
            parent: Some("lower".into()),
            bind_local: Transform::from_translation(Vec3::new(0.0, 5.0, 0.0)),
            inverse_bind: None,
        },
    ])
    .unwrap();
    let mut scene = Scene::new(SourceFormat::Sinew);
    scene.skeleton = Some(skeleton);
    let n = lod.positions.len() as u32;
    scene.meshes.push(Mesh {
        name: "tube".into(),
        geometry: lod,
        source_vertex: (0..n).collect(),
        source_vertex_count: n,
        lods: Vec::new(),
    });
    (scene, tris)
}

fn check_lod_invariants(base: &Lod, lod: &Lod) {
    let n = lod.positions.len() as u32;
    assert!(
        lod.indices.iter().all(|&i| i < n),
        "index past the vertices"
    );
    assert_eq!(lod.indices.len() % 3, 0);
    for w in &lod.weights {
        let s: f32 = w.iter().sum();
        assert!((s - 1.0).abs() < 1e-5, "weights sum to {s}");
    }
    assert_eq!(lod.submeshes.len(), base.submeshes.len());
    for (a, b) in lod.submeshes.iter().zip(&base.submeshes) {
        assert_eq!(a.material, b.material);
    }
    let covered: u32 = lod.submeshes.iter().map(|s| s.index_count).sum();
    assert_eq!(covered as usize, lod.indices.len());
    // Every vertex of the LOD is used (compacted).
    let mut used = vec![false; lod.positions.len()];
    for &i in &lod.indices {
        used[i as usize] = true;
    }
    assert!(used.iter().all(|&u| u));
}

#[test]
fn tube_reaches_targets_keeps_materials_and_stays_close() {
    let (mut scene, tris) = tube();
    assert_eq!(tris, 2560);
    let options = LodOptions {
        max_error: 1.0,
        ..Default::default()
    };
    let reports = generate_lods(&mut scene, &options).unwrap();
    let mesh = &scene.meshes[0];
    let base = &mesh.geometry;
    assert_eq!(reports[0].lods.len(), 2);
    let diag = diagonal(&base.positions);
    for (g, target) in mesh.lods.iter().zip([0.5, 0.25]) {
        check_lod_invariants(base, &g.lod);
        let got = g.lod.triangle_count() as f32 / tris as f32;
        // Within 5% of the target (the rounding of each submesh's share, plus what meshoptimizer stops at).
        assert!(
            (got - target).abs() <= 0.05 * target,
            "ratio {got} for target {target}"
        );
        assert_eq!(g.reached_ratio, got);
        let h = hausdorff(
            &base.positions,
            &base.indices,
            &g.lod.positions,
            &g.lod.indices,
        );
        assert!(h < 0.02 * diag, "Hausdorff {h} vs diagonal {diag}");
    }
    // Chain errors accumulate.
    assert!(mesh.lods[1].error_relative >= mesh.lods[0].error_relative);
    // The source map followed LOD 0's reordering: every source vertex still appears once.
    let mut seen = mesh.source_vertex.clone();
    seen.sort_unstable();
    assert_eq!(seen, (0..base.positions.len() as u32).collect::<Vec<_>>());
}

#[test]
fn posed_lod_stays_close_to_posed_base() {
    let (mut scene, _) = tube();
    generate_lods(
        &mut scene,
        &LodOptions {
            max_error: 1.0,
            ..Default::default()
        },
    )
    .unwrap();
    let skeleton = scene.skeleton.as_ref().unwrap();
    let mut locals = skeleton.bind_local().to_vec();
    locals[1].rotation = Quat::from_rotation_z(1.0);
    let models = model_matrices(skeleton, &locals);
    let mesh = &scene.meshes[0];
    let base = &mesh.geometry;
    let posed_base = skin_positions(base, skeleton, &models);
    let diag = diagonal(&base.positions);
    for g in &mesh.lods {
        let posed = skin_positions(&g.lod, skeleton, &models);
        let h = hausdorff(&posed_base, &base.indices, &posed, &g.lod.indices);
        assert!(h < 0.02 * diag, "posed Hausdorff {h} vs diagonal {diag}");
    }
}

#[test]
fn error_limit_stops_early_and_says_so() {
    let (scene, tris) = tube();
    let mesh = &scene.meshes[0];
    let lods = build_lods(
        mesh,
        scene.skeleton.as_ref(),
        &LodOptions {
            ratios: vec![0.05],
            max_error: 1e-5,
            lowest_lod_influences: 4,
        },
    )
    .unwrap();
    assert!(lods[0].stopped_by_error_limit);
    assert!(lods[0].lod.triangle_count() > tris / 20 + 2);
    assert!(lods[0].error_relative <= 1e-5);
}

#[test]
fn lowest_lod_influences_are_cut_and_renormalised() {
    let (scene, _) = tube();
    let mut mesh = scene.meshes[0].clone();
    // Give every vertex three influences so that cutting to two changes something.
    for w in &mut mesh.geometry.weights {
        *w = [0.5, 0.3, 0.2, 0.0];
    }
    let lods = build_lods(
        &mesh,
        scene.skeleton.as_ref(),
        &LodOptions {
            ratios: vec![0.5, 0.25],
            max_error: 1.0,
            lowest_lod_influences: 2,
        },
    )
    .unwrap();
    for w in &lods[1].lod.weights {
        assert_eq!(w[2], 0.0);
        assert!(
            (w[0] - 0.625).abs() < 1e-6 && (w[1] - 0.375).abs() < 1e-6,
            "{w:?}"
        );
    }
    // The middle LOD keeps all three.
    assert!(lods[0].lod.weights.iter().all(|w| w[2] == 0.2));
}

#[test]
fn bad_buffers_are_rejected_before_meshoptimizer_sees_them() {
    let (scene, _) = tube();
    let mut mesh = scene.meshes[0].clone();
    mesh.geometry.indices[7] = 1_000_000;
    let e = build_lods(&mesh, scene.skeleton.as_ref(), &LodOptions::default()).unwrap_err();
    assert!(e.to_string().contains("index 1000000"), "{e}");
    let mut mesh = scene.meshes[0].clone();
    mesh.geometry.indices.pop();
    assert!(build_lods(&mesh, None, &LodOptions::default()).is_err());
    let bad = LodOptions {
        ratios: vec![0.25, 0.5],
        ..Default::default()
    };
    assert!(build_lods(&scene.meshes[0], None, &bad).is_err());
}
