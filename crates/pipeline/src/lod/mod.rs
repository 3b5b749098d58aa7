//! Level-of-detail generation for (skinned) meshes, on meshoptimizer.
//!
//! Each LOD is simplified from the previous one (meshoptimizer's recommendation for chains), submesh by
//! submesh so that material ranges survive, with:
//! - attribute-aware collapses: normals and UVs weigh in the collapse cost;
//! - skin awareness: each vertex also carries its displacement under two fixed test poses of the
//!   skeleton (every joint turned 25 degrees about its local X, then about its local Z), weighted
//!   above the normals. Two vertices whose influences differ move apart under those poses, so
//!   collapsing one into the other costs what it would tear at runtime: bone boundaries are kept where
//!   they matter and cheap where they do not;
//! - locks on material borders: a vertex whose position is also used by another submesh does not move,
//!   so neighbouring submeshes still meet;
//! - meshoptimizer's `Permissive` option with every vertex protected except those on hard normal
//!   edges: vertices that share a position but differ only in their normal may be collapsed across,
//!   with the normal difference counted as attribute error, while UV seams, skin seams and everything
//!   else keep meshoptimizer's usual rules;
//! - meshoptimizer's `RegularizeLight` option, which its author recommends for deforming meshes.
//!
//! Simplification only ever selects among existing vertices, so skin weights travel with their vertices
//! unchanged; the lowest LOD may be cut to fewer influences, renormalised. Every LOD's index order is
//! then optimised for the vertex cache and its vertices reordered for fetch.
//!
//! meshoptimizer passes indices to C++ unchecked, so every buffer is validated before each call.

mod weld;

use crate::lod_parts::position_ids;
use crate::surface::{
    beyond_and_farthest, farthest_above, sample_points, used_vertices, TriangleGrid,
};
use meshopt::{SimplifyOptions, SimplifyVertex};
use rayon::prelude::*;
use sinew_core::glam;
use sinew_core::skinning;
use sinew_core::{Lod, Skeleton, Submesh, Transform, MAX_INFLUENCES};
use sinew_scene::{GeneratedLod, Mesh, Scene};
use weld::{flat_soup, is_flat_soup, weld};

/// A LOD's reported error is at least its measured distance to LOD 0 times this margin: the larger
/// of the distance from LOD 0's vertices to the LOD's surface and from the LOD's vertices, centroids
/// and edge midpoints to LOD 0's surface. The margin covers what a denser measurement finds between
/// those samples (docs/lod.md: on the corpus and fixtures, LOD 0's centroids and midpoints added at
/// most 4%, and 20,000 random surface points at most 3%).
const MEASURE_MARGIN: f32 = 1.1;

/// At most this many far LOD 0 vertices are locked when a step is built again (`repair_far_vertices`).
const REPAIR_VERTICES: usize = 16;

/// What to build.
#[derive(Debug, Clone, PartialEq)]
pub struct LodOptions {
    /// Target fraction of LOD 0's triangles for each generated LOD, decreasing.
    pub ratios: Vec<f32>,
    /// Largest simplification error allowed, relative to the mesh extent, accumulated along the chain.
    pub max_error: f32,
    /// Influences per vertex kept in the lowest LOD (1 to 4).
    pub lowest_lod_influences: usize,
}

impl Default for LodOptions {
    fn default() -> Self {
        Self {
            ratios: vec![0.5, 0.25],
            max_error: DEFAULT_MAX_ERROR,
            lowest_lod_influences: MAX_INFLUENCES,
        }
    }
}

/// Default error limit: 5% of the mesh extent. A 25% LOD of a low-polygon character usually needs
/// about this much; the error actually reached is always reported.
pub const DEFAULT_MAX_ERROR: f32 = 0.05;

