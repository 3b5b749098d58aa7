//! Level-of-detail generation for (skinned) meshes, on meshoptimizer.
//!
//! **What each level is for** (docs/lod.md, "What LOD 1 and LOD 2 are for"): LOD `k` has a triangle
//! budget, `ratios[k]` of LOD 0's triangles (default half and a quarter), and reports the error it
//! reached; the runtime picks a level by that error and the object's size on screen
//! (`sinew_core::select_lod`). No error limit applies unless one is given. A level that cannot
//! remove at least half of the triangles it asks of the level before it (seams and locks leave
//! nothing to collapse, or the given error limit stops it) is not written: the mesh's
//! `lods_not_built` says which and why, and no later level is built either.
//!
//! Each LOD is simplified from the previous one (meshoptimizer's recommendation for chains), the
//! whole mesh in one call (`step`), with:
//! - attribute-aware collapses: normals and UVs weigh in the collapse cost; UVs that no texture
//!   reads (no range's material has one) neither weigh nor make seams: copies of a vertex that
//!   differ only in UV are welded, as gltfpack drops unused texture coordinates;
//! - skin awareness: each vertex also carries its displacement under two fixed test poses of the
//!   skeleton (every joint turned 25 degrees about its local X, then about its local Z), weighted
//!   above the normals. Two vertices whose influences differ move apart under those poses, so
//!   collapsing one into the other costs what it would tear at runtime: bone boundaries are kept where
//!   they matter and cheap where they do not;
//! - material borders as seams: each vertex belongs to one material range, so meshoptimizer keeps a
//!   border closed and moves both sides of it together;
//! - meshoptimizer's `Permissive` option with every vertex protected except those on hard normal
//!   edges: vertices that share a position but differ only in their normal may be collapsed across,
//!   with the normal difference counted as attribute error, while UV seams, skin seams and everything
//!   else keep meshoptimizer's usual rules;
//! - meshoptimizer's `RegularizeLight` option, which its author recommends for deforming meshes;
//! - `Priority` on the extreme vertices of every connected part, whatever its size (`lod_parts`);
//! - a repair build: LOD 0's farthest vertices from the step's result are locked, each with one
//!   triangle around it, the step is built again and the closer build is kept (`measure`);
//! - on a mesh whose plain builds cost little ([`plain_work`] within
//!   `LodTuning::plain_work_bound`, or within the share of a file's clips: [`SceneMotion`]), and
//!   on every mesh with `LodTuning::plain_candidate` (`convert --effort max`), six plain
//!   builds of the same target from LOD 0 as it came in (gltfpack's `-si` way, on positions
//!   alone, gltfpack's `-si -sa` way with its sloppy pass, that sloppy pass on the part's
//!   vertices alone asked for as many triangles as its grid gives within the target, and
//!   gltfpack's `-si` and `-si -sa` on each material range alone as on a glTF export's
//!   primitives, each range's limit 1% of the scene's largest range: `Step::plains`; for a mesh
//!   whose UVs no texture reads, these six from LOD 0 welded without its UVs and six more with
//!   their seams held), each kept instead when it has no more triangles, is closer to LOD 0 at
//!   rest (LOD 0's vertices, centroids and edge midpoints) and under the test poses, and is no
//!   farther under poses sampled from the scene's clips ([`reference_poses`]) than the best
//!   build's farthest distance at rest, in the test poses and in those poses (ties keep the
//!   step's own build); then a posed repair build of the best one (LOD 0's farthest vertices in
//!   the pose where it is farthest locked, kept on the same terms);
//! - on a static mesh above that bound, the positions-only plain build alone, compared at rest
//!   (one simplification and one measurement: docs/lod.md, "Static meshes beyond the bound");
//! - on a skinned mesh above it, a posed check of the step's build: LOD 0's points measured in
//!   each reference pose against the build's triangle each one's rest search ended on (an upper
//!   bound of its distance, no grid per pose); where that is farther than at rest, those
//!   farthest in the worst pose are locked too and the step built again beside the repair, kept
//!   when no farther at rest and closer at rest or by that bound (docs/lod.md, "A posed check
//!   without a grid per pose").
//!
//! Simplification only ever selects among existing vertices, so skin weights travel with their vertices
//! unchanged; the lowest LOD may be cut to fewer influences, renormalised. Every LOD's index order is
//! then optimised for the vertex cache and its vertices reordered for fetch.
//!
//! meshoptimizer passes indices to C++ unchecked, so every buffer is validated before each call.

mod buffers;
mod measure;
mod motion;
mod options;
mod step;
mod weld;

