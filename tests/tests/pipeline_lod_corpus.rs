//! LODs of corpus meshes: CesiumMan and Fox (glTF), ninja (MS3D), spot (static OBJ).
//!
//! Bounds stated once: each LOD reaches its triangle budget within 5% (of the target); the sampled
//! Hausdorff distance to LOD 0 stays under 5% of LOD 0's bounding-box diagonal, at bind pose and with
//! both skinned by the file's first clip at half its duration; no LOD triangle joins two UV charts
//! (UV seams kept).
//!
//! Comparisons: at gltfpack's triangle counts, sinew's LODs are at least as close as gltfpack 1.3.0's
//! (figures measured by tools/lod-compare.sh, docs/performance.md), and closer when posed than a
//! skin-blind meshoptimizer simplification computed here.
#![allow(clippy::unwrap_used)]

use sinew_core::glam::{Mat4, Vec3};
use sinew_core::{ClipBinding, Lod, Sampler};
use sinew_import::{import_path, ImportOptions};
use sinew_pipeline::lod::{
    generate_lods, generate_lods_tuned, plain_work, reference_poses, scene_motion, LodOptions,
    LodTuning, PLAIN_WORK_BOUND,
};
use sinew_scene::Scene;
use sinew_testdata::geometry::*;
use std::collections::HashMap;

const TARGET_TOLERANCE: f32 = 0.05;
const HAUSDORFF_BOUND: f32 = 0.05;

fn load(relative: &str) -> Option<Scene> {
    let path = sinew_testdata::corpus_file(relative)?;
    Some(import_path(&path, &ImportOptions::default()).unwrap())
}

/// Palette of the first clip at half its duration, sampled with the runtime's Sampler.
fn mid_palette(scene: &Scene) -> Option<Vec<Mat4>> {
    palette_at(scene, 0.5)
}

/// Palette of the first clip at `fraction` of its duration, sampled with the runtime's Sampler.
fn palette_at(scene: &Scene, fraction: f32) -> Option<Vec<Mat4>> {
    let skeleton = scene.skeleton.as_ref()?;
    let c = scene.clips.first()?;
    let clip = c.to_clip().unwrap();
    assert!(clip.duration() > 0.0, "clip {} has no duration", c.name);
    let binding = ClipBinding::new(&clip, skeleton);
    let mut locals = skeleton.bind_local().to_vec();
    Sampler::new()
        .sample(
            &clip,
            &binding,
            skeleton,
            clip.duration() * fraction,
            &mut locals,
        )
        .unwrap();
    let models = model_matrices(skeleton, &locals);
    Some(
        models
            .iter()
            .zip(skeleton.inverse_bind())
            .map(|(m, ib)| *m * *ib)
            .collect(),
    )
}

fn skin(lod: &Lod, palette: &[Mat4]) -> Vec<Vec3> {
    let mut out = vec![Vec3::ZERO; lod.positions.len()];
    sinew_core::skin(
        palette,
        &lod.positions,
        &[],
        &lod.joints,
        &lod.weights,
        &mut out,
        &mut [],
    )
    .unwrap();
    out
}

/// The UV chart of every vertex: vertices are joined when a triangle uses both, or when they have the
/// same position and the same UV (vertices split only by their normal stay in one chart). Returns a
/// chart id per (position, UV) key.
fn uv_charts(lod: &Lod) -> HashMap<[u32; 5], usize> {
    let key = |v: usize| {
        let p = lod.positions[v];
        let uv = lod.uvs[v];
        [
            p.x.to_bits(),
            p.y.to_bits(),
            p.z.to_bits(),
            uv.x.to_bits(),
            uv.y.to_bits(),
        ]
    };
    let mut id: HashMap<[u32; 5], usize> = HashMap::new();
    for v in 0..lod.positions.len() {
        let n = id.len();
        id.entry(key(v)).or_insert(n);
    }
    let mut parent: Vec<usize> = (0..id.len()).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for t in lod.indices.chunks_exact(3) {
        let a = find(&mut parent, id[&key(t[0] as usize)]);
        for &c in &t[1..] {
            let b = find(&mut parent, id[&key(c as usize)]);
            parent[b] = a;
        }
    }
    let keys: Vec<([u32; 5], usize)> = id.iter().map(|(k, &v)| (*k, v)).collect();
    keys.into_iter()
        .map(|(k, v)| (k, find(&mut parent, v)))
        .collect()
}

/// Every triangle of `lod` lies in one UV chart of `base` (its corners are copies of base vertices).
fn assert_uv_seams_kept(what: &str, base: &Lod, lod: &Lod) {
    if base.uvs.is_empty() {
        return;
    }
    let mixed = uv_charts_joined(what, base, lod);
    assert_eq!(mixed, 0, "{what}: {mixed} triangles join two UV charts");
}

