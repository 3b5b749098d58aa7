//! The error metric: virtual points carried through the joint chain, measured against the source clip.

use super::options::PARALLEL_VOLUME;
use rayon::prelude::*;
use sinew_core::glam::{Affine3A, Vec3};
use sinew_core::skeleton::inverse_bind_from_locals;
use sinew_core::{Channel, Clip, ClipBinding, Sampler, Skeleton, Transform};

/// The joints the error is measured on: the skeleton's, then one root per track it lacks.
pub(super) struct Rig {
    pub(super) skeleton: Skeleton,
    /// Per joint: the local offsets of its three error points (its local axes times
    /// `point_scale`).
    pub(super) points: Vec<[Vec3; 3]>,
    /// Per joint: how far along its local axes its error points are (the distance over the
    /// joint's bind-pose model scale).
    pub(super) point_scale: Vec<f32>,
    /// Per joint: how far its error points and descendants reach from it in the bind pose.
    pub(super) reach: Vec<f32>,
    /// Per joint: its distance from its parent in the bind pose (0 for roots).
    pub(super) bone: Vec<f32>,
    /// The error points' distance from their joint.
    pub(super) distance: f32,
    /// Per joint: the model-space scale of its parent (1 for roots).
    pub(super) parent_scale: Vec<f32>,
    /// Per joint: itself, then its descendants in skeleton order ([`subtrees`]); computed once
    /// here, as every state of the search reads it.
    pub(super) subtree: Vec<Vec<usize>>,
    /// Per joint `j`, per position `n > 0` in `subtree[j]`: the position of that joint's parent
    /// (`usize::MAX` at `n == 0`, whose parent is outside the subtree).
    pub(super) subtree_parent: Vec<Vec<usize>>,
    /// The anchors, one per root, in joint order: the joint a root's subtree's error points are
    /// measured about ([`Rig::rebase`]): the root, or down the chain of single children from it
    /// while the joint is not animated, the first that is or that has no child or several (`Hips`
    /// under a capture's static `Root`, or under an armature node). Each time's origins
    /// ([`Rig::source_points`]) hold one translation per anchor, in this order.
    pub(super) anchors: Vec<usize>,
    /// Per joint: its position in `anchors` if it is one ([`Rig::anchor_of`]).
    anchor_slot: Vec<Option<usize>>,
}

/// Anchor `slot`'s model transform `m` about its origin in `origins` (one time's,
/// [`Rig::origins_at`]): [`Rig::rebase`] where the caller knows the slot.
#[inline]
pub(super) fn rebase_on(m: &mut Affine3A, origins: &[Vec3], slot: usize) {
    if let Some(o) = origins.get(slot) {
        m.translation -= sinew_core::glam::Vec3A::from(*o);
    }
}

pub(super) fn model_scale(a: &Affine3A) -> f32 {
    let m = a.matrix3;
    m.x_axis
        .length()
        .max(m.y_axis.length())
        .max(m.z_axis.length())
}

pub(super) fn fk(parents: &[Option<u16>], local: &[Transform], out: &mut Vec<Affine3A>) {
    out.clear();
    for (j, t) in local.iter().enumerate() {
        let a = t.to_affine();
        let m = match parents.get(j).copied().flatten() {
            Some(p) => out.get(p as usize).copied().unwrap_or(Affine3A::IDENTITY) * a,
            None => a,
        };
        out.push(m);
    }
}

