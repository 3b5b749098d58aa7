//! One simplification step of the LOD chain: meshoptimizer's attribute-aware simplifier called on
//! a welded mesh with the weights, options and per-vertex flags [`LodTuning`] chooses, then the
//! result regrouped by material, optimised for the vertex cache and compacted.
//!
//! The whole mesh is simplified in one call: each vertex belongs to one material range (`weld`
//! splits shared ones), so a material border is an attribute seam to meshoptimizer, which moves
//! both sides of it together or not at all. The border stays closed and may still simplify along
//! itself, and the target is spread over the materials by error rather than by a fixed share of
//! each. Every triangle of the result keeps the material of its corners.

use super::weld::submesh_of;
use crate::lod_parts::position_ids;
use meshopt::{SimplifyOptions, SimplifyVertex};
use sinew_core::glam;
use sinew_core::skinning;
use sinew_core::{Lod, Skeleton, Submesh, Transform};

mod primitives;

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
    /// Give each connected part's extreme vertices (`lod_parts`), in parts of any size,
    /// meshoptimizer's `Priority`, so that moving them costs their displacement: thin and small
    /// parts keep their reach.
    pub anchor_part_extremes: bool,
    /// Build each step a second time with LOD 0's farthest vertices from its result locked, each
    /// with one triangle around it, and keep the closer of the two builds.
    pub repair_far_vertices: bool,
    /// Simplify all material ranges in one call, their borders as seams (true), or each range
    /// alone towards its share of the target with its border vertices locked (false).
    pub whole_mesh: bool,
    /// Build each step a second way, as gltfpack does (normals alone weigh, no vertex flags,
    /// `Prune`, full `Regularize` when skinned), and keep that build when it is closer to LOD 0 at
    /// rest and under the test poses (the larger distance) with no more triangles, on every mesh.
    /// With the posed repair build it costs 4.0-5.3x the chain's work (docs/lod.md); `convert
    /// --effort max` turns it on.
    pub plain_candidate: bool,
    /// Without `plain_candidate`, the plain builds still run on a mesh whose comparison work
    /// ([`super::plain_work`]) is at most this: where they cost little in absolute terms
    /// (docs/lod.md, "Cost"); a static mesh above it gets the positions-only build alone.
    /// 0: never, on any mesh.
    pub plain_work_bound: usize,
    /// The extent (meshoptimizer's: its vertices' largest box side) of the scene's largest
    /// material range ([`super::largest_range_scale`]), which gltfpack's per-range limit is scaled
    /// by (`Plain::Primitives`), when meshes are built apart from their scene (a tool comparing
    /// one mesh at a time); `None`: the largest of the meshes given.
    pub scene_scale: Option<f32>,
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
            anchor_part_extremes: true,
            repair_far_vertices: true,
            whole_mesh: true,
            plain_candidate: false,
            plain_work_bound: PLAIN_WORK_BOUND,
            scene_scale: None,
        }
    }
}

/// Positions (bit patterns, each list sorted) whose vertices a step must keep: `hard` ones are
/// locked, `soft` ones get meshoptimizer's `Priority` (moving them costs their displacement).
/// `open_uv_seams`: see [`vertex_flags`].
#[derive(Debug, Clone, Default)]
pub(super) struct Anchors {
    pub(super) hard: Vec<[u32; 3]>,
    pub(super) soft: Vec<[u32; 3]>,
    pub(super) open_uv_seams: bool,
}

/// The default [`LodTuning::plain_work_bound`], in LOD 0 triangles measured (docs/lod.md, "Cost").
pub const PLAIN_WORK_BOUND: usize = 10_000;

/// Per-vertex attributes the simplifier weighs: normal (3), UV (2), displacement under two test poses (6).
const ATTRIBUTE_COUNT: usize = 11;
const NORMAL_WEIGHT: f32 = 0.2;
const UV_WEIGHT: f32 = 0.5;
const POSE_WEIGHT: f32 = 4.0;
const TEST_POSE_ANGLE_DEGREES: f32 = 25.0;
/// gltfpack's normal weight (`simplifyAttributes` in its mesh.cpp).
const PLAIN_NORMAL_WEIGHT: f32 = 0.5;
/// gltfpack's default error limit (`-se`), relative to the mesh's extent.
const PLAIN_ERROR: f32 = 0.01;
/// gltfpack's error limit for its sloppy pass under `-sa` (`target_error_aggressive`).
const SLOPPY_ERROR: f32 = 0.1;
/// How many more times [`Plain::SloppyNear`], where it fell short of its target, asks the
/// clustering grid for more triangles ([`Step::sloppy_within`]).
const SLOPPY_RAISES: usize = 6;