use crate::surface::{sample_points, used_vertices, TriangleGrid};
pub use buffers::{limit_influences, validate_lod};
use measure::{
    distinct, far_vertices, farthest_pose, lost_below, measure, measure_below, next_above,
    posed_far_vertices, repair_locks, with_points, Measured,
};
pub use measure::{largest_range_scale, mesh_scale};
pub use motion::{
    clip_joint_keys, plain_work, reference_pose_count, reference_poses, scene_motion,
    scene_motion_for, SceneMotion,
};
use motion::{plain_builds_of, PlainSet};
pub use options::{LodError, LodOptions};
use rayon::prelude::*;
use sinew_core::glam::Vec3;
use sinew_core::{Lod, Skeleton, Transform, MAX_INFLUENCES};
use sinew_scene::{GeneratedLod, Material, Mesh, NotBuiltLod, NotBuiltReason, Scene};
use step::{first_use_remap, optimize_ranges, Anchors, Candidate, Step};
pub use step::{LodTuning, PLAIN_WORK_BOUND};
use weld::{flat_soup, is_flat_soup, merge_uv_mirrors, split_shared, split_uv_mirrors, weld};

/// A step's source under the test poses and under the reference poses (positions per pose).
type PosedSource = (Vec<Vec<Vec3>>, Vec<Vec<Vec3>>);

/// A LOD's reported error is at least its measured distance to LOD 0 times this margin: the larger
/// of the distance from LOD 0's vertices to the LOD's surface and from the LOD's vertices, centroids
/// and edge midpoints to LOD 0's surface. The margin covers what a denser measurement finds between
/// those samples (docs/lod.md: on the corpus and fixtures, LOD 0's centroids and midpoints added at
/// most 4%, and 20,000 random surface points at most 3%).
const MEASURE_MARGIN: f32 = 1.1;

/// Optimises LOD 0 in place for the vertex cache and vertex fetch, keeping `source_vertex` in step.
pub fn optimize_base(mesh: &mut Mesh) -> Result<(), LodError> {
    validate_lod(&mesh.geometry).map_err(|problem| LodError::BadMesh {
        mesh: mesh.name.clone(),
        problem,
    })?;
    let g = &mesh.geometry;
    let mut indices = g.indices.clone();
    optimize_ranges(&mut indices, &g.submeshes, g.positions.len());
    // Unused vertices stay, after the used ones, so the map back to the source stays complete.
    let remap = first_use_remap(&indices, g.positions.len());
    let mut next = remap.iter().filter(|&&r| r != u32::MAX).count() as u32;
    let remap: Vec<u32> = remap
        .iter()
        .map(|&r| {
            if r == u32::MAX {
                next += 1;
                next - 1
            } else {
                r
            }
        })
        .collect();
    let n = g.positions.len();
    let mut order = vec![0u32; n];
    for (old, &new) in remap.iter().enumerate() {
        order[new as usize] = old as u32;
    }
    let g = &mut mesh.geometry;
    fn apply<T: Copy>(v: &mut Vec<T>, order: &[u32]) {
        if !v.is_empty() {
            *v = order.iter().map(|&o| v[o as usize]).collect();
        }
    }
    apply(&mut g.positions, &order);
    apply(&mut g.normals, &order);
    apply(&mut g.uvs, &order);
    apply(&mut g.joints, &order);
    apply(&mut g.weights, &order);
    if mesh.source_vertex.len() == n {
        apply(&mut mesh.source_vertex, &order);
    }
    for i in &mut indices {
        *i = remap[*i as usize];
    }
    g.indices = indices;
    Ok(())
}

/// A mesh's LOD chain: the levels written, most detailed first, and the levels asked for that were
/// not written (each after the last written one).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LodChain {
    /// The generated LODs.
    pub lods: Vec<GeneratedLod>,
    /// The levels not built, and why.
    pub not_built: Vec<NotBuiltLod>,
}

/// Builds the LOD chain of one mesh from its geometry.
pub fn build_lods(
    mesh: &Mesh,
    skeleton: Option<&Skeleton>,
    options: &LodOptions,
) -> Result<LodChain, LodError> {
    build_lods_tuned(mesh, skeleton, options, &LodTuning::default())
}

/// [`build_lods`] with explicit quality knobs. Without the scene's materials, the mesh's UVs are
/// taken to be read by a texture (their seams hold); [`generate_lods`] knows.
pub fn build_lods_tuned(
    mesh: &Mesh,
    skeleton: Option<&Skeleton>,
    options: &LodOptions,
    tuning: &LodTuning,
) -> Result<LodChain, LodError> {
    let plain = plain_builds_of(
        std::slice::from_ref(mesh),
        skeleton,
        tuning,
        &SceneMotion::default(),
    );
    build_lods_timed(
        mesh,
        matches!(plain[0], PlainSet::All | PlainSet::Positions).then_some(&mesh.geometry),
        plain[0],
        skeleton,
        true,
        tuning
            .scene_scale
            .unwrap_or_else(|| largest_range_scale(mesh)),
        options,
        tuning,
        &[],
        &mut Vec::new(),
    )
}

