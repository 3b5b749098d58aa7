//! Which meshes' LOD steps are also built the plain ways (`Step::plain`), and the poses those
//! builds are compared under: what the LOD builder takes from a scene's clips.
//!
//! The plain builds cost 4.0-5.3x the chain's work. They run on every mesh with
//! `LodTuning::plain_candidate` (`convert --effort max`); otherwise on a mesh whose work
//! ([`plain_work`]) is within `LodTuning::plain_work_bound`, and beyond it while the meshes' work
//! fits in the share the file's clips allow ([`SceneMotion`]; docs/lod.md, "Cost"). A static mesh
//! beyond both gets the positions-only build alone ([`PlainSet::Positions`]), a skinned one the
//! posed check of its repair ([`PlainSet::PosedCheck`]), which needs the reference poses too.

use super::step::LodTuning;
use crate::compress::skeleton_extent;
use sinew_core::glam::{Mat4, Vec3};
use sinew_core::{local_to_model, ClipBinding, Lod, Sampler, Skeleton, Transform};
use sinew_scene::{Mesh, SceneClip};

/// How much a mesh's plain builds cost, in LOD 0 triangles measured once: its triangles times
/// `PLAIN_REST_WORK` (the builds themselves and their measurement at rest) plus one for each
/// pose its builds are compared in (when it is skinned to `skeleton`: the two test poses and each
/// of `reference`). What [`LodTuning::plain_work_bound`] bounds (docs/lod.md, "Cost").
pub fn plain_work(lod: &Lod, skeleton: Option<&Skeleton>, reference: &[Vec<Transform>]) -> usize {
    let count = skeleton.map_or(0, |s| {
        reference.iter().filter(|l| l.len() == s.len()).count()
    });
    plain_work_posed(lod, skeleton, count)
}

/// [`plain_work`] with `pose_count` reference poses.
fn plain_work_posed(lod: &Lod, skeleton: Option<&Skeleton>, pose_count: usize) -> usize {
    let poses = match skeleton {
        Some(s) if lod.is_skinned() && !s.is_empty() => 2 + pose_count,
        _ => 0,
    };
    lod.triangle_count().saturating_mul(PLAIN_REST_WORK + poses)
}

/// The plain builds' work at rest in poses' worth ([`plain_work`]): measured, a static mesh's
/// plain builds cost about as much as a skinned one's comparison under eight poses (docs/lod.md,
/// "Cost").
const PLAIN_REST_WORK: usize = 8;

/// Which plain builds ([`super::step::Plain`]) a mesh's LOD steps get beside the step's own build.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum PlainSet {
    /// None: the step's own build alone.
    Off,
    /// The positions-only build alone, measured at rest: a static mesh beyond the bound, where
    /// that build is one simplification and one measurement (docs/lod.md, "Cost").
    Positions,
    /// None, but the step's repair also checked in the reference poses, without a grid per pose
    /// (`measure::hinted_posed_far`): a skinned mesh beyond the bound (docs/lod.md, "A posed
    /// check without a grid per pose").
    PosedCheck,
    /// All six, the step from LOD 0 and the posed repair build.
    All,
}

/// Per mesh, which plain builds its LOD steps get: all of them on every mesh with
/// [`LodTuning::plain_candidate`]; otherwise where its [`plain_work`] is within
/// [`LodTuning::plain_work_bound`], and beyond it while the meshes' work (in mesh order) fits in
/// the scene's clip share (`motion.joint_keys / CLIP_KEYS_PER_PLAIN_WORK`): where the file's clips
/// are large, the plain builds are a small part of the convert (docs/lod.md, "Cost"). A static
/// mesh beyond both gets the positions-only build (its comparison needs no pose); a skinned one
/// the posed check. A bound of 0: none of these on any mesh.
pub(super) fn plain_builds_of(
    meshes: &[Mesh],
    skeleton: Option<&Skeleton>,
    tuning: &LodTuning,
    motion: &SceneMotion,
) -> Vec<PlainSet> {
    let mut share = if tuning.plain_work_bound == 0 {
        0
    } else {
        motion.joint_keys / CLIP_KEYS_PER_PLAIN_WORK
    };
    meshes
        .iter()
        .map(|m| {
            let work = plain_work_posed(&m.geometry, skeleton, motion.pose_count);
            if tuning.plain_candidate || work <= tuning.plain_work_bound {
                return PlainSet::All;
            }
            if work <= share {
                share -= work;
                return PlainSet::All;
            }
            let posed = work != plain_work_posed(&m.geometry, None, 0);
            match (tuning.plain_work_bound == 0, posed) {
                (true, _) => PlainSet::Off,
                (false, true) => PlainSet::PosedCheck,
                (false, false) => PlainSet::Positions,
            }
        })
        .collect()
}