/// How a plain build ([`Step::plain`]) goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Plain {
    /// gltfpack's `-si`: normals weigh, within 1% first, then on to the target.
    Normals,
    /// On positions alone, in one call.
    Positions,
    /// gltfpack's `-si -sa`: normals weigh, within 1%, then meshoptimizer's sloppy simplifier
    /// (vertex clustering, which ignores attribute seams) on to the target within 10%.
    Sloppy,
    /// [`Plain::Sloppy`] as gltfpack gives it one primitive (the part's vertices alone: the grid
    /// over their box), its clustering grid asked for more where it fell short of the target
    /// ([`Step::sloppy_within`]): more triangles, not always closer, so a build of its own.
    SloppyNear,
    /// gltfpack's `-si` as it meets a glTF export: each material range is a primitive of its own,
    /// simplified alone on its own vertices, within 1% of its extent scaled by the scene's
    /// largest range's extent over its own (gltfpack's default `-ss`). Where those passes miss
    /// the target, the ranges above their share go on to it without `Prune` (unlimited, it
    /// removes whole parts) ([`Step::run_primitives`]).
    Primitives,
    /// gltfpack's `-si -sa` as it meets a glTF export: [`Plain::Primitives`]' first passes, then
    /// each range above its share given to meshoptimizer's sloppy simplifier alone, within 10% of
    /// its extent ([`Step::run_primitives`]).
    PrimitivesSloppy,
}

/// A plain build's attributes (values, per-vertex count), weights and options ([`Step::plain`]):
/// normals at gltfpack's weight and, for a skinned source, full regularization, or positions alone.
fn plain_settings(
    source: &Lod,
    kind: Plain,
) -> ((Vec<f32>, usize), [f32; ATTRIBUTE_COUNT], SimplifyOptions) {
    let mut weights = [0.0f32; ATTRIBUTE_COUNT];
    let mut flags = SimplifyOptions::Prune;
    if kind == Plain::Positions {
        return ((Vec::new(), 0), weights, flags);
    }
    weights[0..3].fill(PLAIN_NORMAL_WEIGHT);
    if source.is_skinned() {
        flags |= SimplifyOptions::Regularize;
    }
    let normals = source.normals.iter().flat_map(|n| n.to_array()).collect();
    ((normals, 3), weights, flags)
}

/// The first passes (within gltfpack's 1% limit) of the plain builds that share their settings:
/// [`Plain::Normals`], [`Plain::Sloppy`] and [`Plain::SloppyNear`] differ only after it, so the
/// later ones' are the first one's, asked of meshoptimizer once (the same call on the same input:
/// the same result).
#[derive(Default)]
pub(super) struct FirstPasses(std::sync::Mutex<Vec<FirstPass>>);

/// One first pass: its input (the triangles, the vertex flags and the target) and its result.
struct FirstPass {
    part: Vec<u32>,
    locks: Vec<SimplifyVertex>,
    target: usize,
    result: (Vec<u32>, f32),
}

impl FirstPasses {
    /// The result kept for this input, if any.
    fn get(
        &self,
        part: &[u32],
        locks: &[SimplifyVertex],
        target: usize,
    ) -> Option<(Vec<u32>, f32)> {
        let kept = self.0.lock().ok()?;
        kept.iter()
            .find(|f| f.target == target && f.part == part && f.locks == locks)
            .map(|f| f.result.clone())
    }

    fn put(&self, part: &[u32], locks: &[SimplifyVertex], target: usize, result: &(Vec<u32>, f32)) {
        if let Ok(mut kept) = self.0.lock() {
            kept.push(FirstPass {
                part: part.to_vec(),
                locks: locks.to_vec(),
                target,
                result: result.clone(),
            });
        }
    }
}

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
    skinned(lod, skeleton, &locals)
}