/// The triangles of `lod` whose corners lie in two or three UV charts of `base` (its corners are
/// copies of base vertices).
fn uv_charts_joined(what: &str, base: &Lod, lod: &Lod) -> usize {
    let charts = uv_charts(base);
    let chart = |v: u32| {
        let (p, uv) = (lod.positions[v as usize], lod.uvs[v as usize]);
        let k = [
            p.x.to_bits(),
            p.y.to_bits(),
            p.z.to_bits(),
            uv.x.to_bits(),
            uv.y.to_bits(),
        ];
        *charts
            .get(&k)
            .unwrap_or_else(|| panic!("{what}: LOD vertex {v} is not a vertex of LOD 0"))
    };
    lod.indices
        .chunks_exact(3)
        .filter(|t| chart(t[0]) != chart(t[1]) || chart(t[0]) != chart(t[2]))
        .count()
}

/// Builds the default LODs and checks every stated property; returns the LODs' triangle ratios.
fn check(relative: &str, expect_skinned: bool) -> Option<Vec<f32>> {
    let mut scene = load(relative)?;
    let source = scene.clone();
    let options = LodOptions::default();
    generate_lods(&mut scene, &options).unwrap();
    let palette = mid_palette(&scene);
    assert_eq!(
        palette.is_some(),
        expect_skinned,
        "{relative}: clip + skeleton"
    );
    let mut ratios = Vec::new();
    for (mesh, src) in scene.meshes.iter().zip(&source.meshes) {
        let base = &mesh.geometry;
        // LOD 0 is only reordered.
        assert_eq!(base.triangle_count(), src.geometry.triangle_count());
        assert_eq!(mesh.lods.len(), 2, "{relative} {}", mesh.name);
        let diag = diagonal(&base.positions);
        let base_tris = base.triangle_count();
        for (g, &target) in mesh.lods.iter().zip(&options.ratios) {
            let lod = &g.lod;
            let what = format!("{relative} {} target {target}", mesh.name);
            // Buffers: every index in range, weights sum to one, materials kept in order.
            let n = lod.positions.len() as u32;
            assert!(
                lod.indices.iter().all(|&i| i < n),
                "{what}: index past vertices"
            );
            assert_eq!(lod.indices.len() % 3, 0);
            assert_eq!(lod.normals.len(), lod.positions.len());
            if base.is_skinned() {
                assert_eq!(lod.weights.len(), lod.positions.len());
                for w in &lod.weights {
                    let s: f32 = w.iter().sum();
                    assert!((s - 1.0).abs() < 1e-4, "{what}: weights sum to {s}");
                }
            }
            let materials: Vec<&str> = lod.submeshes.iter().map(|s| s.material.as_str()).collect();
            let base_materials: Vec<&str> =
                base.submeshes.iter().map(|s| s.material.as_str()).collect();
            assert_eq!(materials, base_materials, "{what}");
            assert_uv_seams_kept(&what, base, lod);
            // The triangle budget is met (no error limit by default).
            let got = lod.triangle_count() as f32 / base_tris as f32;
            assert_eq!(g.reached_ratio, got);
            assert!(
                (got - target).abs() <= TARGET_TOLERANCE * target,
                "{what}: reached {got}"
            );
            assert!(!g.stopped_by_error_limit && !g.uv_seams_opened, "{what}");
            ratios.push(got);
            // Shape.
            let h = hausdorff(&base.positions, &base.indices, &lod.positions, &lod.indices);
            assert!(
                h < HAUSDORFF_BOUND * diag,
                "{what}: Hausdorff {h}, diagonal {diag}"
            );
            // The reported error bounds the measured distance (issue 18).
            assert!(
                g.error_model >= h,
                "{what}: reports {} model units, measured {h}",
                g.error_model
            );
            if let (Some(pal), true) = (&palette, base.is_skinned()) {
                let pb = skin(base, pal);
                let pl = skin(lod, pal);
                let posed_diag = diagonal(&pb);
                let h = hausdorff(&pb, &base.indices, &pl, &lod.indices);
                assert!(
                    h < HAUSDORFF_BOUND * posed_diag,
                    "{what}: posed Hausdorff {h}, diagonal {posed_diag}"
                );
            }
        }
    }
    Some(ratios)
}

#[test]
fn cesium_man() {
    let Some(r) = check("gltf/CesiumMan.glb", true) else {
        return;
    };
    // Smooth, indexed, 4672 triangles: both targets are met.
    assert!(
        (r[0] - 0.5).abs() < 0.01 && (r[1] - 0.25).abs() < 0.01,
        "{r:?}"
    );
}