/// The simplifier's quality knobs. The defaults are the measured best (docs/lod.md); the other values
/// exist so that `examples/lod_compare.rs --sweep` can show why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LodTuning {
    /// Weight of each normal component in the collapse cost.
    pub normal_weight: f32,
    /// Weight of each UV component.
    pub uv_weight: f32,
    /// Weight of each component of the displacement under the two test poses (0: not skin-aware).
    pub pose_weight: f32,
    /// meshoptimizer's `RegularizeLight` option.
    pub regularize: bool,
    /// meshoptimizer's `Permissive` option, with every vertex but those on hard normal edges protected
    /// (false: hard normal edges restrict collapses like every other attribute seam).
    pub permissive: bool,
    /// Build each LOD from the previous one (true) or every LOD from LOD 0 (false, each with the
    /// whole error budget).
    pub chain: bool,
    /// Lock each connected part's extreme vertices (`lod_parts`), so that thin and small parts keep
    /// their reach.
    pub lock_part_extremes: bool,
    /// Build a step again with LOD 0's vertices locked where the result lies farther from them than
    /// meshoptimizer's reported error (at most [`REPAIR_VERTICES`]).
    pub repair_far_vertices: bool,
}

impl Default for LodTuning {
    fn default() -> Self {
        Self {
            normal_weight: NORMAL_WEIGHT,
            uv_weight: UV_WEIGHT,
            pose_weight: POSE_WEIGHT,
            regularize: true,
            permissive: true,
            chain: true,
            lock_part_extremes: true,
            repair_far_vertices: true,
        }
    }
}

/// Why LODs could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LodError {
    /// A ratio outside (0, 1].
    #[error("LOD ratio {0} is not in (0, 1]")]
    BadRatio(f32),
    /// Ratios not decreasing.
    #[error("LOD ratios must decrease: {0:?}")]
    RatiosNotDecreasing(Vec<f32>),
    /// Error limit negative or not finite.
    #[error("LOD error limit {0} must be a finite number >= 0")]
    BadMaxError(f32),
    /// Influence count outside 1..=4.
    #[error("LOD influences must be 1 to 4, not {0}")]
    BadInfluences(usize),
    /// The mesh's buffers are inconsistent.
    #[error("mesh {mesh:?}: {problem}")]
    BadMesh {
        /// Mesh name.
        mesh: String,
        /// What is wrong.
        problem: String,
    },
}

impl LodOptions {
    /// Checks the options.
    pub fn validate(&self) -> Result<(), LodError> {
        let mut prev = 1.0f32;
        for &r in &self.ratios {
            if !(r > 0.0 && r <= 1.0) {
                return Err(LodError::BadRatio(r));
            }
            if r > prev {
                return Err(LodError::RatiosNotDecreasing(self.ratios.clone()));
            }
            prev = r;
        }
        if !(self.max_error.is_finite() && self.max_error >= 0.0) {
            return Err(LodError::BadMaxError(self.max_error));
        }
        if !(1..=MAX_INFLUENCES).contains(&self.lowest_lod_influences) {
            return Err(LodError::BadInfluences(self.lowest_lod_influences));
        }
        Ok(())
    }
}

/// Checks that a LOD's buffers agree with each other: what meshoptimizer needs before any call.
pub fn validate_lod(lod: &Lod) -> Result<(), String> {
    let n = lod.positions.len();
    if n > u32::MAX as usize {
        return Err(format!("{n} vertices is more than 32-bit indices address"));
    }
    if lod.normals.len() != n {
        return Err(format!("{} normals for {n} positions", lod.normals.len()));
    }
    if !lod.uvs.is_empty() && lod.uvs.len() != n {
        return Err(format!("{} uvs for {n} positions", lod.uvs.len()));
    }
    if lod.joints.len() != lod.weights.len() || (!lod.joints.is_empty() && lod.joints.len() != n) {
        return Err(format!(
            "{} joint and {} weight sets for {n} positions",
            lod.joints.len(),
            lod.weights.len()
        ));
    }
    if lod.indices.len() % 3 != 0 {
        return Err(format!(
            "{} indices is not a whole number of triangles",
            lod.indices.len()
        ));
    }
    if let Some(bad) = lod.indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("index {bad} refers past the {n} vertices"));
    }
    if !lod.positions.iter().all(|p| p.is_finite()) {
        return Err("non-finite position".into());
    }
    let mut next = 0u32;
    for s in &lod.submeshes {
        if s.first_index != next || s.index_count % 3 != 0 {
            return Err("submeshes do not cover the indices in order, by whole triangles".into());
        }
        next = s
            .first_index
            .checked_add(s.index_count)
            .ok_or("submesh range overflows")?;
    }
    if next as usize != lod.indices.len() && !lod.submeshes.is_empty() {
        return Err("submeshes do not cover every index".into());
    }
    Ok(())
}