/// The skeleton's extent: bind-pose bounding-box diagonal of the joint positions (1 when degenerate).
pub fn skeleton_extent(skeleton: &Skeleton) -> f32 {
    let mut m = Vec::new();
    fk(skeleton.parents(), skeleton.bind_local(), &mut m);
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for a in &m {
        let p = Vec3::from(a.translation);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let d = (hi - lo).length();
    if d.is_finite() && d > 1e-6 {
        d
    } else {
        1.0
    }
}

pub(super) fn clip_extent(clip: &Clip) -> f32 {
    let mut r: f32 = 0.0;
    let p = clip.to_plain();
    for t in p.tracks() {
        if let Channel::Constant(v) = t.translation {
            r = r.max(v.length());
        }
        if let Channel::Animated(o) = t.translation {
            for f in p.frames().chunks_exact(p.stride().max(1)) {
                let o = o as usize;
                r = r.max(Vec3::new(f[o], f[o + 1], f[o + 2]).length());
            }
        }
    }
    if r.is_finite() && r > 1e-6 {
        2.0 * r
    } else {
        1.0
    }
}

/// Per joint: itself, then its descendants in skeleton order (parents come before children).
pub(super) fn subtrees(parents: &[Option<u16>]) -> Vec<Vec<usize>> {
    let mut subtree: Vec<Vec<usize>> = (0..parents.len()).map(|j| vec![j]).collect();
    for d in 0..parents.len() {
        let mut p = parents[d];
        while let Some(a) = p {
            let a = usize::from(a);
            subtree[a].push(d);
            p = parents.get(a).copied().flatten();
        }
    }
    subtree
}

/// Per joint `j`, per position `n` in `subtree[j]`: the position of that joint's parent in
/// `subtree[j]` (`usize::MAX` at `n == 0`, whose parent is outside the subtree).
pub(super) fn subtree_parents(parents: &[Option<u16>], subtree: &[Vec<usize>]) -> Vec<Vec<usize>> {
    let nj = parents.len();
    // Per joint `j`, per joint `d`: `d`'s position in `subtree[j]`, or `u32::MAX`.
    let mut subtree_at = vec![u32::MAX; nj * nj];
    for (j, list) in subtree.iter().enumerate() {
        for (n, &d) in list.iter().enumerate() {
            if let Some(slot) = subtree_at.get_mut(j * nj + d) {
                *slot = n as u32;
            }
        }
    }
    subtree
        .iter()
        .enumerate()
        .map(|(j, list)| {
            list.iter()
                .enumerate()
                .map(|(n, &d)| {
                    let p = parents.get(d).copied().flatten().map(usize::from);
                    match p.and_then(|p| subtree_at.get(j * nj + p)) {
                        Some(&np) if n > 0 && np != u32::MAX => np as usize,
                        _ => usize::MAX,
                    }
                })
                .collect()
        })
        .collect()
}

impl Rig {
    pub(super) fn new(clip: &Clip, skeleton: Option<&Skeleton>, distance: f32) -> Option<Rig> {
        let (mut names, mut parents, mut bind) = match skeleton {
            Some(s) => (
                s.names().to_vec(),
                s.parents().to_vec(),
                s.bind_local().to_vec(),
            ),
            None => (Vec::new(), Vec::new(), Vec::new()),
        };
        for t in clip.tracks() {
            if !names.contains(&t.joint) {
                names.push(t.joint.clone());
                parents.push(None);
                bind.push(Transform::IDENTITY);
            }
        }
        let inv = inverse_bind_from_locals(&parents, &bind);
        let skeleton = Skeleton::new(names, parents.clone(), bind.clone(), inv).ok()?;
        let mut m = Vec::new();
        fk(&parents, &bind, &mut m);
        let n = parents.len();
        let scale: Vec<f32> = m.iter().map(|a| model_scale(a).max(1e-12)).collect();
        let point_scale: Vec<f32> = scale.iter().map(|s| distance / s).collect();
        let points = point_scale
            .iter()
            .map(|&c| [Vec3::X, Vec3::Y, Vec3::Z].map(|a| a * c))
            .collect();
        let mut reach = vec![distance; n];
        let mut bone = vec![0.0; n];
        // Children come after parents: walk backwards, pushing reach up the chain.
        for j in (0..n).rev() {
            if let Some(p) = parents[j] {
                let p = p as usize;
                let d = (Vec3::from(m[j].translation) - Vec3::from(m[p].translation)).length();
                bone[j] = d;
                reach[p] = reach[p].max(reach[j] + d);
            }
        }
        let parent_scale = parents
            .iter()
            .map(|p| p.map_or(1.0, |p| scale[p as usize]))
            .collect();
        let subtree = subtrees(skeleton.parents());
        let subtree_parent = subtree_parents(skeleton.parents(), &subtree);
        let mut children = vec![Vec::new(); n];
        for (j, p) in parents.iter().enumerate() {
            if let Some(p) = p.map(usize::from).filter(|&p| p < j) {
                children[p].push(j);
            }
        }
        let mut animated = vec![false; n];
        for t in clip.tracks() {
            let moves = matches!(t.translation, Channel::Animated(_))
                || matches!(t.rotation, Channel::Animated(_))
                || matches!(t.scale, Channel::Animated(_));
            if let Some(j) = skeleton.find(&t.joint).map(usize::from).filter(|_| moves) {
                animated[j] = true;
            }
        }
        let mut anchors: Vec<usize> = (0..n)
            .filter(|&j| parents[j].is_none())
            .map(|mut j| {
                while let (false, [only]) = (animated[j], children[j].as_slice()) {
                    j = *only;
                }
                j
            })
            .collect();
        // In joint order, so that a pass over the joints meets them in turn (`Eval::pose_into`).
        anchors.sort_unstable();
        let mut anchor_slot = vec![None; n];
        for (slot, &j) in anchors.iter().enumerate() {
            anchor_slot[j] = Some(slot);
        }
        Some(Rig {
            skeleton,
            points,
            point_scale,
            reach,
            bone,
            distance,
            parent_scale,
            subtree,
            subtree_parent,
            anchors,
            anchor_slot,
        })
    }

    /// Joint `j`'s position among the anchors, if it is one.
    #[inline]
    pub(super) fn anchor_of(&self, j: usize) -> Option<usize> {
        self.anchor_slot.get(j).copied().flatten()
    }

    /// The origins of one time (`anchors.len()` of them) in `origins` (time-major).
    #[inline]
    pub(super) fn origins_at<'o>(&self, origins: &'o [Vec3], time: usize) -> &'o [Vec3] {
        let n = self.anchors.len();
        origins.get(time * n..(time + 1) * n).unwrap_or(&[])
    }

    /// Joint `j`'s model transform `m` as the error metric measures it at a time whose origins are
    /// `origins` ([`Rig::origins_at`]): an anchor's translation less the source's at that time, so
    /// that its subtree is carried through the chain near the origin (see the module docs: the
    /// same distances in exact arithmetic, without the f32 rounding of coordinates far from it).
    #[inline]
    pub(super) fn rebase(&self, j: usize, origins: &[Vec3], m: &mut Affine3A) {
        if let Some(slot) = self.anchor_of(j) {
            rebase_on(m, origins, slot);
        }
    }

    /// Per joint: how far its rotation error moves error points once the joints with quantized
    /// rotations compensate their parents' (see [`super::eval::Eval`]): its own points, and the
    /// joints below it down to (and including) the first with a compensated rotation on each
    /// branch: a joint without one (a constant or bind rotation) passes its parent's orientation
    /// error on to its children. `compensating`: per joint, whether its rotation is quantized with
    /// compensation. An upper bound (distances summed along the branch).
    pub(super) fn levers(&self, compensating: &[bool]) -> Vec<f32> {
        let n = self.bone.len();
        let parents = self.skeleton.parents();
        // Per joint: how far its error points and the joints below it that its orientation error
        // reaches (through joints that do not compensate) extend from it.
        let mut far = vec![self.distance; n];
        let mut lever = vec![self.distance; n];
        for j in (0..n).rev() {
            let Some(p) = parents.get(j).copied().flatten().map(usize::from) else {
                continue;
            };
            let passes = !compensating.get(j).copied().unwrap_or(false);
            let below = if passes { far[j] } else { 0.0 };
            let reach = self.bone[j] + below.max(if passes { 0.0 } else { self.distance });
            lever[p] = lever[p].max(self.distance.max(reach));
            far[p] = far[p].max(reach);
        }
        lever
    }

    /// Error points of every joint for a local pose, its anchors rebased on `origins`
    /// ([`Rig::rebase`]).
    pub(super) fn points_of(
        &self,
        local: &[Transform],
        origins: &[Vec3],
        m: &mut Vec<Affine3A>,
        out: &mut Vec<[Vec3; 3]>,
    ) {
        self.rebased_fk(local, origins, m);
        out.clear();
        for (a, p) in m.iter().zip(&self.points) {
            out.push(p.map(|x| a.transform_point3(x)));
        }
    }

    /// The model transforms of a local pose, its anchors rebased on `origins` ([`Rig::rebase`]).
    pub(super) fn rebased_fk(
        &self,
        local: &[Transform],
        origins: &[Vec3],
        out: &mut Vec<Affine3A>,
    ) {
        self.anchored_fk(local, out, |slot, m| rebase_on(m, origins, slot));
    }

    /// The model transforms of a local pose, each anchor's handed to `at_anchor` (with its
    /// position among the anchors) before its children are composed with it.
    fn anchored_fk(
        &self,
        local: &[Transform],
        out: &mut Vec<Affine3A>,
        mut at_anchor: impl FnMut(usize, &mut Affine3A),
    ) {
        let parents = self.skeleton.parents();
        out.clear();
        for (j, t) in local.iter().enumerate() {
            let a = t.to_affine();
            let mut m = match parents.get(j).copied().flatten() {
                Some(p) => out.get(p as usize).copied().unwrap_or(Affine3A::IDENTITY) * a,
                None => a,
            };
            if let Some(slot) = self.anchor_of(j) {
                at_anchor(slot, &mut m);
            }
            out.push(m);
        }
    }

    /// Local poses of `clip` at each time (joints not driven keep their bind values).
    pub(super) fn poses(&self, clip: &Clip, times: &[f32]) -> Vec<Vec<Transform>> {
        let binding = ClipBinding::new(clip, &self.skeleton);
        let defaults: Vec<Transform> = if clip.additive() {
            vec![Transform::IDENTITY; self.skeleton.len()]
        } else {
            self.skeleton.bind_local().to_vec()
        };
        let poses_at = |times: &[f32]| -> Vec<Vec<Transform>> {
            let mut sampler = Sampler::new();
            times
                .iter()
                .map(|&t| {
                    let mut pose = defaults.clone();
                    // The output length matches the skeleton and the binding was made for it.
                    let _ = sampler.sample(clip, &binding, &self.skeleton, t, &mut pose);
                    pose
                })
                .collect()
        };
        if self.side_by_side(times.len()) {
            let parts: Vec<Vec<Vec<Transform>>> =
                times.par_chunks(TIMES_PER_CHUNK).map(poses_at).collect();
            parts.into_iter().flatten().collect()
        } else {
            poses_at(times)
        }
    }

    /// Error points for each pose of the source, and the origins they are about (time-major, one
    /// per anchor): each anchor's model-space translation in that pose, so that its own points
    /// have no translation ([`Rig::rebase`]).
    pub(super) fn source_points(
        &self,
        poses: &[Vec<Transform>],
    ) -> (Vec<Vec<[Vec3; 3]>>, Vec<Vec3>) {
        let na = self.anchors.len();
        let points_of = |m: &mut Vec<Affine3A>, pose: &Vec<Transform>| {
            let mut origins = vec![Vec3::ZERO; na];
            self.anchored_fk(pose, m, |slot, mj| {
                if let Some(o) = origins.get_mut(slot) {
                    *o = mj.translation.into();
                }
                rebase_on(mj, &origins, slot);
            });
            let points = m
                .iter()
                .zip(&self.points)
                .map(|(a, p)| p.map(|x| a.transform_point3(x)))
                .collect::<Vec<_>>();
            (points, origins)
        };
        let per_pose: Vec<(Vec<[Vec3; 3]>, Vec<Vec3>)> = if self.side_by_side(poses.len()) {
            poses.par_iter().map_init(Vec::new, points_of).collect()
        } else {
            let mut m = Vec::new();
            poses.iter().map(|p| points_of(&mut m, p)).collect()
        };
        let mut origins = Vec::with_capacity(poses.len() * na);
        let points = per_pose
            .into_iter()
            .map(|(p, o)| {
                origins.extend(o);
                p
            })
            .collect();
        (points, origins)
    }

    /// Whether a pass over `times` source times of a clip on this rig runs in chunks of
    /// [`TIMES_PER_CHUNK`] side by side: from [`PARALLEL_VOLUME`] joint-times on, where the
    /// search's own work is spread too. Every time is computed alone, so the results are the same
    /// either way.
    pub(super) fn side_by_side(&self, times: usize) -> bool {
        times > TIMES_PER_CHUNK && times * self.skeleton.len() >= PARALLEL_VOLUME
    }
}