#[test]
fn fox_is_welded_before_simplifying() {
    let Some(r) = check("gltf/Fox.glb", true) else {
        return;
    };
    // Fox.glb is non-indexed (1728 vertices, 576 triangles) with generated flat normals: without the
    // weld nothing collapses (ratio 1.0); with it both LODs meet their budgets.
    assert!(
        (r[0] - 0.5).abs() < 0.01 && (r[1] - 0.25).abs() < 0.01,
        "{r:?}"
    );
}

#[test]
fn ninja_ms3d() {
    let Some(r) = check("ms3d/ninja.ms3d", true) else {
        return;
    };
    assert!((r[0] - 0.5).abs() < 0.01, "{r:?}");
}

#[test]
fn spot_obj_static() {
    let Some(r) = check("obj/spot.obj", false) else {
        return;
    };
    assert!(
        (r[0] - 0.5).abs() < 0.01 && (r[1] - 0.25).abs() < 0.01,
        "{r:?}"
    );
}

#[test]
fn grid_hausdorff_matches_brute_force() {
    let Some(scene) = load("obj/spot.obj") else {
        return;
    };
    let mut s = scene.clone();
    generate_lods(&mut s, &LodOptions::default()).unwrap();
    let a = &s.meshes[0].geometry;
    let b = &s.meshes[0].lods[1].lod;
    let grid = one_sided(&b.positions, &b.indices, &a.positions, &a.indices);
    let brute = one_sided_brute(&b.positions, &b.indices, &a.positions, &a.indices);
    assert!(brute > 0.0);
    assert!(
        (grid - brute).abs() <= 1e-6 * brute.max(1.0),
        "{grid} vs {brute}"
    );
}

/// Sampled Hausdorff distances (rest, posed) between LOD 0 and a LOD in percent of LOD 0's bind-pose
/// bounding-box diagonal, as examples/lod_compare.rs reports them.
fn distances_percent(base: &Lod, lod: &Lod, palette: &[Mat4]) -> (f32, f32) {
    let diag = diagonal(&base.positions);
    let rest = hausdorff(&base.positions, &base.indices, &lod.positions, &lod.indices);
    let posed = hausdorff(
        &skin(base, palette),
        &base.indices,
        &skin(lod, palette),
        &lod.indices,
    );
    (rest / diag * 100.0, posed / diag * 100.0)
}

/// gltfpack 1.3.0 (`gltfpack -i IN -o OUT -si R -noq`), as measured by tools/lod-compare.sh and
/// recorded in docs/performance.md: (triangles reached, Hausdorff %, posed Hausdorff % with the
/// original's palette). These are the other tool's figures, not sinew's.
const GLTFPACK_CESIUM_MAN: [(usize, f32, f32); 2] = [(2336, 0.247, 0.319), (1184, 0.548, 0.688)];
const GLTFPACK_FOX: (usize, f32, f32) = (418, 0.935, 1.125);

/// Builds sinew's chain at the given triangle counts (ratios of LOD 0) and returns its LODs.
fn chain_at(scene: &Scene, counts: &[usize]) -> Scene {
    chain_tuned_at(scene, counts, &LodTuning::default())
}

/// [`chain_at`] with the plain builds (`convert --effort max`).
fn plain_chain_at(scene: &Scene, counts: &[usize]) -> Scene {
    let tuning = LodTuning {
        plain_candidate: true,
        ..LodTuning::default()
    };
    chain_tuned_at(scene, counts, &tuning)
}

/// The first mesh's LOD built with the plain builds at `tris` triangles: its triangles and its
/// distance to LOD 0 at rest, % of the diagonal.
fn plain_rest_at(scene: &Scene, tris: usize) -> (usize, f32) {
    rest_at(&plain_chain_at(scene, &[tris]))
}

/// The first mesh's first generated LOD: its triangles and its distance to LOD 0 at rest, % of the
/// diagonal.
fn rest_at(built: &Scene) -> (usize, f32) {
    let base = &built.meshes[0].geometry;
    let lod = &built.meshes[0].lods[0].lod;
    let d = hausdorff(&base.positions, &base.indices, &lod.positions, &lod.indices);
    (lod.triangle_count(), d / diagonal(&base.positions) * 100.0)
}

fn chain_tuned_at(scene: &Scene, counts: &[usize], tuning: &LodTuning) -> Scene {
    let mut s = scene.clone();
    let base = s.meshes[0].geometry.triangle_count() as f32;
    let options = LodOptions {
        ratios: counts.iter().map(|&c| c as f32 / base).collect(),
        ..Default::default()
    };
    generate_lods_tuned(&mut s, &options, tuning).unwrap();
    s
}