/// Per-vertex attributes the simplifier weighs: normal (3), UV (2), displacement under two test poses (6).
const ATTRIBUTE_COUNT: usize = 11;
const NORMAL_WEIGHT: f32 = 0.2;
const UV_WEIGHT: f32 = 0.5;
const POSE_WEIGHT: f32 = 4.0;
const TEST_POSE_ANGLE_DEGREES: f32 = 25.0;

/// Model-space positions of every vertex under a test pose, by plain linear blend skinning.
fn posed_positions(lod: &Lod, skeleton: &Skeleton, axis: glam::Vec3) -> Vec<glam::Vec3> {
    let turn = glam::Quat::from_axis_angle(axis, TEST_POSE_ANGLE_DEGREES.to_radians());
    let locals: Vec<Transform> = skeleton
        .bind_local()
        .iter()
        .map(|b| Transform {
            rotation: b.rotation * turn,
            ..*b
        })
        .collect();
    // The runtime's own local-to-model, palette and skinning, so the test poses deform exactly as a
    // game would draw them. Joint indices were validated by the caller; on any error the vertices keep
    // their bind positions (no displacement attribute).
    let n = skeleton.len();
    let (mut models, mut palette) = (vec![glam::Mat4::IDENTITY; n], vec![glam::Mat4::IDENTITY; n]);
    let mut out = lod.positions.clone();
    let posed = skinning::local_to_model_and_palette(
        skeleton.parents(),
        &locals,
        skeleton.inverse_bind(),
        &mut models,
        &mut palette,
    )
    .and_then(|()| {
        skinning::skin(
            &palette,
            &lod.positions,
            &[],
            &lod.joints,
            &lod.weights,
            &mut out,
            &mut [],
        )
    });
    if posed.is_err() {
        out.clone_from(&lod.positions);
    }
    out
}

fn extent(positions: &[glam::Vec3]) -> f32 {
    let (mut lo, mut hi) = (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN));
    for p in positions {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    if positions.is_empty() {
        0.0
    } else {
        (hi - lo).max_element()
    }
}

fn attributes(lod: &Lod, skeleton: Option<&Skeleton>) -> Vec<f32> {
    let n = lod.positions.len();
    let scale = extent(&lod.positions);
    let inv = if scale > 0.0 { 1.0 / scale } else { 0.0 };
    let poses: Vec<Vec<glam::Vec3>> = match skeleton {
        Some(s) if lod.is_skinned() && !s.is_empty() => [glam::Vec3::X, glam::Vec3::Z]
            .iter()
            .map(|&axis| posed_positions(lod, s, axis))
            .collect(),
        _ => Vec::new(),
    };
    let mut out = vec![0.0f32; n * ATTRIBUTE_COUNT];
    for v in 0..n {
        let a = &mut out[v * ATTRIBUTE_COUNT..(v + 1) * ATTRIBUTE_COUNT];
        a[0..3].copy_from_slice(&lod.normals[v].to_array());
        if let Some(uv) = lod.uvs.get(v) {
            a[3..5].copy_from_slice(&uv.to_array());
        }
        for (k, pose) in poses.iter().enumerate() {
            let d = (pose[v] - lod.positions[v]) * inv;
            if d.is_finite() {
                a[5 + 3 * k..8 + 3 * k].copy_from_slice(&d.to_array());
            }
        }
    }
    out
}