/// Source times per chunk of a pass over a clip's times that runs side by side
/// ([`Rig::poses`], [`errors_against`]): a chunk's sampler then decodes each segment of a compressed
/// clip about once.
const TIMES_PER_CHUNK: usize = 64;

pub(super) fn point_error<'a>(
    a: &'a [[Vec3; 3]],
    b: &'a [[Vec3; 3]],
) -> impl Iterator<Item = f32> + 'a {
    a.iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|i| p[i].distance(q[i])).fold(0.0f32, f32::max))
}

/// Errors (one per joint per key time of `source`, time-major) of `candidate` against `source`, by the
/// metric of the module docs. Empty when the joints cannot form a skeleton (more than 65535).
pub fn measure(
    source: &Clip,
    candidate: &Clip,
    skeleton: Option<&Skeleton>,
    error_distance: f32,
) -> Vec<f32> {
    let Some(rig) = Rig::new(source, skeleton, error_distance) else {
        return Vec::new();
    };
    let times = source.times();
    let (src, origins) = rig.source_points(&rig.poses(source, times));
    errors_against(&rig, &src, &origins, candidate, times)
}

/// [`measure`] with the source's error points and origins at `times` already computed (`src`,
/// `origins`). Long clips are measured in chunks side by side ([`Rig::poses`]); the errors are the
/// same.
pub(super) fn errors_against(
    rig: &Rig,
    src: &[Vec<[Vec3; 3]>],
    origins: &[Vec3],
    candidate: &Clip,
    times: &[f32],
) -> Vec<f32> {
    let errors_of = |first: usize, times: &[f32]| {
        let mut out = Vec::with_capacity(times.len() * rig.skeleton.len());
        beside_source((rig, src, origins), candidate, first, times, |s, pts| {
            out.extend(point_error(s, pts));
            false
        });
        out
    };
    if rig.side_by_side(times.len()) {
        let parts: Vec<Vec<f32>> = times
            .par_chunks(TIMES_PER_CHUNK)
            .enumerate()
            .map(|(n, chunk)| errors_of(n * TIMES_PER_CHUNK, chunk))
            .collect();
        parts.concat()
    } else {
        errors_of(0, times)
    }
}