#[test]
fn cesium_man_at_least_as_close_as_gltfpack() {
    let Some(scene) = load("gltf/CesiumMan.glb") else {
        return;
    };
    let palette = mid_palette(&scene).unwrap();
    let counts: Vec<usize> = GLTFPACK_CESIUM_MAN.iter().map(|g| g.0).collect();
    let s = chain_at(&scene, &counts);
    let mesh = &s.meshes[0];
    for (k, &(tris, rest, posed)) in GLTFPACK_CESIUM_MAN.iter().enumerate() {
        let lod = &mesh.lods[k].lod;
        assert_eq!(lod.triangle_count(), tris);
        let (r, p) = distances_percent(&mesh.geometry, lod, &palette);
        assert!(r <= rest, "LOD{} rest {r:.3}% vs gltfpack {rest}%", k + 1);
        // At 50% the chain's own build was 0.325% posed, gltfpack's 0.319%, until the repair's
        // posed check (beyond the plain builds' bound: docs/lod.md, "A posed check without a
        // grid per pose"); the test below shows the chain without it.
        assert!(
            p <= posed,
            "LOD{} posed {p:.3}% vs gltfpack {posed}%",
            k + 1
        );
    }
}

/// gltfpack 1.2 (`-si 0.5 -kn -noq`, the peers' build) on RiggedFigure: 228 of 256 triangles,
/// 0.306% of the diagonal at rest and at 1/8, 1/4, 1/2 and 3/4 of its clip (docs/lod.md).
const GLTFPACK_RIGGED_FIGURE: (usize, f32) = (228, 0.306);

/// The plain builds are also compared under poses sampled from the scene's own clips (docs/lod.md,
/// "How one step is built"): under the two test poses alone the positions-only build won at 228
/// and tore at 1/8 of the clip (0.648% against gltfpack's 0.306%). The clip times checked here
/// are not among those the reference poses are picked from (the middles of 64 equal parts).
#[test]
fn rigged_figure_at_least_as_close_as_gltfpack_in_its_clip() {
    let Some(scene) = load("gltf/RiggedFigure.glb") else {
        return;
    };
    let (tris, gltfpack) = GLTFPACK_RIGGED_FIGURE;
    let s = plain_chain_at(&scene, &[tris]);
    let mesh = &s.meshes[0];
    let lod = &mesh.lods[0].lod;
    assert_eq!(lod.triangle_count(), tris);
    for fraction in [0.125, 0.25, 0.5, 0.75] {
        let palette = palette_at(&scene, fraction).unwrap();
        let (r, p) = distances_percent(&mesh.geometry, lod, &palette);
        assert!(
            r <= gltfpack + 0.001,
            "rest {r:.3}% vs gltfpack {gltfpack}%"
        );
        assert!(
            p <= gltfpack + 0.001,
            "at {fraction} of the clip {p:.3}% vs gltfpack {gltfpack}%"
        );
    }
}

/// `--effort max`'s posed repair build (docs/lod.md, "How one step is built"): at 2,336 triangles
/// the step's own build was 0.325% from LOD 0 at half the clip, gltfpack's 0.319%; locking LOD 0's
/// vertices farthest from the build in its worst test or reference pose brings it to 0.161%.
#[test]
fn cesium_man_at_max_effort_at_least_as_close_as_gltfpack_posed() {
    let Some(scene) = load("gltf/CesiumMan.glb") else {
        return;
    };
    let palette = mid_palette(&scene).unwrap();
    let (tris, rest, posed) = GLTFPACK_CESIUM_MAN[0];
    let s = plain_chain_at(&scene, &[tris]);
    let mesh = &s.meshes[0];
    let lod = &mesh.lods[0].lod;
    assert_eq!(lod.triangle_count(), tris);
    let (r, p) = distances_percent(&mesh.geometry, lod, &palette);
    assert!(r <= rest, "rest {r:.3}% vs gltfpack {rest}%");
    assert!(p <= posed, "posed {p:.3}% vs gltfpack {posed}%");
}

#[test]
fn fox_at_least_as_close_as_gltfpack() {
    let Some(scene) = load("gltf/Fox.glb") else {
        return;
    };
    let palette = mid_palette(&scene).unwrap();
    let (tris, rest, posed) = GLTFPACK_FOX;
    let s = chain_at(&scene, &[tris]);
    let mesh = &s.meshes[0];
    let lod = &mesh.lods[0].lod;
    assert_eq!(lod.triangle_count(), tris);
    let (r, p) = distances_percent(&mesh.geometry, lod, &palette);
    assert!(r <= rest, "rest {r:.3}% vs gltfpack {rest}%");
    assert!(p <= posed, "posed {p:.3}% vs gltfpack {posed}%");
}