/// [`build_lods_tuned`], pushing the wall time in seconds of each level attempted (with its
/// repair and measurement; a level not built counts when simplification was tried) onto
/// `seconds`. `plain_input`: LOD 0 as it came in, where plain builds run; `plain`: which of
/// them, or the posed check alone ([`motion::PlainSet`]).
#[allow(clippy::too_many_arguments)]
fn build_lods_timed(
    mesh: &Mesh,
    plain_input: Option<&Lod>,
    plain: PlainSet,
    skeleton: Option<&Skeleton>,
    uvs_read: bool,
    scene_scale: f32,
    options: &LodOptions,
    tuning: &LodTuning,
    reference: &[Vec<Transform>],
    seconds: &mut Vec<f64>,
) -> Result<LodChain, LodError> {
    options.validate()?;
    let positions_only = plain == PlainSet::Positions;
    // UVs that no texture reads are not seams: vertices that differ only in UV are welded (each
    // keeps its first copy's UV) and UVs do not weigh in the collapse cost, as gltfpack drops
    // the texture coordinates no material uses before it simplifies.
    let untextured = LodTuning {
        uv_weight: 0.0,
        ..*tuning
    };
    let tuning = if uvs_read { tuning } else { &untextured };
    validate_lod(&mesh.geometry).map_err(|problem| LodError::BadMesh {
        mesh: mesh.name.clone(),
        problem,
    })?;
    if let Some(s) = skeleton {
        if mesh
            .geometry
            .joints
            .iter()
            .flatten()
            .any(|&j| j as usize >= s.len())
        {
            return Err(LodError::BadMesh {
                mesh: mesh.name.clone(),
                problem: format!("joint index past the skeleton's {} joints", s.len()),
            });
        }
    }
    let scale = mesh_scale(mesh);
    let base_tris = mesh.geometry.triangle_count();
    // Part extremes are found once, on LOD 0, and kept through the chain: a part simplified to a
    // few triangles in one step must keep its reach in the next.
    let mut keep = Anchors::default();
    if tuning.anchor_part_extremes {
        let g = &mesh.geometry;
        keep.soft = crate::lod_parts::part_extremes(&g.positions, &g.indices)
            .into_iter()
            .zip(&g.positions)
            .filter(|(e, _)| *e)
            .map(|(_, p)| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .collect();
        keep.soft.sort_unstable();
        keep.soft.dedup();
    }
    // The measured distance to LOD 0 is a floor under each reported error (see `MEASURE_MARGIN`)
    // and decides between a step's builds. LOD 0's vertices only: what simplification loses shows
    // at the vertices it removed (on the corpus and fixtures the centroids and edge midpoints of
    // LOD 0 add at most 4%; the margin covers it).
    let base_grid = TriangleGrid::new(&mesh.geometry.positions, &mesh.geometry.indices);
    // Each with the vertex behind it, which the posed check skins.
    let base_vertices = measure::distinct_used(&mesh.geometry.positions, &mesh.geometry.indices);
    let base_points: Vec<Vec3> = base_vertices
        .iter()
        .map(|&v| mesh.geometry.positions[v as usize])
        .collect();
    // The posed check of the step's build (`PlainSet::PosedCheck`): LOD 0 under the reference
    // poses.
    let check_base = if plain == PlainSet::PosedCheck {
        step::reference_positions(&mesh.geometry, skeleton, reference)
    } else {
        Vec::new()
    };
    let checked = !check_base.is_empty();
    // The plain builds (`Step::plain`) of every level, when they run, start from LOD 0 in the
    // order it came in (`plain_input`), welded as each step's source is.
    let plain_flat = plain_input.is_some_and(is_flat_soup);
    // meshoptimizer squares the limit: the largest finite value stays finite.
    let plain_budget = options.max_error.unwrap_or(f32::MAX.sqrt());
    // Without a texture reading the UVs, the plain builds are made from two sources: welded
    // without UVs, as gltfpack (which drops texture coordinates no material uses) builds, and with
    // them, their seams held: measured on the corpus, each is the closer on some meshes (docs/lod.md).
    // Where UVs are kept, each source split as gltfpack splits a primitive's mirrored UVs
    // (`split_uv_mirrors`), with each copy's original.
    let mut plain_sources: Vec<Lod> = Vec::new();
    let mut plain_copies: Vec<Vec<u32>> = Vec::new();
    if let Some(input) = plain_input {
        let split = split_shared(input);
        let input = split.as_ref().unwrap_or(input);
        // The positions-only build alone: from the first source only (gltfpack's).
        let uvs_ignored: &[bool] = match (uvs_read, positions_only) {
            (true, _) => &[false],
            (false, true) => &[true],
            (false, false) => &[true, false],
        };
        for &ignore_uvs in uvs_ignored {
            let welded = weld(input, plain_flat, ignore_uvs);
            validate_lod(&welded).map_err(|problem| LodError::BadMesh {
                mesh: mesh.name.clone(),
                problem: format!("after welding: {problem}"),
            })?;
            let (source, copy_of) = match split_uv_mirrors(&welded).filter(|_| !ignore_uvs) {
                Some(split) => split,
                None => (welded, Vec::new()),
            };
            plain_sources.push(source);
            plain_copies.push(copy_of);
        }
    }
    // A plain build on its source's vertices before the mirror split.
    let merged = |from: &Step, mut built: Candidate| {
        let i = plain_sources
            .iter()
            .position(|s| std::ptr::eq(s, from.source()));
        if let Some(copy_of) = i.and_then(|i| plain_copies.get(i)) {
            let vertex_count = from.source().positions.len();
            merge_uv_mirrors(
                (&mut built.indices, &mut built.submeshes),
                vertex_count,
                copy_of,
            );
        }
        built
    };
    // And from the second level on, sinew's own step from LOD 0 (the plain builds' first source,
    // welded as the chain's steps are): a LOD 1 closest in itself can leave the next level worse
    // off than a build from LOD 0 would be.
    // (The positions-only build alone where that is all that runs: `PlainSet::Positions`.)
    let plains: Vec<Step> = if positions_only {
        plain_sources
            .iter()
            .map(|source| Step::positions_plain(source, tuning))
            .collect()
    } else {
        plain_sources
            .iter()
            .flat_map(|source| Step::plains(source, tuning, scene_scale))
            .chain(
                plain_sources
                    .first()
                    .map(|s| Step::new(s, skeleton, tuning)),
            )
            .collect()
    };
    // What a step's builds are compared by: LOD 0's distinct vertices under the test poses
    // (skinned meshes) and its vertices, centroids and edge midpoints at rest; then LOD 0's
    // vertices under the reference poses. The plain builds' source under the same poses.
    let points_of = |poses: &[Vec<Vec3>]| -> Vec<Vec<Vec3>> {
        poses
            .iter()
            .map(|p| distinct(&used_vertices(p, &mesh.geometry.indices)))
            .collect()
    };
    let (base_posed, base_reference) = if plain_sources.is_empty() {
        Default::default()
    } else {
        (
            step::test_poses(&mesh.geometry, skeleton),
            step::reference_positions(&mesh.geometry, skeleton, reference),
        )
    };
    // Each plain source under the test poses and under the reference poses.
    let plain_posed: Vec<PosedSource> = plain_sources
        .iter()
        .map(|source| {
            (
                step::test_poses(source, skeleton),
                step::reference_positions(source, skeleton, reference),
            )
        })
        .collect();
    let (posed_points, reference_points) = (points_of(&base_posed), points_of(&base_reference));
    // LOD 0's vertices that triangles use, for the posed repair build.
    let base_used: Vec<u32> = if !plain_sources.is_empty() {
        let mut used = mesh.geometry.indices.clone();
        used.sort_unstable();
        used.dedup();
        used
    } else {
        Vec::new()
    };
    let base_dense = if plain_input.is_some() {
        // Centroids and edge midpoints (`sample_points` puts them first): the vertices are in
        // `base_points`.
        let g = &mesh.geometry;
        let mut points = sample_points(&g.positions, &g.indices);
        points.truncate(g.indices.len() / 3 * 4);
        distinct(&points)
    } else {
        Vec::new()
    };
    // The target is met when within one triangle per material range of it.
    let slack = mesh.geometry.submeshes.len().max(1);
    let mut chain = LodChain::default();
    let mut previous = mesh.geometry.clone();
    let mut previous_tris = base_tris;
    let mut accumulated = 0.0f32;
    let mut started = std::time::Instant::now();
    for (k, &ratio) in options.ratios.iter().enumerate() {
        let target = ((base_tris as f64) * ratio as f64).round() as usize;
        let not_built = |reached, reason| NotBuiltLod {
            level: k + 1,
            target_ratio: ratio,
            previous_triangles: previous_tris,
            reached_triangles: reached,
            reason,
        };
        if !chain.not_built.is_empty() {
            chain
                .not_built
                .push(not_built(None, NotBuiltReason::PreviousNotBuilt));
            continue;
        }
        let budget = match options.max_error {
            Some(e) if tuning.chain => (e - accumulated).max(0.0),
            Some(e) => e,
            // meshoptimizer squares the limit: the largest finite value stays finite.
            None => f32::MAX.sqrt(),
        };
        let flat = is_flat_soup(&previous);
        let welded = match split_shared(&previous) {
            Some(split) => weld(&split, flat, !uvs_read),
            None => weld(&previous, flat, !uvs_read),
        };
        validate_lod(&welded).map_err(|problem| LodError::BadMesh {
            mesh: mesh.name.clone(),
            problem: format!("after welding: {problem}"),
        })?;
        let step = Step::new(&welded, skeleton, tuning);
        let check_source = if checked {
            step::reference_positions(&welded, skeleton, reference)
        } else {
            Vec::new()
        };
        // The largest distance of LOD 0's points from a build under the reference poses, as the
        // posed check bounds it, and that pose's farthest points.
        let posed_check = |m: &Measured, indices: &[u32]| {
            measure::hinted_posed_far(
                m,
                (&base_vertices, &base_points),
                indices,
                (&check_base, &check_source),
            )
        };
        let (step_posed, step_reference) = if plains.is_empty() {
            Default::default()
        } else {
            (
                step::test_poses(&welded, skeleton),
                step::reference_positions(&welded, skeleton, reference),
            )
        };
        // One build of the step and its repair build; the closer with no more triangles.
        let build_current = |keep: &Anchors| {
            let built = step.run(target, budget, keep);
            let m = measure(&welded.positions, &built.indices, &base_points, &base_grid);
            let most = built.indices.len().max(3 * (target + slack));
            // Repair: the attribute terms (normals, UVs, test poses) weigh in meshoptimizer's
            // error and its quadrics let a thin part's tip slide along the part at little cost, so
            // a step can remove a shape feature cheaply. When LOD 0's farthest vertices decide the
            // distance, they are locked (each with a triangle around it) and the step is built
            // again; the closer build with no more triangles is kept.
            let rest_far = if tuning.repair_far_vertices && m.lost > m.added {
                far_vertices(&m, &base_points)
            } else {
                Vec::new()
            };
            let rest_repair = || {
                if rest_far.is_empty() {
                    return None;
                }
                let mut more = keep.clone();
                more.hard = repair_locks(&welded, &rest_far);
                let again = step.run(target, budget, &more);
                if again.indices.len() > most {
                    return None;
                }
                measure_below(
                    &welded.positions,
                    &again.indices,
                    &base_points,
                    &base_grid,
                    m.distance(),
                )
                .map(|m2| (again, m2))
            };
            // Beyond the plain builds' bound, on a skinned mesh (`PlainSet::PosedCheck`): the
            // build is checked in the reference poses by the bound of `measure::hinted_posed_far`
            // and, where that is larger than its rest distance, built again beside the rest
            // repair (on another core when one is free) with LOD 0's points farthest in the pose
            // where it is largest locked too (and the rest repair's). That build is kept instead
            // of the rest repair's choice when no farther at rest (the bound is loose where a
            // point's rest triangle is not its nearest in the pose: it must not trade rest away),
            // closer at rest or by the bound, and no farther by the larger of the two (docs/lod.md,
            // "A posed check without a grid per pose").
            let posed = (checked && tuning.repair_far_vertices)
                .then(|| posed_check(&m, &built.indices))
                .filter(|(bound, far)| !far.is_empty() && *bound > m.distance());
            let posed_repair = || {
                let (_, far) = posed.as_ref()?;
                let mut locked = rest_far.clone();
                locked.extend_from_slice(far);
                let mut more = keep.clone();
                more.hard = repair_locks(&welded, &locked);
                let again = step.run(target, budget, &more);
                if again.indices.len() > most {
                    return None;
                }
                // No farther at rest than the first build, at least (the rest repair's choice is
                // no farther than it either).
                let m2 = measure_below(
                    &welded.positions,
                    &again.indices,
                    &base_points,
                    &base_grid,
                    next_above(m.distance()),
                )?;
                let (bound, _) = posed_check(&m2, &again.indices);
                Some((again, m2, bound))
            };
            let (repaired, posed_repaired) = rayon::join(rest_repair, posed_repair);
            let first_bound = posed.as_ref().map_or(0.0, |p| p.0);
            let rest_kept = repaired.is_some();
            let mut best = repaired.unwrap_or((built, m));
            if let Some((again, m2, bound2)) = posed_repaired {
                let bound = if rest_kept {
                    posed_check(&best.1, &best.0.indices).0
                } else {
                    first_bound
                };
                let (rest, rest2) = (best.1.distance(), m2.distance());
                if rest2 <= rest
                    && (rest2 < rest || bound2 < bound)
                    && rest2.max(bound2) <= rest.max(bound)
                {
                    best = (again, m2);
                }
            }
            best
        };
        // The larger of a build's distances to LOD 0 at rest (`m`, with LOD 0's centroids and
        // edge midpoints measured too) and of LOD 0's vertices from the build under the test
        // poses, model units;
        // `None` as soon as it is known to be at least `limit`. `from`: the step the build's
        // indices refer to.
        // A step's source under the test poses and under the reference poses: the step's own,
        // then the plain builds'.
        let posed_of = |from: &Step| -> (&Vec<Vec<Vec3>>, &Vec<Vec<Vec3>>) {
            plain_sources
                .iter()
                .position(|s| std::ptr::eq(s, from.source()))
                .map_or((&step_posed, &step_reference), |i| {
                    (&plain_posed[i].0, &plain_posed[i].1)
                })
        };
        let score = |from: &Step, indices: &[u32], m: &Measured, limit: f32| -> Option<f32> {
            let mut worst = 0.0f32;
            let mut hints = Vec::new();
            for (positions, points) in posed_of(from).0.iter().zip(&posed_points) {
                worst = lost_below(positions, indices, points, (worst, limit), &mut hints)?;
            }
            worst = worst.max(with_points(m, &base_dense, limit)?);
            (worst < limit).then_some(worst)
        };
        // The distance of LOD 0's vertices from a build (`indices` into a source under the test
        // poses, `posed`, and the reference poses, `reference`) under each pose, test poses first;
        // where a pose is no farther than an earlier one of its kind (test or reference), the
        // largest distance so far instead (measured only until known: the largest of each kind and
        // the first pose that reaches it are those of the exact distances).
        let pose_distances = |posed: &[Vec<Vec3>], reference: &[Vec<Vec3>], indices: &[u32]| {
            let mut out = Vec::with_capacity(posed.len() + reference.len());
            let mut hints = Vec::new();
            for (kind, points) in [(posed, &posed_points), (reference, &reference_points)] {
                let mut floor = 0.0f32;
                for (positions, points) in kind.iter().zip(points) {
                    let range = (floor, f32::INFINITY);
                    floor = lost_below(positions, indices, points, range, &mut hints)
                        .unwrap_or(f32::INFINITY);
                    out.push(floor);
                }
            }
            out
        };
        // The largest distance of LOD 0's vertices from a build under the reference poses (0
        // without them).
        let reference_score = |from: &Step, indices: &[u32]| -> f32 {
            pose_distances(&[], posed_of(from).1, indices)
                .into_iter()
                .fold(0.0, f32::max)
        };
        // The current build against the plain ones (`Step::plain`, from LOD 0: gltfpack's way,
        // on positions alone, and gltfpack's sloppy way): a plain build is kept when it has no
        // more triangles, is closer by `score` than every build before it and no farther by
        // `reference_score` than the best build's farthest distance of either kind (a veto, not
        // part of `score`: one far pose of many must not outweigh rest and the test poses; but a
        // build nearly exact in the reference poses must not veto one closer everywhere it
        // counts: Sentry's, docs/lod.md); ties keep the earlier build. Also says which plain
        // build was kept, if any.
        // Each plain build of this level, once: they read only `keep.hard` of the anchors (the
        // retry with UV seams open below differs in nothing else), so the retry reuses them.
        let plain_built: Vec<std::sync::OnceLock<Candidate>> =
            plains.iter().map(|_| std::sync::OnceLock::new()).collect();
        // Whether a build of `plains` is a candidate at this level: sinew's own step from LOD 0
        // only from the second level on (at the first it is the step itself).
        let candidate_here = |plain: &Step| k > 0 || plain.is_plain();
        // A plain build of this level (`i`, of `plains`), made once.
        let plain_build = |i: usize, keep: &Anchors| -> &Candidate {
            plain_built[i].get_or_init(|| {
                let plain = &plains[i];
                merged(plain, plain.run(target, plain_budget, keep))
            })
        };
        let build = |keep: &Anchors| {
            // The plain builds are made beside the step's own build (on another core when one
            // is free: meshoptimizer runs on one); in order, so that those sharing a first pass
            // find it (`FirstPasses`). Each is what it would be made alone.
            let ((built, m), ()) = rayon::join(
                || build_current(keep),
                || {
                    for (i, plain) in plains.iter().enumerate() {
                        if candidate_here(plain) {
                            plain_build(i, keep);
                        }
                    }
                },
            );
            let most = built.indices.len().max(3 * (target + slack));
            let mut best = (built, m, None);
            if plains.is_empty() {
                return best;
            }
            // The step's own build measured in full: its distance under every pose (test, then
            // reference), which also says in which pose the posed repair build starts.
            let own_posed = pose_distances(&step_posed, &step_reference, &best.0.indices);
            let (own_test, own_reference) = own_posed.split_at(step_posed.len());
            // `score` and `reference_score` of the step's own build, from those.
            let Some(rest) = with_points(&best.1, &base_dense, f32::INFINITY) else {
                return best;
            };
            let mut limit = own_test.iter().fold(rest, |a, &b| a.max(b));
            if !limit.is_finite() {
                return best;
            }
            let mut reference_limit = own_reference.iter().fold(0.0f32, |a, &b| a.max(b));
            let worst_pose = farthest_pose(&own_posed);
            for (i, plain) in plains.iter().enumerate() {
                if !candidate_here(plain) {
                    continue;
                }
                let other = plain_build(i, keep).clone();
                if other.indices.len() > most {
                    continue;
                }
                // The same triangles as an earlier plain build (the sloppy build when the first
                // pass reached the target): the same distances, so the same verdict, which left
                // `best` as it is (an equal build is not closer).
                let same =
                    |c: &Candidate| c.indices == other.indices && c.submeshes == other.submeshes;
                if plain_built[..i].iter().filter_map(|c| c.get()).any(same) {
                    continue;
                }
                let source = plain.source();
                let Some(m2) = measure_below(
                    &source.positions,
                    &other.indices,
                    &base_points,
                    &base_grid,
                    limit,
                ) else {
                    continue;
                };
                let Some(s2) = score(plain, &other.indices, &m2, limit) else {
                    continue;
                };
                let r2 = reference_score(plain, &other.indices);
                if r2 <= reference_limit.max(limit) {
                    (best, limit, reference_limit) = ((other, m2, Some(i)), s2, r2);
                }
            }
            // The posed repair build: LOD 0's vertices farthest from the best build in the pose
            // where it is farthest (test or reference) are locked, each with a triangle around
            // it, and that build is made again; kept on the same terms as a plain build.
            // Which step the best build came from, and that step's source under the poses.
            let from = match best.2 {
                None => &step,
                Some(i) => &plains[i],
            };
            let (from_posed, from_reference) = posed_of(from);
            let worst_pose = match best.2 {
                None => worst_pose,
                Some(_) => {
                    farthest_pose(&pose_distances(from_posed, from_reference, &best.0.indices))
                }
            };
            if let Some((k, farthest)) = worst_pose {
                let base = base_posed.iter().chain(&base_reference).nth(k);
                let own = from_posed.iter().chain(from_reference).nth(k);
                let far = match (base, own) {
                    (Some(base), Some(own)) => posed_far_vertices(
                        &mesh.geometry.positions,
                        &base_used,
                        (base, own),
                        &best.0.indices,
                        farthest,
                    ),
                    _ => Vec::new(),
                };
                if !far.is_empty() {
                    let source = from.source();
                    let mut more = keep.clone();
                    more.hard.extend(repair_locks(source, &far));
                    more.hard.sort_unstable();
                    more.hard.dedup();
                    let limit_of = if from.is_plain() {
                        plain_budget
                    } else {
                        budget
                    };
                    let again = merged(from, from.run(target, limit_of, &more));
                    // No more triangles than the build it would replace (or the target's).
                    let fewer = best.0.indices.len().max(3 * (target + slack));
                    if again.indices.len() <= fewer {
                        // Kept when closer by `score`, or, where it ties (the farthest test
                        // pose is not where the repair moved anything), when it is no farther at
                        // rest and closer in the reference poses, which it was built for.
                        let kept = measure_below(
                            &source.positions,
                            &again.indices,
                            &base_points,
                            &base_grid,
                            limit,
                        )
                        .and_then(|m2| {
                            let s2 = score(from, &again.indices, &m2, next_above(limit))?;
                            let r2 = reference_score(from, &again.indices);
                            let better = s2 < limit
                                || (m2.distance() <= best.1.distance() && r2 < reference_limit);
                            (better && r2 <= reference_limit.max(limit)).then_some(m2)
                        });
                        if let Some(m2) = kept {
                            best = (again, m2, best.2);
                        }
                    }
                }
            }
            best
        };
        // A level is written when it removed at least half of the triangles it asks of the level
        // before it; otherwise it would be (nearly) a copy.
        let enough = |tris: usize| tris < previous_tris && 2 * tris <= previous_tris + target;
        let (mut built, mut m, mut from_plain) = build(&keep);
        let mut uv_seams_opened = false;
        if !enough(built.indices.len() / 3) {
            // UV seams hold the rest: let collapses cross them (skin seams and material borders
            // stay), as the last resort before not building the level; the LOD says so.
            let open = Anchors {
                open_uv_seams: true,
                ..keep.clone()
            };
            let (b2, m2, p2) = build(&open);
            if b2.indices.len() < built.indices.len() {
                (built, m, uv_seams_opened, from_plain) = (b2, m2, p2.is_none(), p2);
            }
        }
        let reached = built.indices.len() / 3;
        // Stopped above its target with an error limit given: did the limit stop it?
        let by_limit = options.max_error.is_some()
            && reached > target + slack
            && step.run(target, f32::MAX.sqrt(), &keep).indices.len() / 3 < reached;
        if !enough(reached) {
            let reason = if by_limit {
                NotBuiltReason::ErrorLimit
            } else {
                NotBuiltReason::NoCollapse
            };
            chain.not_built.push(not_built(Some(reached), reason));
            let now = std::time::Instant::now();
            seconds.push(now.duration_since(started).as_secs_f64());
            started = now;
            continue;
        }
        let step_error = built.error;
        let (mut lod, flat) = match from_plain {
            Some(i) => (plains[i].finish(built), plain_flat),
            None => (step.finish(built), flat),
        };
        if flat {
            lod = flat_soup(&lod);
        }
        // A plain build starts from LOD 0: its error is the whole chain's.
        accumulated = if tuning.chain && from_plain.is_none() {
            accumulated + step_error
        } else {
            step_error
        };
        if k + 1 == options.ratios.len() && options.lowest_lod_influences < MAX_INFLUENCES {
            limit_influences(&mut lod, options.lowest_lod_influences);
        }
        // `finish`, `flat_soup` and `limit_influences` keep every triangle's corners in place, so
        // the measurement is that of `lod` as it is now.
        let measured = if scale > 0.0 && m.distance().is_finite() {
            m.distance() / scale * MEASURE_MARGIN
        } else {
            0.0
        };
        let reported = accumulated.max(measured);
        lod.error = reported;
        chain.lods.push(GeneratedLod {
            target_ratio: ratio,
            reached_ratio: if base_tris == 0 {
                1.0
            } else {
                reached as f32 / base_tris as f32
            },
            error_relative: reported,
            error_model: reported * scale,
            stopped_by_error_limit: by_limit,
            uv_seams_opened,
            lod: lod.clone(),
        });
        previous_tris = reached;
        if tuning.chain {
            previous = lod;
        }
        let now = std::time::Instant::now();
        seconds.push(now.duration_since(started).as_secs_f64());
        started = now;
    }
    Ok(chain)
}

/// What [`generate_lods`] did to each mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshLodReport {
    /// Mesh name.
    pub mesh: String,
    /// Triangles of LOD 0.
    pub base_triangles: usize,
    /// The generated LODs' figures: (triangles, vertices, target ratio, reached ratio, relative error,
    /// error in model units, stopped by the error limit).
    pub lods: Vec<GeneratedLod>,
    /// The levels asked for and not built, and why.
    pub not_built: Vec<NotBuiltLod>,
}

