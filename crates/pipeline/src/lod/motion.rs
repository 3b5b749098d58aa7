//! Which meshes' LOD steps are also built the plain ways (`Step::plain`), and the poses those
//! builds are compared under: what the LOD builder takes from a scene's clips.
//!
//! The plain builds cost 4.0-5.3x the chain's work. They run on every mesh with
//! `LodTuning::plain_candidate` (`convert --effort max`); otherwise on a mesh whose work
//! ([`plain_work`]) is within `LodTuning::plain_work_bound`, and beyond it while the meshes' work
//! fits in the share the file's clips allow ([`SceneMotion`]; docs/lod.md, "Cost"). A static mesh
//! beyond both gets the positions-only build alone ([`PlainSet::Positions`]).

use super::step::LodTuning;
use sinew_core::{ClipBinding, Lod, Sampler, Skeleton, Transform};
use sinew_scene::{Mesh, SceneClip};

/// How much a mesh's plain builds cost, in LOD 0 triangles measured once: its triangles times
/// `PLAIN_REST_WORK` (the builds themselves and their measurement at rest) plus one for each
/// pose its builds are compared in (when it is skinned to `skeleton`: the two test poses and each
/// of `reference`). What [`LodTuning::plain_work_bound`] bounds (docs/lod.md, "Cost").
pub fn plain_work(lod: &Lod, skeleton: Option<&Skeleton>, reference: &[Vec<Transform>]) -> usize {
    let poses = match skeleton {
        Some(s) if lod.is_skinned() && !s.is_empty() => {
            2 + reference.iter().filter(|l| l.len() == s.len()).count()
        }
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
    /// All six, the step from LOD 0 and the posed repair build.
    All,
}

/// Per mesh, which plain builds its LOD steps get: all of them on every mesh with
/// [`LodTuning::plain_candidate`]; otherwise where its [`plain_work`] is within
/// [`LodTuning::plain_work_bound`], and beyond it while the meshes' work (in mesh order) fits in
/// the scene's clip share (`motion.joint_keys / CLIP_KEYS_PER_PLAIN_WORK`): where the file's clips
/// are large, the plain builds are a small part of the convert (docs/lod.md, "Cost"). A static
/// mesh beyond both gets the positions-only build (its comparison needs no pose); a skinned one
/// none. A bound of 0: none on any mesh.
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
            let work = plain_work(&m.geometry, skeleton, &motion.poses);
            if tuning.plain_candidate || work <= tuning.plain_work_bound {
                return PlainSet::All;
            }
            if work <= share {
                share -= work;
                return PlainSet::All;
            }
            let posed = work != plain_work(&m.geometry, None, &[]);
            if tuning.plain_work_bound == 0 || posed {
                PlainSet::Off
            } else {
                PlainSet::Positions
            }
        })
        .collect()
}

/// Clip joint-keys per unit of [`plain_work`] the clips' share allows: the clip encoder spends
/// 20-61k instructions per joint-key (30-100k when this was set, before session 14's encoder
/// changes) and the plain builds 5-12k per unit (docs/lod.md, "Cost"), so a share of one unit per
/// two joint-keys is a few percent to a third of the encoder's work.
const CLIP_KEYS_PER_PLAIN_WORK: usize = 2;

/// What the LOD builder takes from a scene's clips ([`scene_motion`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneMotion {
    /// Poses the plain builds are compared under ([`reference_poses`]).
    pub poses: Vec<Vec<Transform>>,
    /// The clips' size ([`clip_joint_keys`]), which sets how much plain-build work meshes beyond
    /// [`LodTuning::plain_work_bound`] may share.
    pub joint_keys: usize,
}

/// [`SceneMotion`] of `clips` (poses only with a skeleton).
pub fn scene_motion(clips: &[SceneClip], skeleton: Option<&Skeleton>) -> SceneMotion {
    SceneMotion {
        poses: skeleton.map_or_else(Vec::new, |s| reference_poses(clips, s)),
        joint_keys: clip_joint_keys(clips),
    }
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

/// The reference poses the plain builds are compared under besides the test poses
/// ([`LodTuning::plain_candidate`]): each clip's local pose (the runtime's sampler) at the middle
/// of each eighth of its duration, at most `REFERENCE_POSES` in all, the first clips' first
/// (fewer per clip when there are more than two clips). A clip that does not bind gives none.
pub fn reference_poses(clips: &[SceneClip], skeleton: &Skeleton) -> Vec<Vec<Transform>> {
    let per_clip = (REFERENCE_POSES / clips.len().max(1)).clamp(1, REFERENCE_POSES_PER_CLIP);
    let mut poses = Vec::new();
    let mut sampler = Sampler::new();
    for c in clips {
        let Ok(clip) = c.to_clip() else {
            continue;
        };
        let binding = ClipBinding::new(&clip, skeleton);
        for k in 0..per_clip {
            if poses.len() == REFERENCE_POSES {
                return poses;
            }
            let at = clip.duration() * (k as f32 + 0.5) / per_clip as f32;
            let mut locals = skeleton.bind_local().to_vec();
            if sampler
                .sample(&clip, &binding, skeleton, at, &mut locals)
                .is_ok()
            {
                poses.push(locals);
            }
        }
    }
    poses
}