/// Skin awareness: at the same triangle counts, sinew's posed LODs stay closer to the posed LOD 0
/// than plain position-only meshoptimizer simplification of LOD 0 (no attributes, no skin, no
/// regularisation; the baseline is computed here, with the same meshoptimizer).
#[test]
fn cesium_man_posed_closer_than_skin_blind_simplification() {
    let Some(mut scene) = load("gltf/CesiumMan.glb") else {
        return;
    };
    generate_lods(&mut scene, &LodOptions::default()).unwrap();
    let palette = mid_palette(&scene).unwrap();
    let mesh = &scene.meshes[0];
    let base = &mesh.geometry;
    let positions: Vec<[f32; 3]> = base.positions.iter().map(|p| p.to_array()).collect();
    for g in &mesh.lods {
        let target = g.lod.indices.len();
        let indices = meshopt::simplify_decoder(
            &base.indices,
            &positions,
            target,
            1.0,
            meshopt::SimplifyOptions::None,
            None,
        );
        assert_eq!(indices.len(), target, "baseline reaches the same count");
        let blind = Lod {
            indices,
            ..base.clone()
        };
        let (_, sinew_posed) = distances_percent(base, &g.lod, &palette);
        let (_, blind_posed) = distances_percent(base, &blind, &palette);
        assert!(
            sinew_posed < blind_posed,
            "target {}: sinew posed {sinew_posed:.3}% vs skin-blind {blind_posed:.3}%",
            g.target_ratio
        );
    }
}

/// gltfpack 1.3.0 on zombie.ms3d (exported to glTF by `sinew export`): `-si 0.4986 -sa -noq` reaches
/// 361 triangles at 2.211% of the diagonal (`../shared/peers/lod_hausdorff.py`, docs/lod.md).
const GLTFPACK_ZOMBIE: (usize, f32) = (361, 2.211);

/// The repair step (docs/lod.md): zombie's LOD 1 lost a shape feature to the attribute terms
/// (2.725% at about gltfpack's count, farther than gltfpack); locking the far vertices and building
/// the step again keeps it. Checked at gltfpack's count and at the default 50%.
#[test]
fn zombie_at_least_as_close_as_gltfpack_at_rest() {
    let Some(scene) = load("ms3d/zombie.ms3d") else {
        return;
    };
    let (tris, rest) = GLTFPACK_ZOMBIE;
    let base = &scene.meshes[0].geometry;
    let diag = diagonal(&base.positions);
    let mut nominal = scene.clone();
    generate_lods(&mut nominal, &LodOptions::default()).unwrap();
    let matched = chain_at(&scene, &[tris]);
    for lod in [
        &matched.meshes[0].lods[0].lod,
        &nominal.meshes[0].lods[0].lod,
    ] {
        assert!(
            lod.triangle_count().abs_diff(tris) <= 8,
            "{}",
            lod.triangle_count()
        );
        let r =
            hausdorff(&base.positions, &base.indices, &lod.positions, &lod.indices) / diag * 100.0;
        assert!(
            r <= rest,
            "{} triangles: rest {r:.3}% vs gltfpack {rest}%",
            lod.triangle_count()
        );
    }
}

/// gltfpack 1.2 (`-si 0.5 -kn -noq`, the peers' build) at rest, % of the diagonal: (file,
/// triangles, distance). Light reductions where its 1% error limit keeps gltfpack to nearly free
/// collapses; sinew's own build spent a little shape on its attribute terms there until the
/// plain builds (docs/lod.md, "How one step is built"; `convert --effort max`).
const GLTFPACK_LIGHT: [(&str, usize, f32); 3] = [
    ("gltf/RiggedSimple.glb", 94, 0.364),
    ("smd/holy_grailref.smd", 852, 0.319),
    ("obj/spot.obj", 2928, 0.276),
];

/// gltfpack 1.2 with `-sa` (the peers' build, `-si 0.25 -sa -kn -noq`) at rest, % of the diagonal:
/// (file, mesh, triangles, distance). Counts its precise pass does not reach within its 1% limit,
/// which its sloppy pass (vertex clustering) reaches; sinew's plain builds end the same way
/// (`convert --effort max`, docs/lod.md). zombie at 178: gltfpack asked its clustering grid for 183
/// triangles and it gave 178; asked for 178, the same grid gives fewer, so sinew raises what it asks
/// for until the grid's count is as near the target as it gets without going over. twospheres at
/// 208 (two spheres, a material each): gltfpack clusters each sphere on a grid over its own box.
const GLTFPACK_AGGRESSIVE: [(&str, &str, usize, f32); 4] = [
    ("gltf/RiggedSimple.glb", "Cylinder", 44, 1.090),
    ("obj/spider.obj", "Zahn", 24, 2.850),
    ("ms3d/zombie.ms3d", "zombie", 178, 3.385),
    (
        "ms3d/twospheres_withmats.ms3d",
        "twospheres_withmats",
        208,
        1.145,
    ),
];

