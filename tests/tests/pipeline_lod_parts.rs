//! LODs of a many-part mesh with a thin blade (`fixtures/parts.gltf`, issue 18): the generated LODs
//! keep every part's reach (the blade's tip survives), stay closer to LOD 0 than gltfpack 1.3.0 did
//! on the same file, at rest and posed at several times of its clip, and the error each LOD reports
//! bounds the distance measured here.
//!
//! Bounds come from measurements with the peers' script (`../shared/peers/lod_hausdorff.py`, vertices,
//! centroids, edge midpoints and 20,000 random points; docs/lod.md): gltfpack `-si 0.5` and `-si 0.25`
//! both stop at 933 of 1,466 triangles on this file, 1.935% of the diagonal away (with `-sa` it reaches
//! 715 triangles at 1.935% and 313 at 13.6%). sinew's LODs have fewer triangles than that and must stay
//! under 1.9% — which the same LOD builder without its part locks does not (1.935% at LOD 2).
#![allow(clippy::unwrap_used)]

use sinew_core::glam::{Mat4, Vec3};
use sinew_import::{import_path, ImportOptions};
use sinew_pipeline::compile::compile;
use sinew_pipeline::lod::{generate_lods, LodOptions};
use sinew_scene::Scene;
use sinew_testdata::geometry::{diagonal, hausdorff, posed_models, skin_positions, TriangleGrid};

/// gltfpack 1.3.0's distance on this file at more triangles than either LOD, in % of the diagonal,
/// less a little: sinew must do better.
const GLTFPACK_BOUND_PCT: f32 = 1.9;
/// The blade's tip at rest (fixtures/generator/src/parts.rs, `BLADE_TIP`).
const BLADE_TIP: Vec3 = Vec3::new(2.15, 1.5, 0.0);

fn scene() -> Scene {
    let path = sinew_testdata::fixtures().join("parts.gltf");
    import_path(&path, &ImportOptions::default()).unwrap()
}

fn lods(scene: &mut Scene) -> Vec<sinew_scene::GeneratedLod> {
    let reports = generate_lods(scene, &LodOptions::default()).unwrap();
    assert_eq!(reports.len(), 1);
    reports[0].lods.clone()
}

/// `n` points on the surface, area-weighted, from a fixed xorshift sequence.
fn random_points(positions: &[Vec3], indices: &[u32], n: usize) -> Vec<Vec3> {
    let tris: Vec<[Vec3; 3]> = indices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|i| positions[t[i] as usize]))
        .collect();
    let areas: Vec<f32> = tris
        .iter()
        .map(|t| (t[1] - t[0]).cross(t[2] - t[0]).length() * 0.5)
        .collect();
    let total: f32 = areas.iter().sum();
    let mut s = 0x9E37_79B9u32;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        (s >> 8) as f32 / (1u32 << 24) as f32
    };
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let mut pick = rnd() * total;
        let mut k = 0;
        while k + 1 < areas.len() && pick > areas[k] {
            pick -= areas[k];
            k += 1;
        }
        let (mut u, mut v) = (rnd(), rnd());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let t = tris[k];
        out.push(t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v);
    }
    out
}

/// Symmetric distance measured here: the test library's sampled Hausdorff (vertices, centroids, edge
/// midpoints) and 5,000 random surface points of each mesh against the other.
fn measured(a: (&[Vec3], &[u32]), b: (&[Vec3], &[u32])) -> f32 {
    let mut d = hausdorff(a.0, a.1, b.0, b.1);
    for (from, to) in [(a, b), (b, a)] {
        let grid = TriangleGrid::new(to.0, to.1);
        for p in random_points(from.0, from.1, 5_000) {
            d = d.max(grid.distance(p));
        }
    }
    d
}

/// Model matrices of the fixture's first clip at time `t` (for `skin_positions`).
fn models(scene: &Scene, t: f32) -> Vec<Mat4> {
    let clip = &compile(scene).unwrap().clips[0];
    posed_models(scene.skeleton.as_ref().unwrap(), clip, t)
}

#[test]
fn the_fixture_is_many_parts_with_a_thin_blade() {
    let s = scene();
    let g = &s.meshes[0].geometry;
    assert_eq!(g.triangle_count(), 1_466);
    // The blade's tip is one vertex, far out along +x.
    assert_eq!(g.positions.iter().filter(|p| **p == BLADE_TIP).count(), 1);
    assert!(diagonal(&g.positions) > 3.0);
}

#[test]
fn lods_keep_the_blade_tip_and_stay_closer_than_gltfpack_at_rest() {
    let mut s = scene();
    let base = s.meshes[0].geometry.clone();
    let diag = diagonal(&base.positions);
    let lods = lods(&mut s);
    assert_eq!(lods.len(), 2);
    for (k, g) in lods.iter().enumerate() {
        let lod = &g.lod;
        assert!(
            lod.positions.contains(&BLADE_TIP),
            "LOD {} lost the blade's tip",
            k + 1
        );
        // Fewer triangles than gltfpack kept (933), and the target reached.
        assert!(lod.triangle_count() < 933, "LOD {}", k + 1);
        assert!(!g.stopped_by_error_limit, "LOD {}", k + 1);
        let d = measured(
            (&base.positions, &base.indices),
            (&lod.positions, &lod.indices),
        );
        let pct = d / diag * 100.0;
        assert!(
            pct < GLTFPACK_BOUND_PCT,
            "LOD {}: {pct:.3}% of the diagonal",
            k + 1
        );
        // The reported error bounds what was measured here.
        assert!(
            g.error_model >= d,
            "LOD {}: reports {} model units, measured {d}",
            k + 1,
            g.error_model
        );
        assert_eq!(lod.error, g.error_relative);
    }
}

#[test]
fn lods_stay_close_when_posed_at_several_times_of_the_clip() {
    let mut s = scene();
    let base = s.meshes[0].geometry.clone();
    let diag = diagonal(&base.positions);
    let lods = lods(&mut s);
    // 0.5 s: the arm at the top of its swing; 1.5 s: at the bottom; 1.0 s: back at rest.
    for t in [0.25, 0.5, 1.0, 1.5, 1.75] {
        let pal = models(&s, t);
        let sk = s.skeleton.as_ref().unwrap();
        let posed_base = skin_positions(&base, sk, &pal);
        // The blade really moves: its tip is elsewhere at 0.5 s.
        if t == 0.5 {
            let tip = base.positions.iter().position(|p| *p == BLADE_TIP).unwrap();
            assert!(posed_base[tip].distance(BLADE_TIP) > 0.5);
        }
        for (k, g) in lods.iter().enumerate() {
            let posed = skin_positions(&g.lod, sk, &pal);
            let d = measured((&posed_base, &base.indices), (&posed, &g.lod.indices));
            let pct = d / diag * 100.0;
            assert!(
                pct < GLTFPACK_BOUND_PCT,
                "LOD {} at {t} s: {pct:.3}%",
                k + 1
            );
        }
    }
}