/// Per-vertex flags for meshoptimizer, one per vertex (never an empty slice for a mesh with vertices):
/// - `Lock` for vertices whose position is used by more than one submesh (material borders);
/// - `Protect` for every other vertex except those on a hard normal edge: a position shared by
///   several vertices that all have the same UV, joints and weights and differ only in the normal.
///   With `Permissive`, meshoptimizer may collapse across the discontinuities of unprotected vertices
///   (paying the normal difference as attribute error) and treats protected ones as it does without
///   `Permissive`: UV seams, skin seams and whatever it locks for topology stay as they were. Without
///   `Permissive`, `Protect` changes nothing.
fn vertex_flags(lod: &Lod) -> Vec<SimplifyVertex> {
    const NO_OWNER: u32 = u32::MAX;
    let (count, id_of) = position_ids(&lod.positions);
    // Per position: the first submesh using it, and whether another submesh uses it too.
    let mut owner = vec![NO_OWNER; count];
    let mut shared = vec![false; count];
    for (s, sub) in lod.submeshes.iter().enumerate() {
        let range = sub.first_index as usize..(sub.first_index + sub.index_count) as usize;
        for &i in &lod.indices[range] {
            let id = id_of[i as usize] as usize;
            if owner[id] == NO_OWNER {
                owner[id] = s as u32;
            } else if owner[id] != s as u32 {
                shared[id] = true;
            }
        }
    }
    // Per position: its first vertex, and whether every later vertex there has the same UV and
    // skin (a hard normal edge, opened) or not (a UV or skin seam, kept). `None` while the position
    // has one vertex.
    let mut first = vec![u32::MAX; count];
    let mut hard_edge: Vec<Option<bool>> = vec![None; count];
    for (v, &id) in id_of.iter().enumerate() {
        let id = id as usize;
        if first[id] == u32::MAX {
            first[id] = v as u32;
            continue;
        }
        let a = first[id] as usize;
        let same = lod.uvs.get(a) == lod.uvs.get(v)
            && lod.joints.get(a) == lod.joints.get(v)
            && lod.weights.get(a) == lod.weights.get(v);
        let open = hard_edge[id].get_or_insert(true);
        *open &= same;
    }
    id_of
        .iter()
        .map(|&id| {
            let id = id as usize;
            if shared[id] {
                SimplifyVertex::Lock
            } else if hard_edge[id] == Some(true) {
                SimplifyVertex::None
            } else {
                SimplifyVertex::Protect
            }
        })
        .collect()
}

/// Runs `each` on the indices of every material range of `lod` (all its indices when it has
/// none), optimises each result for the vertex cache and joins them: the new indices and material
/// ranges (none when `lod` has none).
fn per_submesh(lod: &Lod, mut each: impl FnMut(&[u32]) -> Vec<u32>) -> (Vec<u32>, Vec<Submesh>) {
    let whole = [Submesh {
        first_index: 0,
        index_count: lod.indices.len() as u32,
        material: String::new(),
    }];
    let subs: &[Submesh] = if lod.submeshes.is_empty() {
        &whole
    } else {
        &lod.submeshes
    };
    let mut indices = Vec::with_capacity(lod.indices.len());
    let mut submeshes = Vec::with_capacity(subs.len());
    for sub in subs {
        let range = sub.first_index as usize..(sub.first_index + sub.index_count) as usize;
        let mut part = each(&lod.indices[range]);
        if !part.is_empty() {
            meshopt::optimize_vertex_cache_in_place(&mut part, lod.positions.len());
        }
        submeshes.push(Submesh {
            first_index: indices.len() as u32,
            index_count: part.len() as u32,
            material: sub.material.clone(),
        });
        indices.extend(part);
    }
    if lod.submeshes.is_empty() {
        submeshes.clear();
    }
    (indices, submeshes)
}