/// True when every error of `errors` (time-major, one per joint, as [`errors_against`] gives them)
/// is within its joint's limit.
pub(super) fn within_limits(errors: &[f32], limits: &[f32]) -> bool {
    errors
        .chunks(limits.len().max(1))
        .all(|at| !at.iter().zip(limits).any(|(&e, &l)| exceeds(e, l)))
}

/// Samples `clip` with the runtime's sampler at each of `times` (over the bind pose, or the identity
/// for an additive clip) and calls `stop` with the time's index and the rig's error points (about
/// the source's origins at that time, `origins`: time-major, as [`Rig::source_points`] gives them),
/// until `stop` returns true.
pub(super) fn runtime_points(
    rig: &Rig,
    clip: &Clip,
    times: &[f32],
    origins: &[Vec3],
    mut stop: impl FnMut(usize, &[[Vec3; 3]]) -> bool,
) {
    let binding = ClipBinding::new(clip, &rig.skeleton);
    let mut sampler = Sampler::new();
    let defaults: Vec<Transform> = if clip.additive() {
        vec![Transform::IDENTITY; rig.skeleton.len()]
    } else {
        rig.skeleton.bind_local().to_vec()
    };
    let mut pose = defaults.clone();
    let (mut m, mut pts) = (Vec::new(), Vec::new());
    for (k, &t) in times.iter().enumerate() {
        pose.copy_from_slice(&defaults);
        let _ = sampler.sample(clip, &binding, &rig.skeleton, t, &mut pose);
        rig.points_of(&pose, rig.origins_at(origins, k), &mut m, &mut pts);
        if stop(k, &pts) {
            return;
        }
    }
}

