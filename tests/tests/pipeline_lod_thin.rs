//! LODs of a many-material figure with thin parts of 12 to 60 triangles (`fixtures/thin.gltf`,
//! issue 30): every thin piece keeps its shape in both LODs, at rest and at five times of the
//! fixture's clip, the tips survive, LOD 2 has at most 0.6x LOD 1's triangles, and at gltfpack's
//! triangle counts the LODs are closer than gltfpack's.
//!
//! gltfpack's figures are the other tool's, measured by `crates/pipeline/examples/lod_peers.rs`
//! (native gltfpack built from the peers' meshoptimizer mirror, `-si R -sa -kn -noq`; docs/lod.md).
#![allow(clippy::unwrap_used)]

use sinew_core::glam::{Mat4, Vec3};
use sinew_core::Lod;
use sinew_import::{import_path, ImportOptions};
use sinew_pipeline::compile::compile;
use sinew_pipeline::lod::{generate_lods, LodOptions};
use sinew_scene::Scene;
use sinew_testdata::geometry::{diagonal, hausdorff, posed_models, skin_positions, TriangleGrid};

/// The sword's and the antenna's tips (fixtures/generator/src/thin.rs).
const TIPS: [Vec3; 2] = [Vec3::new(0.9, 2.4, 0.0), Vec3::new(0.12, 2.62, 0.0)];
/// Times of the `act` clip the LODs are posed at (s).
const TIMES: [f32; 5] = [0.25, 0.5, 0.75, 1.25, 1.5];

fn scene() -> Scene {
    let path = sinew_testdata::fixtures().join("thin.gltf");
    import_path(&path, &ImportOptions::default()).unwrap()
}

/// Model matrices of the fixture's first clip at time `t` (for `skin_positions`).
fn models(scene: &Scene, t: f32) -> Vec<Mat4> {
    let clip = &compile(scene).unwrap().clips[0];
    posed_models(scene.skeleton.as_ref().unwrap(), clip, t)
}

/// LOD 0's connected pieces (triangles joined through shared positions) of at most 60 triangles:
/// per piece, the positions of its vertices.
fn thin_pieces(base: &Lod) -> Vec<Vec<Vec3>> {
    let n = base.positions.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    // Vertices at one position are one.
    let mut order: Vec<usize> = (0..n).collect();
    let key = |v: usize| base.positions[v].to_array().map(f32::to_bits);
    order.sort_by_key(|&v| key(v));
    for w in order.windows(2) {
        if key(w[0]) == key(w[1]) {
            let (a, b) = (find(&mut parent, w[0]), find(&mut parent, w[1]));
            parent[b] = a;
        }
    }
    for t in base.indices.chunks_exact(3) {
        let a = find(&mut parent, t[0] as usize);
        for &c in &t[1..] {
            let b = find(&mut parent, c as usize);
            parent[b] = a;
        }
    }
    let mut tris = vec![0usize; n];
    for t in base.indices.chunks_exact(3) {
        tris[find(&mut parent, t[0] as usize)] += 1;
    }
    let mut pieces: std::collections::BTreeMap<usize, Vec<Vec3>> = Default::default();
    for t in base.indices.chunks_exact(3) {
        let r = find(&mut parent, t[0] as usize);
        if tris[r] <= 60 {
            let e = pieces.entry(r).or_default();
            e.extend(t.iter().map(|&v| base.positions[v as usize]));
        }
    }
    pieces.into_values().collect()
}

fn extent(points: &[Vec3]) -> f32 {
    let (lo, hi) = points.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    (hi - lo).length()
}