#[test]
fn aggressive_reductions_at_least_as_close_as_gltfpack_at_rest() {
    for (file, mesh, tris, rest) in GLTFPACK_AGGRESSIVE {
        let Some(mut scene) = load(file) else {
            return;
        };
        scene.meshes.retain(|m| m.name == mesh);
        assert_eq!(scene.meshes.len(), 1, "{file}: mesh {mesh}");
        let (reached, r) = plain_rest_at(&scene, tris);
        assert!(reached <= tris, "{file} {mesh}: {reached}");
        assert!(
            r <= rest + 0.001,
            "{file} {mesh}: {tris} triangles: rest {r:.3}% vs gltfpack -sa {rest}%"
        );
    }
}

/// UVs that no texture reads are not seams (docs/lod.md, "UVs no texture reads"): jeep1's material
/// names a texture the corpus does not have, and its glTF export (`sinew export`) carries none, so
/// gltfpack drops its texture coordinates before simplifying: `-si 0.25 -sa -kn -noq` on the export
/// gives 458 triangles at 8.905% of the diagonal, where sinew, holding the UV seams, came to 8.980
/// at 415 triangles. Without the texture, `--effort max`'s chain at 458 is closer than gltfpack;
/// with it, the default chain keeps every UV chart whole (no triangle joins two), and without it
/// the default chain joins charts and is closer.
#[test]
fn uv_seams_hold_only_where_a_texture_reads_them() {
    let Some(textured) = load("ms3d/jeep1.ms3d") else {
        return;
    };
    assert!(textured.materials.iter().all(|m| m.texture.is_some()));
    let mut untextured = textured.clone();
    for m in &mut untextured.materials {
        m.texture = None;
    }
    let (reached, r) = plain_rest_at(&untextured, 458);
    assert!(reached <= 458, "{reached}");
    assert!(
        r <= 8.905,
        "untextured jeep1 at 458: rest {r:.3}% vs gltfpack -sa 8.905%"
    );
    let (held, opened) = (chain_at(&textured, &[458]), chain_at(&untextured, &[458]));
    let base = &held.meshes[0].geometry;
    let joined = |s: &Scene| uv_charts_joined("jeep1", base, &s.meshes[0].lods[0].lod);
    assert_eq!(joined(&held), 0);
    assert!(joined(&opened) > 0);
    let ((held_tris, held_rest), (opened_tris, opened_rest)) = (rest_at(&held), rest_at(&opened));
    // The seams held stop the textured chain above the target (472 triangles).
    assert!(opened_tris <= 458 + 7 && opened_tris <= held_tris);
    assert!(
        opened_rest < held_rest,
        "untextured {opened_rest:.3}% at {opened_tris} vs textured {held_rest:.3}% at {held_tris}"
    );
    // `--lod-keep-uv-seams`: the untextured mesh's seams hold as the textured one's.
    let mut kept = untextured.clone();
    let options = LodOptions {
        ratios: vec![458.0 / kept.meshes[0].geometry.triangle_count() as f32],
        keep_uv_seams: true,
        ..Default::default()
    };
    generate_lods_tuned(&mut kept, &options, &LodTuning::default()).unwrap();
    assert_eq!(joined(&kept), 0);
    assert_eq!(kept.meshes[0].lods[0].lod, held.meshes[0].lods[0].lod);
}

#[test]
fn light_reductions_at_least_as_close_as_gltfpack_at_rest() {
    for (file, tris, rest) in GLTFPACK_LIGHT {
        let Some(scene) = load(file) else {
            return;
        };
        let (reached, r) = plain_rest_at(&scene, tris);
        assert_eq!(reached, tris, "{file}");
        assert!(
            r <= rest + 0.001,
            "{file}: {tris} triangles: rest {r:.3}% vs gltfpack {rest}%"
        );
    }
}