/// Model-space positions of every vertex under the local pose `locals` (one per joint).
fn skinned(lod: &Lod, skeleton: &Skeleton, locals: &[Transform]) -> Vec<glam::Vec3> {
    // The runtime's own local-to-model, palette and skinning, so the test poses deform exactly as a
    // game would draw them. Joint indices were validated by the caller; on any error the vertices keep
    // their bind positions (no displacement attribute).
    let n = skeleton.len();
    let (mut models, mut palette) = (vec![glam::Mat4::IDENTITY; n], vec![glam::Mat4::IDENTITY; n]);
    let mut out = lod.positions.clone();
    let posed = skinning::local_to_model_and_palette(
        skeleton.parents(),
        locals,
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

/// `lod`'s vertices under the two test poses (every joint turned about its local X, then about
/// its local Z); none when it is not skinned to a skeleton.
pub(super) fn test_poses(lod: &Lod, skeleton: Option<&Skeleton>) -> Vec<Vec<glam::Vec3>> {
    match skeleton {
        Some(s) if lod.is_skinned() && !s.is_empty() => [glam::Vec3::X, glam::Vec3::Z]
            .iter()
            .map(|&axis| posed_positions(lod, s, axis))
            .collect(),
        _ => Vec::new(),
    }
}

/// `lod`'s vertices under each of `reference` (local poses sampled from the scene's clips,
/// [`super::reference_poses`]); none when it is not skinned to a skeleton.
pub(super) fn reference_positions(
    lod: &Lod,
    skeleton: Option<&Skeleton>,
    reference: &[Vec<Transform>],
) -> Vec<Vec<glam::Vec3>> {
    match skeleton {
        Some(s) if lod.is_skinned() && !s.is_empty() => reference
            .iter()
            .filter(|l| l.len() == s.len())
            .map(|l| skinned(lod, s, l))
            .collect(),
        _ => Vec::new(),
    }
}

fn attributes(lod: &Lod, poses: &[Vec<glam::Vec3>]) -> Vec<f32> {
    let n = lod.positions.len();
    let scale = extent(&lod.positions);
    let inv = if scale > 0.0 { 1.0 / scale } else { 0.0 };
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
/// - at a position used by more than one submesh (a material border): `Lock` when `lock_borders`
///   (each material simplified alone, so that neighbouring ranges still meet), else `Protect`
///   (the whole mesh in one call: the border is a seam that meshoptimizer keeps closed);
/// - `Protect` for every other vertex except those on a hard normal edge: a position shared by
///   several vertices that all have the same UV, joints and weights and differ only in the normal.
///   With `Permissive`, meshoptimizer may collapse across the discontinuities of unprotected vertices
///   (paying the normal difference as attribute error) and treats protected ones as it does without
///   `Permissive`: UV seams, skin seams and whatever it locks for topology stay as they were. Without
///   `Permissive`, `Protect` changes nothing. With `open_uv_seams`, positions whose vertices differ
///   in their UV (and normal) but not in their skin are opened too: the step may then join two UV
///   charts in one triangle, which the LOD builder allows only where a level could not be built
///   otherwise, and reports.
///
/// `of` is each vertex's submesh ([`submesh_of`]).
#[cfg(test)]
pub(super) fn vertex_flags(
    lod: &Lod,
    of: &[u32],
    lock_borders: bool,
    open_uv_seams: bool,
) -> Vec<SimplifyVertex> {
    vertex_flags_with(
        lod,
        of,
        &position_ids(&lod.positions),
        lock_borders,
        open_uv_seams,
    )
}

/// [`vertex_flags`] with the positions' ids ([`position_ids`]) given.
fn vertex_flags_with(
    lod: &Lod,
    of: &[u32],
    ids: &(usize, Vec<u32>),
    lock_borders: bool,
    open_uv_seams: bool,
) -> Vec<SimplifyVertex> {
    const NONE: u32 = u32::MAX;
    let (count, id_of) = (ids.0, &ids.1);
    // Per position: the first submesh using it, and whether another submesh uses it too.
    let mut owner = vec![NONE; count];
    let mut shared = vec![false; count];
    for (&id, &s) in id_of.iter().zip(of) {
        let id = id as usize;
        if s == NONE {
            continue;
        }
        if owner[id] == NONE {
            owner[id] = s;
        } else if owner[id] != s {
            shared[id] = true;
        }
    }
    // Per position: its first vertex, and whether every later vertex there has the same UV and
    // skin (a hard normal edge, opened) or not (a UV or skin seam, kept). `None` while the position
    // has one vertex.
    let mut first = vec![NONE; count];
    let mut hard_edge: Vec<Option<bool>> = vec![None; count];
    for (v, &id) in id_of.iter().enumerate() {
        let id = id as usize;
        if first[id] == NONE {
            first[id] = v as u32;
            continue;
        }
        let a = first[id] as usize;
        let same = (open_uv_seams || lod.uvs.get(a) == lod.uvs.get(v))
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
                if lock_borders {
                    SimplifyVertex::Lock
                } else {
                    SimplifyVertex::Protect
                }
            } else if hard_edge[id] == Some(true) {
                SimplifyVertex::None
            } else {
                SimplifyVertex::Protect
            }
        })
        .collect()
}

/// The material ranges of `lod` (one range over every index when it has none).
fn ranges(lod: &Lod) -> Vec<Submesh> {
    if lod.submeshes.is_empty() {
        vec![Submesh {
            first_index: 0,
            index_count: lod.indices.len() as u32,
            material: String::new(),
        }]
    } else {
        lod.submeshes.clone()
    }
}

/// Optimises `indices` (into `vertex_count` vertices) for the vertex cache, each material range
/// of `submeshes` on its own (all of them as one range when there are none).
pub(super) fn optimize_ranges(indices: &mut [u32], submeshes: &[Submesh], vertex_count: usize) {
    if submeshes.is_empty() {
        if !indices.is_empty() {
            meshopt::optimize_vertex_cache_in_place(indices, vertex_count);
        }
        return;
    }
    for sub in submeshes {
        let part =
            &mut indices[sub.first_index as usize..(sub.first_index + sub.index_count) as usize];
        if !part.is_empty() {
            meshopt::optimize_vertex_cache_in_place(part, vertex_count);
        }
    }
}

/// A simplification step's result: `indices` into the step's source, grouped by material range
/// (`submeshes`, empty when the source has none), and meshoptimizer's relative error.
#[derive(Clone)]
pub(super) struct Candidate {
    pub(super) indices: Vec<u32>,
    pub(super) submeshes: Vec<Submesh>,
    pub(super) error: f32,
}

/// One simplification step of a welded source: what every build of the step shares (positions,
/// attributes and their weights, options, each vertex's material range).
pub(super) struct Step<'a> {
    source: &'a Lod,
    positions: Vec<[f32; 3]>,
    attrs: Vec<f32>,
    weights: [f32; ATTRIBUTE_COUNT],
    flags: SimplifyOptions,
    of: Vec<u32>,
    ids: (usize, Vec<u32>),
    whole: bool,
    /// A plain build (see [`Step::plain`]): normals alone weigh or nothing does, no vertex flags.
    plain: Option<Plain>,
    /// Attributes per vertex in `attrs` (the first of `weights`).
    count: usize,
    /// Where a plain build's first passes are kept for the other plain builds of its settings.
    first_passes: Option<std::sync::Arc<FirstPasses>>,
    /// [`Plain::Primitives`]: the extent of the scene's largest material range, which gltfpack's
    /// 1% is of.
    scene_scale: f32,
}