/// One simplification step: `source` to about `target_triangles`, within `max_error` (relative).
/// Returns the new LOD (compacted and optimised) and the relative error of this step.
/// `keep`: positions (bit patterns, sorted) whose vertices are locked (the part extremes of LOD 0).
fn simplify_step(
    source: &Lod,
    skeleton: Option<&Skeleton>,
    target_triangles: usize,
    max_error: f32,
    tuning: &LodTuning,
    keep: &[[u32; 3]],
) -> (Lod, f32) {
    let positions: Vec<[f32; 3]> = source.positions.iter().map(|p| p.to_array()).collect();
    let attrs = attributes(source, skeleton);
    let mut weights = [0.0f32; ATTRIBUTE_COUNT];
    weights[0..3].fill(tuning.normal_weight);
    if !source.uvs.is_empty() {
        weights[3..5].fill(tuning.uv_weight);
    }
    if source.is_skinned() && skeleton.is_some() {
        weights[5..].fill(tuning.pose_weight);
    }
    let mut flags = if tuning.regularize {
        SimplifyOptions::RegularizeLight
    } else {
        SimplifyOptions::None
    };
    if tuning.permissive {
        flags |= SimplifyOptions::Permissive;
    }
    let mut locks = vertex_flags(source);
    for (l, p) in locks.iter_mut().zip(&source.positions) {
        if keep
            .binary_search(&[p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .is_ok()
        {
            *l = SimplifyVertex::Lock;
        }
    }
    let total = source.triangle_count().max(1);
    let mut worst = 0.0f32;
    let (indices, submeshes) = per_submesh(source, |part| {
        let part_tris = part.len() / 3;
        // Each submesh gets its share of the target, rounded; never below one triangle if it had any.
        let target = ((part_tris as f64 * target_triangles as f64 / total as f64).round() as usize)
            .clamp(part_tris.min(1), part_tris);
        let mut err = 0.0f32;
        let simplified = if part.is_empty() || target >= part_tris {
            part.to_vec()
        } else {
            meshopt::simplify_with_attributes_and_locks_decoder(
                part,
                &positions,
                &attrs,
                &weights,
                ATTRIBUTE_COUNT * std::mem::size_of::<f32>(),
                &locks,
                target * 3,
                max_error,
                flags,
                Some(&mut err),
            )
        };
        worst = worst.max(err);
        simplified
    });
    let lod = compact(source, indices, submeshes);
    (lod, worst)
}

/// For each old vertex, its new index in order of first use by `indices` (`u32::MAX` when unused): the
/// vertex-fetch order meshoptimizer's `optimizeVertexFetchRemap` computes. Written here because the
/// meshopt 0.7 wrapper truncates that table to the number of used vertices, dropping entries.
fn first_use_remap(indices: &[u32], vertex_count: usize) -> Vec<u32> {
    let mut remap = vec![u32::MAX; vertex_count];
    let mut next = 0u32;
    for &i in indices {
        let r = &mut remap[i as usize];
        if *r == u32::MAX {
            *r = next;
            next += 1;
        }
    }
    remap
}

/// Keeps only the vertices the indices use, in first-use order (meshoptimizer's vertex-fetch order).
fn compact(source: &Lod, mut indices: Vec<u32>, submeshes: Vec<Submesh>) -> Lod {
    let remap = first_use_remap(&indices, source.positions.len());
    let kept = remap.iter().filter(|&&r| r != u32::MAX).count();
    let mut order = vec![0u32; kept];
    for (old, &new) in remap.iter().enumerate() {
        if new != u32::MAX {
            order[new as usize] = old as u32;
        }
    }
    for i in &mut indices {
        *i = remap[*i as usize];
    }
    Lod {
        positions: order
            .iter()
            .map(|&o| source.positions[o as usize])
            .collect(),
        normals: order.iter().map(|&o| source.normals[o as usize]).collect(),
        uvs: if !source.uvs.is_empty() {
            order.iter().map(|&o| source.uvs[o as usize]).collect()
        } else {
            Vec::new()
        },
        joints: if !source.joints.is_empty() {
            order.iter().map(|&o| source.joints[o as usize]).collect()
        } else {
            Vec::new()
        },
        weights: if !source.weights.is_empty() {
            order.iter().map(|&o| source.weights[o as usize]).collect()
        } else {
            Vec::new()
        },
        indices,
        submeshes,
        error: 0.0,
    }
}

/// Keeps the `keep` largest influences of every vertex and renormalises them to sum to one.
pub fn limit_influences(lod: &mut Lod, keep: usize) {
    for (j, w) in lod.joints.iter_mut().zip(&mut lod.weights) {
        let mut order: [usize; MAX_INFLUENCES] = [0, 1, 2, 3];
        // Stable: equal weights keep slot order.
        order.sort_by(|&a, &b| w[b].total_cmp(&w[a]));
        let (mut nj, mut nw) = ([0u16; MAX_INFLUENCES], [0.0f32; MAX_INFLUENCES]);
        for (slot, &k) in order.iter().take(keep).enumerate() {
            nj[slot] = j[k];
            nw[slot] = w[k];
        }
        let sum: f32 = nw.iter().sum();
        if sum > 0.0 {
            for x in &mut nw {
                *x /= sum;
            }
            *j = nj;
            *w = nw;
        }
    }
}

/// Optimises LOD 0 in place for the vertex cache and vertex fetch, keeping `source_vertex` in step.
pub fn optimize_base(mesh: &mut Mesh) -> Result<(), LodError> {
    validate_lod(&mesh.geometry).map_err(|problem| LodError::BadMesh {
        mesh: mesh.name.clone(),
        problem,
    })?;
    let g = &mesh.geometry;
    let (mut indices, submeshes) = per_submesh(g, <[u32]>::to_vec);
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
    g.submeshes = submeshes;
    Ok(())
}

/// The largest distance that cannot raise a reported error of `accumulated`: every distance `d` up
/// to it gives `d / scale * MEASURE_MARGIN <= accumulated` in f32 (the same expression as the
/// measurement's), so distance searches may stop at the first triangle that close with the same
/// result. 0 when nothing can be skipped.
fn irrelevant_below(accumulated: f32, scale: f32) -> f32 {
    if !(scale > 0.0 && accumulated > 0.0 && accumulated.is_finite()) {
        return 0.0;
    }
    // The neighbouring floats of a non-negative finite value (`f32::next_up` and `next_down` need
    // Rust 1.86, past the workspace's MSRV).
    let up = |d: f32| f32::from_bits(d.to_bits() + 1);
    let down = |d: f32| f32::from_bits(d.to_bits() - 1);
    let raises = |d: f32| d / scale * MEASURE_MARGIN > accumulated;
    let mut floor = accumulated * scale / MEASURE_MARGIN;
    if !floor.is_finite() {
        return 0.0;
    }
    // Rounding puts the estimate a few ulps off; the expression is monotone in `d`, so step down
    // until it does not raise the error and up while the next float does not either (a bounded
    // number of steps: 0 is always a safe answer).
    for _ in 0..64 {
        if floor > 0.0 && raises(floor) {
            floor = down(floor);
        }
    }
    if raises(floor) {
        return 0.0;
    }
    for _ in 0..64 {
        if !raises(up(floor)) {
            floor = up(floor);
        }
    }
    floor.max(0.0)
}

/// Builds the LOD chain of one mesh from its geometry.
pub fn build_lods(
    mesh: &Mesh,
    skeleton: Option<&Skeleton>,
    options: &LodOptions,
) -> Result<Vec<GeneratedLod>, LodError> {
    build_lods_tuned(mesh, skeleton, options, &LodTuning::default())
}

/// [`build_lods`] with explicit quality knobs.
pub fn build_lods_tuned(
    mesh: &Mesh,
    skeleton: Option<&Skeleton>,
    options: &LodOptions,
    tuning: &LodTuning,
) -> Result<Vec<GeneratedLod>, LodError> {
    build_lods_timed(mesh, skeleton, options, tuning, &mut Vec::new())
}

/// [`build_lods_tuned`], pushing each level's wall time in seconds (with its repair and
/// measurement) onto `seconds`.
fn build_lods_timed(
    mesh: &Mesh,
    skeleton: Option<&Skeleton>,
    options: &LodOptions,
    tuning: &LodTuning,
    seconds: &mut Vec<f64>,
) -> Result<Vec<GeneratedLod>, LodError> {
    options.validate()?;
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
    let positions: Vec<[f32; 3]> = mesh
        .geometry
        .positions
        .iter()
        .map(|p| p.to_array())
        .collect();
    let scale = if positions.is_empty() {
        0.0
    } else {
        meshopt::simplify_scale_decoder(&positions)
    };
    let base_tris = mesh.geometry.triangle_count();
    // Part extremes are found once, on LOD 0, and kept through the chain: a part simplified below
    // `lod_parts::SMALL_PART` triangles in one step must keep them in the next.
    let mut keep: Vec<[u32; 3]> = if tuning.lock_part_extremes {
        let g = &mesh.geometry;
        crate::lod_parts::part_extremes(&g.positions, &g.indices)
            .into_iter()
            .zip(&g.positions)
            .filter(|(e, _)| *e)
            .map(|(_, p)| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
            .collect()
    } else {
        Vec::new()
    };
    keep.sort_unstable();
    keep.dedup();
    // The measured distance to LOD 0 is a floor under each reported error (see `MEASURE_MARGIN`).
    let base_grid = TriangleGrid::new(&mesh.geometry.positions, &mesh.geometry.indices);
    // LOD 0's vertices only: what simplification loses shows at the vertices it removed (on the
    // corpus and fixtures the centroids and edge midpoints of LOD 0 add at most 4%; the margin
    // covers it).
    let base_vertices = used_vertices(&mesh.geometry.positions, &mesh.geometry.indices);
    let mut out: Vec<GeneratedLod> = Vec::with_capacity(options.ratios.len());
    let mut previous = mesh.geometry.clone();
    let mut accumulated = 0.0f32;
    let mut started = std::time::Instant::now();
    for (k, &ratio) in options.ratios.iter().enumerate() {
        let target = ((base_tris as f64) * ratio as f64).round() as usize;
        let budget = if tuning.chain {
            (options.max_error - accumulated).max(0.0)
        } else {
            options.max_error
        };
        let flat = is_flat_soup(&previous);
        let welded = weld(&previous, flat);
        validate_lod(&welded).map_err(|problem| LodError::BadMesh {
            mesh: mesh.name.clone(),
            problem: format!("after welding: {problem}"),
        })?;
        let (mut lod, mut step_error) =
            simplify_step(&welded, skeleton, target, budget, tuning, &keep);
        // Repair: the attribute terms (normals, UVs, test poses) weigh in meshoptimizer's error, so
        // it can remove a shape feature while reporting a small error. LOD 0 vertices farther from
        // the result than that error (the 16 farthest at most) are locked and the step is built
        // again (zombie.ms3d's LOD 1: 2.725% of the diagonal before, 1.756% after; docs/lod.md).
        let base_accum = if tuning.chain { accumulated } else { 0.0 };
        // The grid of the step's result; `lost` is LOD 0's farthest vertex from it, as far as it
        // can matter (`irrelevant_below`).
        let mut lod_grid = TriangleGrid::new(&lod.positions, &lod.indices);
        let mut lost = None;
        if tuning.repair_far_vertices {
            let threshold = (base_accum + step_error) * scale;
            // Only distances above the threshold matter: the search may stop at the first
            // triangle within it (the kept distances are exact, the rest are dropped either way).
            // The same pass finds the farthest vertex, which the measurement below needs when
            // the step is kept.
            let (beyond, largest) = beyond_and_farthest(
                &base_vertices,
                &lod_grid,
                threshold,
                irrelevant_below(base_accum + step_error, scale),
            );
            let mut far: Vec<(f32, [u32; 3])> = beyond
                .into_iter()
                .filter(|(_, d)| d.is_finite())
                .map(|(i, d)| {
                    let p = base_vertices[i];
                    (d, [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
                })
                .collect();
            far.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            far.truncate(REPAIR_VERTICES);
            if !far.is_empty() {
                let mut more = keep.clone();
                more.extend(far.iter().map(|f| f.1));
                more.sort_unstable();
                more.dedup();
                (lod, step_error) = simplify_step(&welded, skeleton, target, budget, tuning, &more);
                lod_grid = TriangleGrid::new(&lod.positions, &lod.indices);
            } else {
                lost = Some(largest);
            }
        }
        let mut lod = if flat { flat_soup(&lod) } else { lod };
        accumulated = if tuning.chain {
            accumulated + step_error
        } else {
            step_error
        };
        if k + 1 == options.ratios.len() && options.lowest_lod_influences < MAX_INFLUENCES {
            limit_influences(&mut lod, options.lowest_lod_influences);
        }
        // `flat_soup` and `limit_influences` keep every triangle's corners in place and in order,
        // so `lod_grid` is the grid of `lod` as it is now.
        let floor = irrelevant_below(accumulated, scale);
        let lost = lost.unwrap_or_else(|| farthest_above(&base_vertices, &lod_grid, floor));
        // Each point once: an edge's midpoint comes from both its triangles (the same bits, as
        // float addition commutes), and a maximum does not depend on repeats or order.
        let samples = sample_points(&lod.positions, &lod.indices);
        let (count, ids) = position_ids(&samples);
        let mut distinct = Vec::with_capacity(count);
        let mut taken = vec![false; count];
        for (p, &id) in samples.iter().zip(&ids) {
            if !std::mem::replace(&mut taken[id as usize], true) {
                distinct.push(*p);
            }
        }
        let added = farthest_above(&distinct, &base_grid, floor);
        let measured = if scale > 0.0 && lost.is_finite() {
            lost.max(added) / scale * MEASURE_MARGIN
        } else {
            0.0
        };
        let reported = accumulated.max(measured);
        lod.error = reported;
        let reached = if base_tris == 0 {
            1.0
        } else {
            lod.triangle_count() as f32 / base_tris as f32
        };
        // The target is met when within one triangle per submesh of it (rounding per submesh).
        let slack = mesh.geometry.submeshes.len().max(1);
        let stopped = lod.triangle_count() > target + slack;
        out.push(GeneratedLod {
            target_ratio: ratio,
            reached_ratio: reached,
            error_relative: reported,
            error_model: reported * scale,
            stopped_by_error_limit: stopped,
            lod: lod.clone(),
        });
        if tuning.chain {
            previous = lod;
        }
        let now = std::time::Instant::now();
        seconds.push(now.duration_since(started).as_secs_f64());
        started = now;
    }
    Ok(out)
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
    let Scene {
        meshes, skeleton, ..
    } = scene;
    generate_mesh_lods(meshes, skeleton.as_ref(), options, tuning)
}

/// [`generate_lods_tuned`] on a scene's meshes alone, so that a caller can work on the scene's clips
/// at the same time. Meshes are independent: they run in parallel (rayon), each with the same
/// result as alone; the first failing mesh in mesh order gives the error.
pub fn generate_mesh_lods(
    meshes: &mut [Mesh],
    skeleton: Option<&Skeleton>,
    options: &LodOptions,
    tuning: &LodTuning,
) -> Result<Vec<MeshLodReport>, LodError> {
    generate_mesh_lods_timed(meshes, skeleton, options, tuning).map(|(r, _)| r)
}

/// Wall times of one mesh's LOD work, in seconds: what `convert --timings` reports.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MeshLodTimes {
    /// Vertex-cache optimisation of LOD 0.
    pub optimize: f64,
    /// Each generated level (simplification, repair and error measurement), most detailed first.
    pub levels: Vec<f64>,
}

/// [`generate_mesh_lods`], with each mesh's wall times (mesh order; meshes run in parallel, so
/// the times overlap).
pub fn generate_mesh_lods_timed(
    meshes: &mut [Mesh],
    skeleton: Option<&Skeleton>,
    options: &LodOptions,
    tuning: &LodTuning,
) -> Result<(Vec<MeshLodReport>, Vec<MeshLodTimes>), LodError> {
    options.validate()?;
    let one = |mesh: &mut Mesh| -> Result<(MeshLodReport, MeshLodTimes), LodError> {
        let started = std::time::Instant::now();
        optimize_base(mesh)?;
        let mut times = MeshLodTimes {
            optimize: started.elapsed().as_secs_f64(),
            levels: Vec::new(),
        };
        mesh.lods = build_lods_timed(mesh, skeleton, options, tuning, &mut times.levels)?;
        let report = MeshLodReport {
            mesh: mesh.name.clone(),
            base_triangles: mesh.geometry.triangle_count(),
            lods: mesh.lods.clone(),
        };
        Ok((report, times))
    };
    let done: Vec<Result<(MeshLodReport, MeshLodTimes), LodError>> = if meshes.len() > 1 {
        meshes.par_iter_mut().map(one).collect()
    } else {
        meshes.iter_mut().map(one).collect()
    };
    let done: Vec<(MeshLodReport, MeshLodTimes)> = done.into_iter().collect::<Result<_, _>>()?;
    Ok(done.into_iter().unzip())
}

#[cfg(test)]
mod tests;