/// Clip joint-keys per unit of [`plain_work`] the clips' share allows: the clip encoder spends
/// 20-61k instructions per joint-key (30-100k when this was set, before session 14's encoder
/// changes) and the plain builds 5-12k per unit (docs/lod.md, "Cost"), so a share of one unit per
/// two joint-keys is a few percent to a third of the encoder's work.
const CLIP_KEYS_PER_PLAIN_WORK: usize = 2;

/// What the LOD builder takes from a scene's clips ([`scene_motion`], [`scene_motion_for`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneMotion {
    /// Poses the plain builds are compared under ([`reference_poses`]); empty when no mesh's
    /// plain builds use them ([`scene_motion_for`]).
    pub poses: Vec<Vec<Transform>>,
    /// How many reference poses the clips give ([`reference_pose_count`]): what [`plain_work`]
    /// counts, whether or not `poses` were made.
    pub pose_count: usize,
    /// The clips' size ([`clip_joint_keys`]), which sets how much plain-build work meshes beyond
    /// [`LodTuning::plain_work_bound`] may share.
    pub joint_keys: usize,
}

/// [`SceneMotion`] of `clips`, with its reference poses (only with a skeleton).
pub fn scene_motion(clips: &[SceneClip], skeleton: Option<&Skeleton>) -> SceneMotion {
    let poses = skeleton.map_or_else(Vec::new, |s| reference_poses(clips, s));
    SceneMotion {
        pose_count: poses.len(),
        poses,
        joint_keys: clip_joint_keys(clips),
    }
}

/// [`SceneMotion`] of `clips` for LODs of `meshes` with `tuning`: the reference poses are made
/// only when some skinned mesh gets the plain builds or the posed check, all that compare under
/// them (picking them samples each clip 64 times: 0.5 and 0.8 ms on ninja's and Fox's clips,
/// 2.3-3.0 ms on a Half-Life model's first 16 sequences, against 0.2-0.8 ms for poses at fixed
/// times; docs/lod.md, session 32).
/// The same plain builds and the same LODs as with [`scene_motion`].
pub fn scene_motion_for(
    clips: &[SceneClip],
    skeleton: Option<&Skeleton>,
    meshes: &[Mesh],
    tuning: &LodTuning,
) -> SceneMotion {
    let mut motion = SceneMotion {
        poses: Vec::new(),
        pose_count: skeleton.map_or(0, |_| reference_pose_count(clips)),
        joint_keys: clip_joint_keys(clips),
    };
    let used = plain_builds_of(meshes, skeleton, tuning, &motion)
        .iter()
        .zip(meshes)
        .any(|(p, m)| matches!(p, PlainSet::All | PlainSet::PosedCheck) && m.geometry.is_skinned());
    if let (true, Some(s)) = (used, skeleton) {
        motion.poses = reference_poses(clips, s);
    }
    motion
}

/// The clips' size as the clip encoder's work grows with it: per clip, per track, the most keys
/// of its channels, summed.
pub fn clip_joint_keys(clips: &[SceneClip]) -> usize {
    clips
        .iter()
        .flat_map(|c| &c.tracks)
        .map(|t| {
            t.translation
                .times
                .len()
                .max(t.rotation.times.len())
                .max(t.scale.times.len())
        })
        .sum()
}

/// Poses sampled from each clip, at most this many in all.
const REFERENCE_POSES: usize = 16;
/// Poses sampled from one clip, at most.
const REFERENCE_POSES_PER_CLIP: usize = 8;
/// The times of a clip its reference poses are picked from: the middles of this many equal parts.
const POSE_CANDIDATES: usize = 64;
/// The reach of the points a pose is compared by, as a fraction of the skeleton's extent
/// ([`skeleton_extent`], [`joint_points`]).
const POSE_REACH: f32 = 0.1;