impl<'a> Step<'a> {
    /// Prepares a step of `source` (valid, welded) with `tuning`'s weights and options.
    pub(super) fn new(source: &'a Lod, skeleton: Option<&Skeleton>, tuning: &LodTuning) -> Self {
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
        let attrs = attributes(source, &test_poses(source, skeleton));
        Step::assemble(
            source,
            tuning,
            (attrs, ATTRIBUTE_COUNT),
            weights,
            flags,
            None,
        )
    }

    /// A step of `source` with these attributes (values, per-vertex count), weights and options;
    /// `plain`: built as [`Step::plain`] builds.
    fn assemble(
        source: &'a Lod,
        tuning: &LodTuning,
        (attrs, count): (Vec<f32>, usize),
        weights: [f32; ATTRIBUTE_COUNT],
        flags: SimplifyOptions,
        plain: Option<Plain>,
    ) -> Self {
        Step {
            source,
            positions: source.positions.iter().map(|p| p.to_array()).collect(),
            attrs,
            weights,
            flags,
            of: submesh_of(source),
            ids: position_ids(&source.positions),
            whole: tuning.whole_mesh && source.submeshes.len() > 1,
            plain,
            count,
            first_passes: None,
            scene_scale: 0.0,
        }
    }

    /// A step of `source` (valid, welded) built the way gltfpack's `-si` builds one
    /// ([`Plain::Normals`]): normals weigh (0.5), UVs and the test poses do not (a UV or skin seam
    /// still holds), no vertex is protected, locked (but by a posed repair build) or given
    /// priority, with meshoptimizer's `Prune` and, for a skinned source, its full `Regularize`,
    /// first within gltfpack's error limit (1%) and then on to the target; [`Plain::Sloppy`] goes on from 1% as gltfpack's `-sa` does.
    /// [`Plain::Positions`]: on positions alone, no attribute, `Prune` only, in one call.
    fn plain(source: &'a Lod, tuning: &LodTuning, kind: Plain) -> Self {
        let (attrs, weights, flags) = plain_settings(source, kind);
        Step::assemble(source, tuning, attrs, weights, flags, Some(kind))
    }