/// The default builds small meshes the plain ways too (`LodTuning::plain_work_bound`): where the
/// work is within the bound the default chain is as close as gltfpack at its counts (the peers'
/// build, `-si 0.5 -kn -noq`, or `-sa` for spider's tooth, at rest, % of the diagonal; without the
/// plain builds 0.399, 0.390, 1.435 and 3.946); above it a static mesh gets the positions-only
/// build alone and a skinned one the chain without them.
#[test]
fn default_builds_small_meshes_the_plain_ways_too() {
    let within: [(&str, Option<&str>, usize, f32); 4] = [
        ("gltf/RiggedSimple.glb", None, 94, 0.364),
        ("smd/holy_grailref.smd", None, 852, 0.319),
        ("obj/regr01.obj", Some("Raft-l-01"), 76, 1.080),
        ("obj/spider.obj", Some("Zahn"), 24, 2.850),
    ];
    for (file, mesh, tris, rest) in within {
        let Some(mut scene) = load(file) else {
            return;
        };
        if let Some(name) = mesh {
            scene.meshes.retain(|m| m.name == name);
        }
        assert_eq!(scene.meshes.len(), 1, "{file}");
        let skeleton = scene.skeleton.as_ref();
        let motion = scene_motion(&scene.clips, skeleton);
        let work = plain_work(&scene.meshes[0].geometry, skeleton, &motion.poses);
        assert!(work <= PLAIN_WORK_BOUND, "{file}: work {work}");
        let (reached, r) = rest_at(&chain_at(&scene, &[tris]));
        assert!(reached <= tris, "{file}: {reached}");
        assert!(
            r <= rest + 0.001,
            "{file}: {tris} triangles: rest {r:.3}% vs gltfpack {rest}%"
        );
    }
    // spot: 5,856 triangles, static: 46,848 units of work, above the bound: the positions-only
    // build alone runs, and is as close as gltfpack (the chain without it: 0.298%).
    let Some(scene) = load("obj/spot.obj") else {
        return;
    };
    let work = plain_work(&scene.meshes[0].geometry, None, &[]);
    assert_eq!(work, 5_856 * 8);
    let without = LodTuning {
        plain_work_bound: 0,
        ..LodTuning::default()
    };
    let (a, b) = (
        chain_at(&scene, &[2928]),
        chain_tuned_at(&scene, &[2928], &without),
    );
    let ((reached, r), (_, r_without)) = (rest_at(&a), rest_at(&b));
    assert_eq!(reached, 2928);
    assert!(
        r <= 0.276 + 0.001 && r < r_without,
        "spot: {r:.3}% (without the plain builds {r_without:.3}%)"
    );
    // A skinned mesh above the bound (CesiumMan: 4,672 triangles under 2 test poses and 8
    // reference poses, 84,096 units) gets none, but its repair is checked in the reference poses
    // (docs/lod.md, "A posed check without a grid per pose"): at 2,336 triangles its LOD differs
    // from the chain with neither, the same at rest and closer at half the clip, where the
    // chain with neither is farther than gltfpack (0.325% against 0.319%).
    let Some(scene) = load("gltf/CesiumMan.glb") else {
        return;
    };
    let motion = scene_motion(&scene.clips, scene.skeleton.as_ref());
    let work = plain_work(
        &scene.meshes[0].geometry,
        scene.skeleton.as_ref(),
        &motion.poses,
    );
    assert_eq!(work, 4_672 * 18);
    let (a, b) = (
        chain_at(&scene, &[2336]),
        chain_tuned_at(&scene, &[2336], &without),
    );
    let (checked, unchecked) = (&a.meshes[0].lods[0].lod, &b.meshes[0].lods[0].lod);
    assert_ne!(checked, unchecked);
    let palette = mid_palette(&scene).unwrap();
    let base = &scene.meshes[0].geometry;
    let ((r, p), (r0, p0)) = (
        distances_percent(base, checked, &palette),
        distances_percent(base, unchecked, &palette),
    );
    let (_, _, gltfpack) = GLTFPACK_CESIUM_MAN[0];
    assert!(r <= r0, "rest {r:.4}% vs {r0:.4}% unchecked");
    assert!(
        p <= gltfpack && p0 > gltfpack,
        "half the clip: {p:.4}%, unchecked {p0:.4}%, gltfpack {gltfpack}%"
    );
}

/// `--effort max`'s reference poses: at most 16 in all, the same number from each clip (16 / 3 = 5
/// for Fox's three), each a pose of its clip (the runtime's sampler) at the middle of one of 64
/// equal parts of its duration, in time order, no two the same.
#[test]
fn reference_poses_are_poses_of_each_clip_at_the_middles_of_64_parts() {
    let Some(scene) = load("gltf/Fox.glb") else {
        return;
    };
    let skeleton = scene.skeleton.as_ref().unwrap();
    assert_eq!(scene.clips.len(), 3);
    let poses = reference_poses(&scene.clips, skeleton);
    assert_eq!(poses.len(), 15);
    for (c, clip) in scene.clips.iter().enumerate() {
        let clip = clip.to_clip().unwrap();
        let binding = ClipBinding::new(&clip, skeleton);
        let candidates: Vec<_> = (0..64)
            .map(|k| {
                let mut locals = skeleton.bind_local().to_vec();
                let at = clip.duration() * (k as f32 + 0.5) / 64.0;
                Sampler::new()
                    .sample(&clip, &binding, skeleton, at, &mut locals)
                    .unwrap();
                locals
            })
            .collect();
        let at: Vec<usize> = poses[5 * c..5 * c + 5]
            .iter()
            .map(|p| {
                candidates
                    .iter()
                    .position(|q| q == p)
                    .unwrap_or_else(|| panic!("clip {c}: a pose not sampled at a middle"))
            })
            .collect();
        assert!(at.windows(2).all(|w| w[0] < w[1]), "clip {c}: {at:?}");
    }
    let one = reference_poses(&scene.clips[..1], skeleton);
    assert_eq!(one.len(), 8);
}