#[test]
fn every_thin_piece_keeps_its_shape_and_the_tips_survive() {
    let mut s = scene();
    let base = s.meshes[0].geometry.clone();
    generate_lods(&mut s, &LodOptions::default()).unwrap();
    let mesh = &s.meshes[0];
    let pieces = thin_pieces(&base);
    assert_eq!(pieces.len(), 12);
    assert_eq!(mesh.lods.len(), 2);
    for (k, g) in mesh.lods.iter().enumerate() {
        for tip in TIPS {
            assert!(
                g.lod.positions.contains(&tip),
                "LOD {} lost the tip {tip}",
                k + 1
            );
        }
        // Every vertex of every thin piece lies within a sixth of the piece's size of the LOD's
        // surface (a piece losing its tip, or being swallowed, moves a vertex by most of it).
        let grid = TriangleGrid::new(&g.lod.positions, &g.lod.indices);
        for (i, piece) in pieces.iter().enumerate() {
            let size = extent(piece);
            let far = piece
                .iter()
                .map(|p| grid.distance(*p))
                .fold(0.0f32, f32::max);
            assert!(
                far < size / 6.0,
                "LOD {}: piece {i} ({} triangles) lies {far} from the LOD, size {size}",
                k + 1,
                piece.len() / 3
            );
        }
    }
    // Each level earns its place: LOD 2 has at most 0.6x LOD 1's triangles.
    let (l1, l2) = (
        mesh.lods[0].lod.triangle_count(),
        mesh.lods[1].lod.triangle_count(),
    );
    assert!(l2 * 10 <= l1 * 6, "{l1} -> {l2}");
    assert!(mesh.lods_not_built.is_empty());
}

/// gltfpack `-si 0.5 -sa` and `-si 0.25 -sa` (`-kn -noq`) on this file: triangles reached, distance
/// at rest, and at the five times of [`TIMES`] (% of LOD 0's diagonal, lod_peers' measure).
const GLTFPACK: [(usize, f32, [f32; 5]); 2] = [
    (911, 12.886, [12.886, 12.886, 12.886, 12.886, 12.886]),
    (897, 5.913, [5.913, 5.913, 4.428, 5.913, 5.913]),
];

#[test]
fn at_gltfpacks_counts_the_lods_are_closer_at_rest_and_posed() {
    let s = scene();
    let base = &s.meshes[0].geometry;
    let tris = base.triangle_count() as f32;
    let mut m = s.clone();
    let options = LodOptions {
        ratios: GLTFPACK.iter().map(|g| g.0 as f32 / tris).collect(),
        ..Default::default()
    };
    generate_lods(&mut m, &options).unwrap();
    let diag = diagonal(&base.positions);
    for (k, (count, rest, posed)) in GLTFPACK.iter().enumerate() {
        let lod = &m.meshes[0].lods[k].lod;
        assert!(
            lod.triangle_count() <= count + 1,
            "{}",
            lod.triangle_count()
        );
        let d =
            hausdorff(&base.positions, &base.indices, &lod.positions, &lod.indices) / diag * 100.0;
        assert!(
            d < *rest,
            "LOD {} at rest: {d:.3}% vs gltfpack {rest}%",
            k + 1
        );
        for (t, g) in TIMES.iter().zip(posed) {
            let pal = models(&s, *t);
            let sk = s.skeleton.as_ref().unwrap();
            let d = hausdorff(
                &skin_positions(base, sk, &pal),
                &base.indices,
                &skin_positions(lod, sk, &pal),
                &lod.indices,
            ) / diag
                * 100.0;
            assert!(d < *g, "LOD {} at {t} s: {d:.3}% vs gltfpack {g}%", k + 1);
        }
    }
}

#[test]
fn lods_stay_close_at_rest_and_posed() {
    let mut s = scene();
    let base = s.meshes[0].geometry.clone();
    generate_lods(&mut s, &LodOptions::default()).unwrap();
    let diag = diagonal(&base.positions);
    for (k, g) in s.meshes[0].lods.iter().enumerate() {
        let lod = &g.lod;
        let rest = hausdorff(&base.positions, &base.indices, &lod.positions, &lod.indices);
        // The reported error bounds the measured distance.
        assert!(
            g.error_model >= rest,
            "LOD {}: {} < {rest}",
            k + 1,
            g.error_model
        );
        let mut worst = rest;
        for t in TIMES {
            let pal = models(&s, t);
            let sk = s.skeleton.as_ref().unwrap();
            worst = worst.max(hausdorff(
                &skin_positions(&base, sk, &pal),
                &base.indices,
                &skin_positions(lod, sk, &pal),
                &lod.indices,
            ));
        }
        let pct = worst / diag * 100.0;
        // Measured: 0.72% (LOD 1) and 2.59% (LOD 2) at worst.
        assert!(pct < [1.0, 3.0][k], "LOD {}: {pct:.3}%", k + 1);
    }
}