    /// The six plain builds of `source` ([`Plain::Normals`], [`Plain::Positions`],
    /// [`Plain::Sloppy`], [`Plain::SloppyNear`], [`Plain::Primitives`] and
    /// [`Plain::PrimitivesSloppy`], in that order), sharing what they compute
    /// alike: the vertex positions, material ranges and position ids, and the first pass of the
    /// normals and sloppy builds ([`FirstPasses`]).
    /// `scene_scale`: the extent (meshoptimizer's) of the scene's largest material range, for
    /// [`Plain::Primitives`].
    pub(super) fn plains(source: &'a Lod, tuning: &LodTuning, scene_scale: f32) -> Vec<Self> {
        let mut normals = Step::plain(source, tuning, Plain::Normals);
        let first_passes = std::sync::Arc::new(FirstPasses::default());
        let positions = normals.plain_like(Plain::Positions);
        let mut sloppy = normals.plain_like(Plain::Sloppy);
        let mut near = normals.plain_like(Plain::SloppyNear);
        let mut primitives = normals.plain_like(Plain::Primitives);
        primitives.scene_scale = scene_scale;
        let mut primitives_sloppy = normals.plain_like(Plain::PrimitivesSloppy);
        primitives_sloppy.scene_scale = scene_scale;
        normals.first_passes = Some(std::sync::Arc::clone(&first_passes));
        sloppy.first_passes = Some(std::sync::Arc::clone(&first_passes));
        near.first_passes = Some(first_passes);
        vec![
            normals,
            positions,
            sloppy,
            near,
            primitives,
            primitives_sloppy,
        ]
    }

    /// The positions-only plain build of `source` alone ([`Plain::Positions`]): what a static mesh
    /// beyond the plain builds' work bound gets (`super::motion::PlainSet::Positions`).
    pub(super) fn positions_plain(source: &'a Lod, tuning: &LodTuning) -> Self {
        Step::plain(source, tuning, Plain::Positions)
    }

    /// A plain build of this step's source of another kind, with this step's positions, material
    /// ranges and position ids (computed once for the source).
    fn plain_like(&self, kind: Plain) -> Self {
        let ((attrs, count), weights, flags) = plain_settings(self.source, kind);
        Step {
            source: self.source,
            positions: self.positions.clone(),
            attrs,
            weights,
            flags,
            of: self.of.clone(),
            ids: self.ids.clone(),
            whole: self.whole,
            plain: Some(kind),
            count,
            first_passes: None,
            scene_scale: 0.0,
        }
    }

    /// Whether this is a plain build ([`Step::plain`]).
    pub(super) fn is_plain(&self) -> bool {
        self.plain.is_some()
    }