/// gltfpack 1.2's `-si 0.5 -kn -noq` on ninja.ms3d's export stops at 675 of 1,007 triangles (its
/// 1% error limit): rest and at 1/8, 1/4, 1/2 and 3/4 of the clip, % of the diagonal
/// (tools/lod-compare.sh, docs/lod.md). These are the other tool's figures, not sinew's.
const GLTFPACK_NINJA: (usize, f32, [f32; 4]) = (675, 0.7022, [2.4623, 2.8352, 1.2032, 2.4310]);

/// At half its clip ninja passes through a pose for about a fiftieth of it where the chain's own
/// build at 675 triangles was 1.212% from LOD 0 (gltfpack 1.203%), 0.57-0.72% a hundredth of the
/// clip to either side: reference poses at fixed times (the middles of eighths) passed it by.
/// Picked farthest first, one of them is in it, and the posed repair build started there is kept
/// (no farther at rest or in the test poses, closer in the reference poses): docs/lod.md,
/// session 32. With the plain builds (`--effort max`; the default builds ninja.ms3d's mesh the
/// plain ways only where its clips' share allows, which its export's denser keys do).
#[test]
fn ninja_at_gltfpacks_count_at_max_effort_at_least_as_close_in_its_clip() {
    let Some(scene) = load("ms3d/ninja.ms3d") else {
        return;
    };
    let (tris, rest, posed) = GLTFPACK_NINJA;
    let s = plain_chain_at(&scene, &[tris]);
    let mesh = &s.meshes[0];
    let lod = &mesh.lods[0].lod;
    assert_eq!(lod.triangle_count(), tris);
    for (fraction, gltfpack) in [0.125, 0.25, 0.5, 0.75].into_iter().zip(posed) {
        let palette = palette_at(&scene, fraction).unwrap();
        let (r, p) = distances_percent(&mesh.geometry, lod, &palette);
        assert!(r <= rest, "rest {r:.4}% vs gltfpack {rest}%");
        assert!(
            p <= gltfpack,
            "at {fraction} of the clip {p:.4}% vs gltfpack {gltfpack}%"
        );
    }
}

/// `convert` makes the reference poses only when some skinned mesh's plain builds use them
/// (`scene_motion_for`); the LODs are those made with the poses always there (`scene_motion`), at
/// both efforts, on meshes with and without plain builds by default (CesiumMan's is beyond the
/// bound and the clip's share; ninja.ms3d's too; Fox's is beyond it; RiggedFigure's within it):
/// those beyond are checked in the reference poses by default (`PlainSet::PosedCheck`), so every
/// one of them makes the poses but with the bound 0 (no plain build, no check).
#[test]
fn reference_poses_made_only_when_used_give_the_same_lods() {
    for file in [
        "gltf/CesiumMan.glb",
        "ms3d/ninja.ms3d",
        "gltf/Fox.glb",
        "gltf/RiggedFigure.glb",
    ] {
        let Some(scene) = load(file) else {
            return;
        };
        let skeleton = scene.skeleton.as_ref();
        for tuning in [
            LodTuning::default(),
            LodTuning {
                plain_candidate: true,
                ..LodTuning::default()
            },
            LodTuning {
                plain_work_bound: 0,
                ..LodTuning::default()
            },
        ] {
            let lazy = sinew_pipeline::lod::scene_motion_for(
                &scene.clips,
                skeleton,
                &scene.meshes,
                &tuning,
            );
            let eager = scene_motion(&scene.clips, skeleton);
            assert_eq!(lazy.pose_count, eager.poses.len(), "{file}");
            assert_eq!(lazy.joint_keys, eager.joint_keys, "{file}");
            let made = !lazy.poses.is_empty();
            let used = tuning.plain_work_bound > 0;
            assert_eq!(made, used, "{file}, {tuning:?}");
            if made {
                assert_eq!(lazy.poses, eager.poses, "{file}");
            }
            let options = LodOptions::default();
            let mut a = scene.clone();
            let mut b = scene.clone();
            sinew_pipeline::lod::generate_mesh_lods(
                &mut a.meshes,
                skeleton,
                &scene.materials,
                &options,
                &tuning,
                &lazy,
            )
            .unwrap();
            sinew_pipeline::lod::generate_mesh_lods(
                &mut b.meshes,
                skeleton,
                &scene.materials,
                &options,
                &tuning,
                &eager,
            )
            .unwrap();
            assert_eq!(a.meshes, b.meshes, "{file}, {tuning:?}");
        }
    }
}