/// Optimises every mesh's LOD 0 and replaces its generated LODs with a new chain.
pub fn generate_lods(
    scene: &mut Scene,
    options: &LodOptions,
) -> Result<Vec<MeshLodReport>, LodError> {
    generate_lods_tuned(scene, options, &LodTuning::default())
}

/// [`generate_lods`] with explicit quality knobs.
pub fn generate_lods_tuned(
    scene: &mut Scene,
    options: &LodOptions,
    tuning: &LodTuning,
) -> Result<Vec<MeshLodReport>, LodError> {
    let motion = scene_motion_for(&scene.clips, scene.skeleton.as_ref(), &scene.meshes, tuning);
    let Scene {
        meshes,
        skeleton,
        materials,
        ..
    } = scene;
    generate_mesh_lods(
        meshes,
        skeleton.as_ref(),
        materials,
        options,
        tuning,
        &motion,
    )
}

/// [`generate_lods_tuned`] on a scene's meshes alone, so that a caller can work on the scene's clips
/// at the same time (`motion`: [`scene_motion`] of the scene's clips). Meshes are independent
/// (but for which of them share the clips' budget for the plain builds, decided first in mesh
/// order): they run in parallel (rayon), each with the same result as alone with the same
/// decision; the first failing mesh in mesh order gives the error.
pub fn generate_mesh_lods(
    meshes: &mut [Mesh],
    skeleton: Option<&Skeleton>,
    materials: &[Material],
    options: &LodOptions,
    tuning: &LodTuning,
    motion: &SceneMotion,
) -> Result<Vec<MeshLodReport>, LodError> {
    generate_mesh_lods_timed(meshes, skeleton, materials, options, tuning, motion).map(|(r, _)| r)
}