    /// The step's (welded) source.
    pub(super) fn source(&self) -> &'a Lod {
        self.source
    }

    /// The per-vertex flags ([`vertex_flags`]) with `keep`'s positions locked or given priority.
    fn flags(&self, lock_borders: bool, keep: &Anchors) -> Vec<SimplifyVertex> {
        if self.plain.is_some() {
            // No flags, but material borders locked when each range is simplified alone.
            let mut flags = vec![SimplifyVertex::None; self.positions.len()];
            if lock_borders && self.source.submeshes.len() > 1 {
                let borders = vertex_flags_with(self.source, &self.of, &self.ids, true, false);
                for (f, b) in flags.iter_mut().zip(borders) {
                    if b == SimplifyVertex::Lock {
                        *f = SimplifyVertex::Lock;
                    }
                }
            }
            // The posed repair build's locks.
            if !keep.hard.is_empty() {
                for (f, p) in flags.iter_mut().zip(&self.source.positions) {
                    let bits = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
                    if keep.hard.binary_search(&bits).is_ok() {
                        *f = SimplifyVertex::Lock;
                    }
                }
            }
            return flags;
        }
        let mut locks = vertex_flags_with(
            self.source,
            &self.of,
            &self.ids,
            lock_borders,
            keep.open_uv_seams,
        );
        for (l, p) in locks.iter_mut().zip(&self.source.positions) {
            let bits = [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
            if keep.hard.binary_search(&bits).is_ok() {
                *l = SimplifyVertex::Lock;
            } else if keep.soft.binary_search(&bits).is_ok() {
                *l |= SimplifyVertex::Priority;
            }
        }
        locks
    }

    fn simplify(
        &self,
        part: &[u32],
        locks: &[SimplifyVertex],
        target: usize,
        max_error: f32,
    ) -> (Vec<u32>, f32) {
        if self.plain.is_some() && self.count > 0 && max_error > PLAIN_ERROR {
            // gltfpack's error limit first (it changes which collapses each pass makes, not only
            // where simplification stops), then on to the target from there.
            let kept = self.first_passes.as_deref();
            let (first, err) = match kept.and_then(|k| k.get(part, locks, target)) {
                Some(done) => done,
                None => {
                    let done = self.simplify_once(part, locks, target, PLAIN_ERROR);
                    if let Some(k) = kept {
                        k.put(part, locks, target, &done);
                    }
                    done
                }
            };
            if first.len() <= target * 3 {
                return (first, err);
            }
            if self.plain == Some(Plain::Sloppy) {
                let mut more = 0.0f32;
                let out = meshopt::simplify_sloppy_with_locks_decoder(
                    &first,
                    &self.positions,
                    locks,
                    target * 3,
                    SLOPPY_ERROR.min(max_error),
                    Some(&mut more),
                );
                return (out, err.max(more));
            }
            if self.plain == Some(Plain::SloppyNear) {
                let (out, more) = self.sloppy_within(part, &first, locks, target, max_error);
                return (out, err.max(more));
            }
            let (out, more) = self.simplify_once(&first, locks, target, max_error);
            return (out, err + more);
        }
        self.simplify_once(part, locks, target, max_error)
    }

    /// [`Plain::SloppyNear`]: meshoptimizer's sloppy simplifier on `first` (a build of `part`),
    /// as many triangles as it gives without going over `target`: its clustering grid lands at or
    /// below the count asked for, often well below (zombie's LOD 2: 176 of 178), so when it falls
    /// short the count asked for is raised (between `target` and `first`'s own count) and the
    /// largest result within `target` is kept (the first of equals). Whatever the grid does, the
    /// result is within `target` whenever the first call's is.
    ///
    /// `part`'s vertices alone are given to meshoptimizer, as gltfpack gives it one primitive's:
    /// the grid spans the part's box and its 10% limit is of the part's extent (a material range
    /// of a larger mesh is clustered at its own scale), and each call reads the part's vertices,
    /// not the mesh's. The error returned is of the mesh's extent, as the other builds' are.
    pub(super) fn sloppy_within(
        &self,
        part: &[u32],
        first: &[u32],
        locks: &[SimplifyVertex],
        target: usize,
        max_error: f32,
    ) -> (Vec<u32>, f32) {
        // The part's vertices in their order, and `first`'s triangles on them.
        let mut local_of = vec![u32::MAX; self.positions.len()];
        let mut used: Vec<u32> = part.to_vec();
        used.sort_unstable();
        used.dedup();
        for (i, &v) in used.iter().enumerate() {
            local_of[v as usize] = i as u32;
        }
        let local: Vec<u32> = first.iter().map(|&v| local_of[v as usize]).collect();
        let positions: Vec<[f32; 3]> = used.iter().map(|&v| self.positions[v as usize]).collect();
        let local_locks: Vec<SimplifyVertex> = used.iter().map(|&v| locks[v as usize]).collect();
        // meshoptimizer's errors are relative to the extent of the vertices it is given.
        let (whole, own) = (
            meshopt::simplify_scale_decoder(&self.positions),
            meshopt::simplify_scale_decoder(&positions),
        );
        let to_mesh = if whole > 0.0 { own / whole } else { 1.0 };
        let limit = if to_mesh > 0.0 {
            SLOPPY_ERROR.min(max_error / to_mesh)
        } else {
            SLOPPY_ERROR
        };
        let sloppy = |asked: usize| {
            let mut err = 0.0f32;
            let out = meshopt::simplify_sloppy_with_locks_decoder(
                &local,
                &positions,
                &local_locks,
                asked * 3,
                limit,
                Some(&mut err),
            );
            (out, err * to_mesh)
        };
        let mut best = sloppy(target);
        // `lo`: asked and got, got within the target; `hi`: asked and got, got above it (at first
        // `first` itself). The next count asked for is interpolated between them (the grid's
        // count grows about in proportion to the count asked for), at most `SLOPPY_RAISES` times.
        let (mut lo, mut hi) = (
            (target, best.0.len() / 3),
            (first.len() / 3, first.len() / 3),
        );
        for _ in 0..SLOPPY_RAISES {
            if best.0.len() >= target * 3 || hi.0 <= lo.0 + 1 || hi.1 <= lo.1 {
                break;
            }
            let step = (target - lo.1) as f64 * (hi.0 - lo.0) as f64 / (hi.1 - lo.1) as f64;
            let asked = (lo.0 + step.round() as usize).clamp(lo.0 + 1, hi.0 - 1);
            let again = sloppy(asked);
            let got = again.0.len() / 3;
            if got <= target {
                lo = (asked, got);
                if again.0.len() > best.0.len() {
                    best = again;
                }
            } else {
                hi = (asked, got);
            }
        }
        let (out, err) = best;
        (out.into_iter().map(|v| used[v as usize]).collect(), err)
    }

    fn simplify_once(
        &self,
        part: &[u32],
        locks: &[SimplifyVertex],
        target: usize,
        max_error: f32,
    ) -> (Vec<u32>, f32) {
        let attrs = (&self.attrs[..], &self.weights[..self.count]);
        simplify_edges(
            part,
            &self.positions,
            attrs,
            locks,
            target,
            max_error,
            self.flags,
        )
    }

    /// Simplifies the source to about `target_triangles` within `max_error` (relative to its
    /// extent), `keep`'s vertices locked or given priority.
    pub(super) fn run(&self, target_triangles: usize, max_error: f32, keep: &Anchors) -> Candidate {
        let source = self.source;
        if let Some(kind @ (Plain::Primitives | Plain::PrimitivesSloppy)) = self.plain {
            return self.run_primitives(target_triangles, max_error, keep, kind);
        }
        if self.whole {
            let target = target_triangles.min(source.triangle_count());
            let (simplified, error) =
                self.simplify(&source.indices, &self.flags(false, keep), target, max_error);
            if let Some((indices, submeshes)) = group_by_submesh(source, &self.of, &simplified) {
                return Candidate {
                    indices,
                    submeshes,
                    error,
                };
            }
            // A triangle whose corners came from two material ranges (meshoptimizer never makes
            // one across seams it keeps; this is the guard): each range alone, as below.
        }
        let locks = self.flags(true, keep);
        // Each range gets its share of the target, rounded; never below one triangle if it had any.
        self.by_range(target_triangles, f64::round, |part, target| {
            self.simplify(part, &locks, target, max_error)
        })
    }

    /// Each material range of the source (the whole index list when there are none) simplified
    /// by `each` towards its share of `target_triangles` (`share` rounds it; at least one triangle
    /// if the range had any), the ranges in order: a range at or under its share stays as it is.
    /// The candidate's error is the largest `each` returned.
    pub(super) fn by_range(
        &self,
        target_triangles: usize,
        share: fn(f64) -> f64,
        mut each: impl FnMut(&[u32], usize) -> (Vec<u32>, f32),
    ) -> Candidate {
        let source = self.source;
        let total = source.triangle_count().max(1);
        let mut worst = 0.0f32;
        let mut indices = Vec::with_capacity(source.indices.len());
        let mut submeshes = Vec::new();
        for sub in ranges(source) {
            let part = &source.indices
                [sub.first_index as usize..(sub.first_index + sub.index_count) as usize];
            let part_tris = part.len() / 3;
            let target = (share(part_tris as f64 * target_triangles as f64 / total as f64)
                as usize)
                .clamp(part_tris.min(1), part_tris);
            let simplified = if part.is_empty() || target >= part_tris {
                part.to_vec()
            } else {
                let (out, err) = each(part, target);
                worst = worst.max(err);
                out
            };
            submeshes.push(Submesh {
                first_index: indices.len() as u32,
                index_count: simplified.len() as u32,
                material: sub.material.clone(),
            });
            indices.extend(simplified);
        }
        if source.submeshes.is_empty() {
            submeshes.clear();
        }
        Candidate {
            indices,
            submeshes,
            error: worst,
        }
    }

    /// The candidate as a LOD: each range optimised for the vertex cache, unused vertices dropped,
    /// the rest in first-use order (meshoptimizer's vertex-fetch order).
    pub(super) fn finish(&self, c: Candidate) -> Lod {
        let mut indices = c.indices;
        optimize_ranges(&mut indices, &c.submeshes, self.source.positions.len());
        compact(self.source, indices, c.submeshes)
    }
}