/// [`runtime_points`] over `times`, the source's times from index `first` on (`src`, `origins`:
/// the source's error points and origins at all its times): `stop` gets each time's source points
/// and the candidate's. False when it stopped early, or at a time the source has no points for.
fn beside_source(
    (rig, src, origins): (&Rig, &[Vec<[Vec3; 3]>], &[Vec3]),
    candidate: &Clip,
    first: usize,
    times: &[f32],
    mut stop: impl FnMut(&[[Vec3; 3]], &[[Vec3; 3]]) -> bool,
) -> bool {
    let origins = origins.get(first * rig.anchors.len()..).unwrap_or(&[]);
    let mut whole = true;
    runtime_points(rig, candidate, times, origins, |k, pts| {
        whole = src.get(first + k).is_some_and(|s| !stop(s, pts));
        !whole
    });
    whole
}

/// Whether `candidate` is within `limits` (per joint) at every one of `times`, stopping at the
/// first time it is not (a pass of the runtime's sampler over the times, in order; on a long
/// clip in chunks side by side, as [`errors_against`], each stopping where it fails and the rest
/// not started once one has: the same verdict at any thread count).
pub(super) fn holds_against(
    rig: &Rig,
    src: &[Vec<[Vec3; 3]>],
    origins: &[Vec3],
    candidate: &Clip,
    times: &[f32],
    limits: &[f32],
) -> bool {
    let holds_from = |first: usize, times: &[f32]| {
        let mut holds = true;
        let whole = beside_source((rig, src, origins), candidate, first, times, |s, pts| {
            holds = point_error(s, pts)
                .zip(limits)
                .all(|(e, &l)| !exceeds(e, l));
            !holds
        });
        holds && whole
    };
    if rig.side_by_side(times.len()) {
        times
            .par_chunks(TIMES_PER_CHUNK)
            .enumerate()
            .all(|(n, chunk)| holds_from(n * TIMES_PER_CHUNK, chunk))
    } else {
        holds_from(0, times)
    }
}