/// Whether a texture may read `mesh`'s UVs: one of its material ranges has a material (of
/// `materials`, by name) with a texture, or a material not found there, or the mesh has UVs and no
/// ranges. Otherwise UV seams do not hold its simplification ([`build_lods_timed`]).
fn uvs_read(mesh: &Mesh, materials: &[Material]) -> bool {
    let g = &mesh.geometry;
    if g.uvs.is_empty() {
        return false;
    }
    g.submeshes.is_empty()
        || g.submeshes.iter().any(|s| {
            materials
                .iter()
                .find(|m| m.name == s.material)
                .is_none_or(|m| m.texture.is_some())
        })
}

/// Wall times of one mesh's LOD work, in seconds: what `convert --timings` reports.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeshLodTimes {
    /// Vertex-cache optimisation of LOD 0.
    pub optimize: f64,
    /// Each level tried (simplification, repair and error measurement), most detailed first: the
    /// generated levels, then a level not built when simplification was tried for it.
    pub levels: Vec<f64>,
}

/// [`generate_mesh_lods`], with each mesh's wall times (mesh order; meshes run in parallel, so
/// the times overlap).
pub fn generate_mesh_lods_timed(
    meshes: &mut [Mesh],
    skeleton: Option<&Skeleton>,
    materials: &[Material],
    options: &LodOptions,
    tuning: &LodTuning,
    motion: &SceneMotion,
) -> Result<(Vec<MeshLodReport>, Vec<MeshLodTimes>), LodError> {
    options.validate()?;
    let reference = &motion.poses;
    let plains = plain_builds_of(meshes, skeleton, tuning, motion);
    let scene_scale = tuning.scene_scale.unwrap_or_else(|| {
        meshes
            .iter()
            .map(largest_range_scale)
            .fold(0.0f32, f32::max)
    });
    let one =
        |(mesh, plain): (&mut Mesh, PlainSet)| -> Result<(MeshLodReport, MeshLodTimes), LodError> {
            let started = std::time::Instant::now();
            // The geometry as it came, before the vertex-cache order: the plain build starts from it.
            let plain_input =
                matches!(plain, PlainSet::All | PlainSet::Positions).then(|| mesh.geometry.clone());
            optimize_base(mesh)?;
            let mut times = MeshLodTimes {
                optimize: started.elapsed().as_secs_f64(),
                levels: Vec::new(),
            };
            let chain = build_lods_timed(
                mesh,
                plain_input.as_ref(),
                plain,
                skeleton,
                options.keep_uv_seams || uvs_read(mesh, materials),
                scene_scale,
                options,
                tuning,
                reference,
                &mut times.levels,
            )?;
            mesh.lods = chain.lods;
            mesh.lods_not_built = chain.not_built;
            let report = MeshLodReport {
                mesh: mesh.name.clone(),
                base_triangles: mesh.geometry.triangle_count(),
                lods: mesh.lods.clone(),
                not_built: mesh.lods_not_built.clone(),
            };
            Ok((report, times))
        };
    let done: Vec<Result<(MeshLodReport, MeshLodTimes), LodError>> = if meshes.len() > 1 {
        meshes.par_iter_mut().zip(plains).map(one).collect()
    } else {
        meshes.iter_mut().zip(plains).map(one).collect()
    };
    let done: Vec<(MeshLodReport, MeshLodTimes)> = done.into_iter().collect::<Result<_, _>>()?;
    Ok(done.into_iter().unzip())
}

#[cfg(test)]
mod tests;