/// The reference poses the plain builds are compared under besides the test poses
/// ([`LodTuning::plain_candidate`]), at most `REFERENCE_POSES` in all, the same number from each
/// clip (`REFERENCE_POSES_PER_CLIP` at most; the first clips' first when there are more than 16).
/// Each clip's are picked from its local poses (the runtime's sampler) at the middles of
/// `POSE_CANDIDATES` equal parts of its duration, farthest first: each time the pose farthest from
/// its nearest among the bind pose and the clip's poses picked before, distance being the
/// largest of the distances between the joints' model-space frames ([`joint_points`]); ties the
/// earlier. So a brief unusual pose (a transition between a clip's actions) is compared under
/// where poses at fixed times pass it by (docs/lod.md, session 32). A clip's are in time order.
/// As many as [`reference_pose_count`] says.
pub fn reference_poses(clips: &[SceneClip], skeleton: &Skeleton) -> Vec<Vec<Transform>> {
    let per_clip = reference_poses_per_clip(clips);
    let bind = skeleton.bind_local();
    let reach = skeleton_extent(skeleton) * POSE_REACH;
    let at_bind = joint_points(skeleton, bind, reach);
    let mut poses = Vec::new();
    let mut sampler = Sampler::new();
    for c in clips {
        let take = per_clip.min(REFERENCE_POSES - poses.len());
        if take == 0 {
            break;
        }
        // A clip that does not compile (a scene that converts has none) gives the bind pose, so
        // that the count is [`reference_pose_count`]'s.
        let Ok(clip) = c.to_clip() else {
            poses.extend(std::iter::repeat_n(bind.to_vec(), take));
            continue;
        };
        let binding = ClipBinding::new(&clip, skeleton);
        let mut candidates: Vec<(Vec<Transform>, Vec<Vec3>)> = (0..POSE_CANDIDATES)
            .map(|k| {
                let at = clip.duration() * (k as f32 + 0.5) / POSE_CANDIDATES as f32;
                let mut locals = bind.to_vec();
                // Cannot fail: `locals` and the binding are of `skeleton`; the bind pose if it did.
                if sampler
                    .sample(&clip, &binding, skeleton, at, &mut locals)
                    .is_err()
                {
                    locals = bind.to_vec();
                }
                let points = joint_points(skeleton, &locals, reach);
                (locals, points)
            })
            .collect();
        // Per candidate: its distance to the nearest of the bind pose and the clip's poses picked.
        let mut nearest: Vec<f32> = candidates
            .iter()
            .map(|(_, p)| pose_distance(p, &at_bind))
            .collect();
        let mut picked: Vec<usize> = Vec::new();
        while picked.len() < take {
            let mut best: Option<(usize, f32)> = None;
            for (i, &d) in nearest.iter().enumerate() {
                if !picked.contains(&i) && best.is_none_or(|(_, b)| d > b) {
                    best = Some((i, d));
                }
            }
            let Some((i, _)) = best else {
                break;
            };
            picked.push(i);
            for (n, (_, p)) in nearest.iter_mut().zip(&candidates) {
                *n = n.min(pose_distance(p, &candidates[i].1));
            }
        }
        picked.sort_unstable();
        poses.extend(
            picked
                .into_iter()
                .map(|i| std::mem::take(&mut candidates[i].0)),
        );
    }
    poses
}

/// How many reference poses [`reference_poses`] makes of `clips` (with a skeleton), without
/// sampling them.
pub fn reference_pose_count(clips: &[SceneClip]) -> usize {
    let per_clip = reference_poses_per_clip(clips);
    (clips.len() * per_clip).min(REFERENCE_POSES)
}

/// Reference poses per clip: 16 shared among the clips, at most 8 and at least 1 each.
fn reference_poses_per_clip(clips: &[SceneClip]) -> usize {
    (REFERENCE_POSES / clips.len().max(1)).clamp(1, REFERENCE_POSES_PER_CLIP)
}

/// The largest distance between the same points of two poses ([`joint_points`]).
fn pose_distance(a: &[Vec3], b: &[Vec3]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p.distance(*q))
        .fold(0.0, f32::max)
}

/// Each joint's model-space origin and the points `reach` along its three axes, under `locals`
/// (nothing if the skeleton's parents are out of order).
fn joint_points(skeleton: &Skeleton, locals: &[Transform], reach: f32) -> Vec<Vec3> {
    let mut models = vec![Mat4::IDENTITY; locals.len()];
    if local_to_model(skeleton.parents(), locals, &mut models).is_err() {
        return Vec::new();
    }
    models
        .iter()
        .flat_map(|m| {
            [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z].map(|a| m.transform_point3(a * reach))
        })
        .collect()
}