/// True when `error` is above `limit` or not a number.
pub(super) fn exceeds(error: f32, limit: f32) -> bool {
    error.is_nan() || error > limit
}

/// How far f32 arithmetic alone may move an error point, per unit of its largest coordinate (about
/// its anchor, [`Rig::rebase`]), as a multiple of `f32::EPSILON`: a one-ulp difference in a local
/// rotation or translation, carried through a chain of parents, moves a point far from the anchor
/// by a few ulps of its coordinates (measured on the corpus: up to 4 ulps between the compiled clip
/// and its source curves).
pub(super) const NOISE_ULPS: f32 = 8.0;

/// Per joint: the error the encoder allows, the tolerance less the f32 noise of the joint's error
/// points ([`NOISE_ULPS`] x epsilon x their largest coordinate about the anchor over the clip), so
/// that the error measured against the source by another computation stays within the tolerance.
/// At least half the tolerance.
pub(super) fn joint_limits(src: &[Vec<[Vec3; 3]>], joints: usize, tolerance: f32) -> Vec<f32> {
    let mut mag = vec![0.0f32; joints];
    for key in src {
        for (m, p) in mag.iter_mut().zip(key) {
            for x in p {
                *m = m.max(x.abs().max_element());
            }
        }
    }
    mag.iter()
        .map(|m| (tolerance - NOISE_ULPS * f32::EPSILON * m).max(0.5 * tolerance))
        .collect()
}
