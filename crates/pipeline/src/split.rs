//! Partial-body clips and joint masks.
//!
//! [`split_clip`] cuts a clip in two at one or more joints: `NAME.upper` keeps the tracks of the joints in
//! the subtrees under the `at` joints (e.g. `walk.upper` under `Bip01 Spine`: spine, arms, neck, head),
//! `NAME.lower` keeps every other track (`walk.lower`: root, pelvis, legs). Each drives only its own
//! joints, so a runtime can play an upper-body clip over a lower-body one. [`clip_for_mask`] does the same
//! for a hand-made joint set given as `NAME=JOINT,JOINT...` ([`parse_mask_spec`]); [`mask_from_joints`]
//! and [`mask_from_subtrees`] give per-joint blend weights for the runtime's masked layers.

use sinew_core::Skeleton;
use sinew_scene::SceneClip;

/// Suffix of the clip holding the subtrees under the split joints.
pub const UPPER_SUFFIX: &str = "upper";
/// Suffix of the clip holding everything else.
pub const LOWER_SUFFIX: &str = "lower";

/// Why a split or mask could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SplitError {
    /// A joint name the skeleton does not have.
    #[error("joint {0:?} does not exist in the skeleton")]
    UnknownJoint(String),
    /// No joint was given.
    #[error("no joint given to split at")]
    NoJoints,
    /// A mask specification that is not `NAME=JOINT,JOINT...`.
    #[error("mask {spec:?}: {message}")]
    BadMaskSpec {
        /// The specification as given.
        spec: String,
        /// What is wrong.
        message: String,
    },
}

/// A named joint set from `--mask NAME=JOINT,JOINT...`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MaskSpec {
    /// Mask name; the masked clip is called `CLIP.NAME`.
    pub name: String,
    /// Joint names, in the order given.
    pub joints: Vec<String>,
}

/// Parses `NAME=JOINT,JOINT...`. The name is everything before the first `=`; joints are separated by
/// commas (names may contain spaces: `arms=Bip01 L UpperArm,Bip01 R UpperArm`); whitespace around each
/// part is trimmed. Errors on a missing `=`, an empty name, an empty joint or a name containing `.`.
pub fn parse_mask_spec(spec: &str) -> Result<MaskSpec, SplitError> {
    let bad = |message: &str| SplitError::BadMaskSpec {
        spec: spec.to_string(),
        message: message.to_string(),
    };
    let (name, list) = spec
        .split_once('=')
        .ok_or_else(|| bad("expected NAME=JOINT,JOINT..."))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(bad("empty mask name"));
    }
    if name.contains('.') {
        return Err(bad("mask name may not contain '.'"));
    }
    let joints: Vec<String> = list.split(',').map(|j| j.trim().to_string()).collect();
    if joints.iter().any(String::is_empty) {
        return Err(bad("empty joint name"));
    }
    Ok(MaskSpec {
        name: name.to_string(),
        joints,
    })
}

fn index_of(skeleton: &Skeleton, name: &str) -> Result<usize, SplitError> {
    skeleton
        .find(name)
        .map(usize::from)
        .ok_or_else(|| SplitError::UnknownJoint(name.to_string()))
}

/// Per-joint weights in skeleton order: 1.0 for the named joints, 0.0 for the others.
pub fn mask_from_joints<S: AsRef<str>>(
    skeleton: &Skeleton,
    names: &[S],
) -> Result<Vec<f32>, SplitError> {
    let mut mask = vec![0.0; skeleton.len()];
    for n in names {
        mask[index_of(skeleton, n.as_ref())?] = 1.0;
    }
    Ok(mask)
}

/// Per-joint weights in skeleton order: 1.0 for the named joints and all their descendants, else 0.0.
pub fn mask_from_subtrees<S: AsRef<str>>(
    skeleton: &Skeleton,
    roots: &[S],
) -> Result<Vec<f32>, SplitError> {
    let mut mask = vec![0.0; skeleton.len()];
    for r in roots {
        let i = index_of(skeleton, r.as_ref())?;
        for j in skeleton.subtree(i as u16) {
            mask[j as usize] = 1.0;
        }
    }
    Ok(mask)
}

/// A copy of `clip` named `name` keeping the tracks for which `keep(joint name)` is true.
fn filtered(clip: &SceneClip, name: String, keep: impl Fn(&str) -> bool) -> SceneClip {
    SceneClip {
        name,
        tracks: clip
            .tracks
            .iter()
            .filter(|t| keep(&t.joint))
            .cloned()
            .collect(),
        ..clip.clone()
    }
}

/// Splits a clip into `(NAME.upper, NAME.lower)` at the subtrees under `at` (see the module docs).
///
/// Tracks naming joints the skeleton does not have go to the lower clip (they drive nothing either
/// way). Duration, rate, looping and additivity are kept on both. Errors when `at` is empty or names
/// a joint the skeleton does not have.
pub fn split_clip(
    clip: &SceneClip,
    skeleton: &Skeleton,
    at: &[&str],
) -> Result<(SceneClip, SceneClip), SplitError> {
    if at.is_empty() {
        return Err(SplitError::NoJoints);
    }
    let mask = mask_from_subtrees(skeleton, at)?;
    let upper = |joint: &str| {
        skeleton
            .find(joint)
            .is_some_and(|i| mask.get(i as usize).is_some_and(|&w| w > 0.5))
    };
    Ok((
        filtered(clip, format!("{}.{UPPER_SUFFIX}", clip.name), upper),
        filtered(clip, format!("{}.{LOWER_SUFFIX}", clip.name), |j| !upper(j)),
    ))
}

/// A clip named `CLIP.MASK` keeping only the tracks of the mask's joints (exactly those, not their
/// subtrees). Errors when the mask names a joint the skeleton does not have.
pub fn clip_for_mask(
    clip: &SceneClip,
    skeleton: &Skeleton,
    mask: &MaskSpec,
) -> Result<SceneClip, SplitError> {
    for j in &mask.joints {
        index_of(skeleton, j)?;
    }
    Ok(filtered(
        clip,
        format!("{}.{}", clip.name, mask.name),
        |j| mask.joints.iter().any(|m| m == j),
    ))
}
/// Gives the clips made from `source` the source's game data (activity, events, motion, blend), so a
/// split Half-Life sequence keeps them; the source's record is dropped unless `keep_source`.
pub fn carry_game_data(
    game: &mut sinew_scene::GameData,
    source: &str,
    made: &[String],
    keep_source: bool,
) {
    let Some(at) = game.clips.iter().position(|c| c.clip == source) else {
        return;
    };
    let record = if keep_source {
        game.clips[at].clone()
    } else {
        game.clips.remove(at)
    };
    for (k, name) in made.iter().enumerate() {
        let mut r = record.clone();
        r.clip = name.clone();
        game.clips
            .insert((at + k + usize::from(keep_source)).min(game.clips.len()), r);
    }
}
