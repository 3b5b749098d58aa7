//! LOD generation on a synthetic skinned tube (always) and, once importers exist, corpus meshes.
#![allow(clippy::unwrap_used)]

use sinew_core::glam::{Quat, Vec2, Vec3};
use sinew_core::{JointDesc, Lod, Skeleton, Submesh, Transform};
use sinew_pipeline::lod::{build_lods, generate_lods, LodOptions};
use sinew_scene::{Mesh, NotBuiltReason, Scene, SourceFormat};
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
    scene.meshes.push(Mesh::unsplit("tube", lod));
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
    let reports = generate_lods(&mut scene, &LodOptions::default()).unwrap();
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
    generate_lods(&mut scene, &LodOptions::default()).unwrap();
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
    // A limit far below what 5% of the triangles needs: the level stops before removing half of
    // what it asks, so it is not written; the report names the limit.
    let chain = build_lods(
        mesh,
        scene.skeleton.as_ref(),
        &LodOptions {
            ratios: vec![0.05, 0.01],
            max_error: Some(1e-5),
            lowest_lod_influences: 4,
            keep_uv_seams: false,
        },
    )
    .unwrap();
    assert!(chain.lods.is_empty());
    assert_eq!(chain.not_built.len(), 2);
    let first = &chain.not_built[0];
    assert_eq!((first.level, first.previous_triangles), (1, tris));
    assert_eq!(first.reason, NotBuiltReason::ErrorLimit);
    let reached = first.reached_triangles.unwrap();
    assert!(2 * reached > tris + tris / 20, "{reached}");
    assert_eq!(chain.not_built[1].reason, NotBuiltReason::PreviousNotBuilt);
    assert_eq!(chain.not_built[1].reached_triangles, None);
    // Without a limit the same level meets its budget.
    let free = build_lods(
        mesh,
        scene.skeleton.as_ref(),
        &LodOptions {
            ratios: vec![0.05],
            ..Default::default()
        },
    )
    .unwrap();
    assert!(free.not_built.is_empty());
    let got = free.lods[0].lod.triangle_count();
    assert!(got.abs_diff(tris / 20) <= 2, "{got}");
    assert!(!free.lods[0].stopped_by_error_limit);
}

/// A box whose six faces are six materials, each face with its own four vertices: every corner is
/// a border of three material ranges, which meshoptimizer keeps in place, so no collapse is left
/// and the level would be a copy.
#[test]
fn a_level_that_would_be_a_copy_is_not_built() {
    let corner = |i: u32| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
    // Faces as corner numbers, counter-clockwise seen from outside.
    let faces: [[u32; 4]; 6] = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut geometry = Lod::default();
    for (f, face) in faces.iter().enumerate() {
        let base = geometry.positions.len() as u32;
        let [a, b, c] = [0, 1, 2].map(|k| corner(face[k]));
        let n = (b - a).cross(c - a).normalize();
        for &v in face {
            geometry.positions.push(corner(v));
            geometry.normals.push(n);
        }
        geometry.submeshes.push(Submesh {
            first_index: geometry.indices.len() as u32,
            index_count: 6,
            material: format!("face{f}"),
        });
        geometry
            .indices
            .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    let mesh = Mesh {
        name: "box".into(),
        geometry,
        ..Mesh::default()
    };
    let chain = build_lods(&mesh, None, &LodOptions::default()).unwrap();
    assert!(chain.lods.is_empty(), "{} LODs", chain.lods.len());
    let reasons: Vec<NotBuiltReason> = chain.not_built.iter().map(|n| n.reason).collect();
    assert_eq!(
        reasons,
        [NotBuiltReason::NoCollapse, NotBuiltReason::PreviousNotBuilt]
    );
    assert_eq!(chain.not_built[0].previous_triangles, 12);
    assert_eq!(chain.not_built[0].target_ratio, 0.5);
    assert_eq!(chain.not_built[0].reached_triangles, Some(12));
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
            max_error: None,
            lowest_lod_influences: 2,
            keep_uv_seams: false,
        },
    )
    .unwrap()
    .lods;
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