/// meshoptimizer's edge-collapse simplifier on `part` (indices into `positions`) towards
/// `target` triangles within `max_error` (relative to the extent of `positions`): with the
/// attributes `attrs` (values, then one weight per attribute of a vertex) when there are any, on
/// positions alone otherwise. The result and meshoptimizer's error.
pub(super) fn simplify_edges(
    part: &[u32],
    positions: &[[f32; 3]],
    (values, weights): (&[f32], &[f32]),
    locks: &[SimplifyVertex],
    target: usize,
    max_error: f32,
    flags: SimplifyOptions,
) -> (Vec<u32>, f32) {
    let mut err = 0.0f32;
    let out = if weights.is_empty() {
        meshopt::simplify_with_locks_decoder(
            part,
            positions,
            locks,
            target * 3,
            max_error,
            flags,
            Some(&mut err),
        )
    } else {
        meshopt::simplify_with_attributes_and_locks_decoder(
            part,
            positions,
            values,
            weights,
            std::mem::size_of_val(weights),
            locks,
            target * 3,
            max_error,
            flags,
            Some(&mut err),
        )
    };
    (out, err)
}

/// The triangles of `simplified` (indices into `source`'s vertices) grouped by the material range
/// of their corners, ranges in `source`'s order (a range may end up empty): the indices and the
/// ranges; `None` when a triangle's corners belong to different ranges.
fn group_by_submesh(
    source: &Lod,
    of: &[u32],
    simplified: &[u32],
) -> Option<(Vec<u32>, Vec<Submesh>)> {
    let mut groups: Vec<Vec<u32>> = vec![Vec::new(); source.submeshes.len()];
    for t in simplified.chunks_exact(3) {
        let s = of[t[0] as usize];
        if of[t[1] as usize] != s || of[t[2] as usize] != s {
            return None;
        }
        groups.get_mut(s as usize)?.extend_from_slice(t);
    }
    let mut indices = Vec::with_capacity(simplified.len());
    let mut submeshes = Vec::with_capacity(groups.len());
    for (g, sub) in groups.into_iter().zip(&source.submeshes) {
        submeshes.push(Submesh {
            first_index: indices.len() as u32,
            index_count: g.len() as u32,
            material: sub.material.clone(),
        });
        indices.extend(g);
    }
    Some((indices, submeshes))
}

/// For each old vertex, its new index in order of first use by `indices` (`u32::MAX` when unused): the
/// vertex-fetch order meshoptimizer's `optimizeVertexFetchRemap` computes. Written here because the
/// meshopt 0.7 wrapper truncates that table to the number of used vertices, dropping entries.
pub(super) fn first_use_remap(indices: &[u32], vertex_count: usize) -> Vec<u32> {
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
