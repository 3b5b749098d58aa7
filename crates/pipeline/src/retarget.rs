//! Retargeting: playing a motion whose rest pose differs from the rig's bind pose (a BVH walk, whose rest
//! pose is offsets with identity rotations, on a Half-Life Biped rig with rotated binds).
//!
//! Copying local rotations from one skeleton to another is only right when both have the same local
//! frames. [`retarget`] instead transfers each bound joint's rotation as a *change from the source's rest
//! pose*, in model space, onto the rig's bind pose:
//!
//! ```text
//! delta_model(j)   = Q_src_anim_model(s) * Q_src_rest_model(s)^-1
//! Q_tgt_model(j)   = delta_model(j) * Q_tgt_bind_model(j)
//! Q_tgt_local(j)   = Q_tgt_model(parent j)^-1 * Q_tgt_model(j)      (parent's *animated* rotation)
//! ```
//!
//! where `s` is the motion joint bound to rig joint `j`. Unbound rig joints keep their bind local
//! rotation. The root translation (of each bound joint whose motion joint has translation keys and no
//! bound ancestor with translation keys, normally the hips) is moved by its change from rest, rotated from
//! the source parent's model frame into the target parent's, and scaled by the ratio of leg lengths
//! (hip-to-foot chain length, target over source, from the thigh and foot slots of the mapping).
//!
//! Assumptions: both skeletons share the model-space axes (same up and forward) and have unit scale;
//! scale keys are not transferred. Other translations stay at the rig's bind values.

use crate::mapping::{Mapping, Side, Slot};
use sinew_core::clip::nlerp;
use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Curve, Skeleton, TrackCurves, Transform};
use sinew_scene::{Diagnostic, SceneClip};
use std::collections::HashMap;

/// Default threshold, degrees, above which `convert` warns that a bound joint's rest and bind
/// orientations differ (see [`rest_orientation_differences`]).
pub const REST_DIFFERENCE_WARN_DEGREES: f32 = 5.0;

/// Why a clip could not be retargeted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RetargetError {
    /// The mapping names a motion joint the source skeleton does not have.
    #[error("mapping names motion joint {0:?}, which the source skeleton does not have")]
    UnknownSourceJoint(String),
    /// The mapping names a rig joint the target skeleton does not have.
    #[error("mapping names rig joint {0:?}, which the target skeleton does not have")]
    UnknownTargetJoint(String),
    /// Additive clips store differences, not poses; they cannot be retargeted this way.
    #[error("clip {0:?} is additive; only absolute clips can be retargeted")]
    Additive(String),
}

/// A retargeted clip and the figures behind it.
#[derive(Debug, Clone, PartialEq)]
pub struct Retargeted {
    /// The clip, with tracks named by rig joints: a rotation track for every bound rig joint and a
    /// translation track for each root joint. Not additive; name, duration, rate and looping kept.
    pub clip: SceneClip,
    /// Factor applied to the root translation's change from rest (1 when no leg was found).
    pub leg_scale: f32,
    /// Summed hip-to-foot chain lengths `(source, target)` over the legs found, if any.
    pub leg_lengths: Option<(f32, f32)>,
    /// Rig joints whose translation was transferred (normally the one bound to the hips).
    pub root_joints: Vec<String>,
    /// Notes: no legs found, and so on.
    pub diagnostics: Vec<Diagnostic>,
}

/// A bound joint pair whose rest (source) and bind (target) orientations differ.
#[derive(Debug, Clone, PartialEq)]
pub struct RestDifference {
    /// Rig joint.
    pub rig: String,
    /// Motion joint.
    pub motion: String,
    /// Angle between the two model-space orientations, degrees, in `[0, 180]`.
    pub degrees: f32,
}

/// Model-space rotations of a pose given as locals in parent-before-child order.
fn model_rotations(parents: &[Option<u16>], local: impl Fn(usize) -> Quat) -> Vec<Quat> {
    let mut out: Vec<Quat> = Vec::with_capacity(parents.len());
    for (i, p) in parents.iter().enumerate() {
        let l = local(i);
        let q = match p.and_then(|p| out.get(p as usize)) {
            Some(pq) => (*pq * l).normalize(),
            None => l.normalize(),
        };
        out.push(q);
    }
    out
}

/// Model-space positions of the bind pose (unit scale assumed).
fn bind_positions(skeleton: &Skeleton) -> Vec<Vec3> {
    let bind = skeleton.bind_local();
    let rot = model_rotations(skeleton.parents(), |i| bind[i].rotation);
    let mut out: Vec<Vec3> = Vec::with_capacity(bind.len());
    for (i, p) in skeleton.parents().iter().enumerate() {
        let t = bind[i].translation;
        let pos = match p.map(|p| p as usize).filter(|&p| p < out.len()) {
            Some(p) => out[p] + rot[p] * t,
            None => t,
        };
        out.push(pos);
    }
    out
}

fn angle_degrees(q: Quat) -> f32 {
    let w = q.normalize().w.abs().min(1.0);
    (2.0 * w.acos()).to_degrees()
}

/// For every bound pair, the angle between the motion joint's model-space rest orientation and the rig
/// joint's model-space bind orientation, in rig order. Pairs naming a joint missing from either
/// skeleton are skipped. Copying local rotations without [`retarget`] is only right where this is
/// near zero along the whole chain; `convert` warns above [`REST_DIFFERENCE_WARN_DEGREES`].
pub fn rest_orientation_differences(
    source: &Skeleton,
    target: &Skeleton,
    mapping: &Mapping,
) -> Vec<RestDifference> {
    let sb = source.bind_local();
    let tb = target.bind_local();
    let src_rest = model_rotations(source.parents(), |i| sb[i].rotation);
    let tgt_bind = model_rotations(target.parents(), |i| tb[i].rotation);
    mapping
        .pairs()
        .filter_map(|(r, m)| {
            let t = target.find(r)? as usize;
            let s = source.find(m)? as usize;
            let d = tgt_bind[t] * src_rest[s].inverse();
            Some(RestDifference {
                rig: r.to_string(),
                motion: m.to_string(),
                degrees: angle_degrees(d),
            })
        })
        .collect()
}

/// Linear sample of a curve at `t` (clamped), or `None` when empty.
fn sample_vec3(c: &Curve<Vec3>, t: f32) -> Option<Vec3> {
    let (a, b, f) = locate(&c.times, c.values.len(), t)?;
    Some(c.values[a].lerp(c.values[b], f))
}

fn sample_quat(c: &Curve<Quat>, t: f32) -> Option<Quat> {
    let (a, b, f) = locate(&c.times, c.values.len(), t)?;
    Some(nlerp(c.values[a], c.values[b], f))
}

/// Indices of the keys around `t` and the blend factor; tolerant of malformed curves.
fn locate(times: &[f32], len: usize, t: f32) -> Option<(usize, usize, f32)> {
    let n = times.len().min(len);
    if n == 0 {
        return if len > 0 { Some((0, 0, 0.0)) } else { None };
    }
    let k = times[..n].partition_point(|&x| x <= t);
    if k == 0 {
        return Some((0, 0, 0.0));
    }
    if k >= n {
        return Some((n - 1, n - 1, 0.0));
    }
    let (t0, t1) = (times[k - 1], times[k]);
    let f = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
    Some((k - 1, k, f.clamp(0.0, 1.0)))
}

/// Summed hip-to-foot chain length of the mapped legs, per skeleton.
fn leg_lengths(source: &Skeleton, target: &Skeleton, mapping: &Mapping) -> Option<(f32, f32)> {
    let sp = bind_positions(source);
    let tp = bind_positions(target);
    let chain = |sk: &Skeleton, pos: &[Vec3], thigh: usize, foot: usize| -> f32 {
        let mut len = 0.0;
        let mut j = foot;
        let mut steps = 0;
        while j != thigh {
            let Some(p) = sk.parents().get(j).copied().flatten().map(usize::from) else {
                return pos[foot].distance(pos[thigh]);
            };
            len += pos[j].distance(pos[p]);
            j = p;
            steps += 1;
            if steps > sk.len() {
                return pos[foot].distance(pos[thigh]);
            }
        }
        len
    };
    let find = |slot: Slot, side: Side| {
        mapping
            .entries
            .iter()
            .find(|e| e.slot == Some(slot) && e.side == side && e.motion.is_some())
    };
    let (mut s_total, mut t_total, mut found) = (0.0f32, 0.0f32, false);
    for side in [Side::Left, Side::Right] {
        let (Some(th), Some(ft)) = (find(Slot::Thigh, side), find(Slot::Foot, side)) else {
            continue;
        };
        let (Some(tt), Some(tf)) = (target.find(&th.rig), target.find(&ft.rig)) else {
            continue;
        };
        let (Some(st), Some(sf)) = (
            th.motion.as_deref().and_then(|m| source.find(m)),
            ft.motion.as_deref().and_then(|m| source.find(m)),
        ) else {
            continue;
        };
        s_total += chain(source, &sp, st as usize, sf as usize);
        t_total += chain(target, &tp, tt as usize, tf as usize);
        found = true;
    }
    found.then_some((s_total, t_total))
}

/// Retargets `clip` (tracks named by `source` joints) onto `target` through `mapping` (rig = target,
/// motion = source). See the module docs for the formulas.
///
/// Keys: one key per distinct key time of the clip's tracks (all curves sampled there). Errors when the
/// mapping names joints the skeletons lack, or the clip is additive.
pub fn retarget(
    clip: &SceneClip,
    source: &Skeleton,
    target: &Skeleton,
    mapping: &Mapping,
) -> Result<Retargeted, RetargetError> {
    if clip.additive {
        return Err(RetargetError::Additive(clip.name.clone()));
    }
    let mut src_of: Vec<Option<usize>> = vec![None; target.len()];
    let mut bound_src = vec![false; source.len()];
    for (r, m) in mapping.pairs() {
        let t = target
            .find(r)
            .ok_or_else(|| RetargetError::UnknownTargetJoint(r.to_string()))?;
        let s = source
            .find(m)
            .ok_or_else(|| RetargetError::UnknownSourceJoint(m.to_string()))?;
        src_of[t as usize] = Some(s as usize);
        bound_src[s as usize] = true;
    }
    let mut track_of: HashMap<&str, &TrackCurves> = HashMap::new();
    for t in &clip.tracks {
        track_of.entry(t.joint.as_str()).or_insert(t);
    }
    let src_tracks: Vec<Option<&TrackCurves>> = source
        .names()
        .iter()
        .map(|n| track_of.get(n.as_str()).copied())
        .collect();

    // Key times: the union of the source tracks' key times.
    let mut times: Vec<f32> = src_tracks
        .iter()
        .flatten()
        .flat_map(|t| {
            t.translation
                .times
                .iter()
                .chain(&t.rotation.times)
                .chain(&t.scale.times)
        })
        .copied()
        .filter(|t| t.is_finite())
        .collect();
    times.sort_by(f32::total_cmp);
    times.dedup();
    if times.is_empty() {
        times.push(0.0);
    }

    let sb = source.bind_local();
    let tb = target.bind_local();
    let src_rest = model_rotations(source.parents(), |i| sb[i].rotation);
    let tgt_bind = model_rotations(target.parents(), |i| tb[i].rotation);

    // Root joints: bound, with translation keys, and no bound ancestor with translation keys.
    let translating =
        |s: usize| bound_src[s] && src_tracks[s].is_some_and(|t| !t.translation.is_empty());
    let is_root = |s: usize| {
        if !translating(s) {
            return false;
        }
        let mut j = s;
        let mut steps = 0;
        while let Some(p) = source.parents()[j].map(usize::from) {
            if translating(p) {
                return false;
            }
            j = p;
            steps += 1;
            if steps > source.len() {
                break;
            }
        }
        true
    };
    let root_target: Vec<bool> = src_of.iter().map(|s| s.is_some_and(is_root)).collect();

    let mut diagnostics = Vec::new();
    let lengths = leg_lengths(source, target, mapping);
    let leg_scale = match lengths {
        Some((s, t)) if s > 1e-6 && t.is_finite() => t / s,
        _ => {
            diagnostics.push(Diagnostic::warning(
                "retarget-no-legs",
                "no bound thigh and foot pair found (or zero source leg length); root translation \
                 is not scaled",
            ));
            1.0
        }
    };

    let mut rot_values: Vec<Vec<Quat>> = vec![Vec::with_capacity(times.len()); target.len()];
    let mut trans_values: Vec<Vec<Vec3>> = vec![Vec::new(); target.len()];
    let mut src_local: Vec<Transform> = sb.to_vec();
    for &t in &times {
        for (s, local) in src_local.iter_mut().enumerate() {
            *local = sb[s];
            if let Some(track) = src_tracks[s] {
                if let Some(v) = sample_vec3(&track.translation, t) {
                    local.translation = v;
                }
                if let Some(q) = sample_quat(&track.rotation, t) {
                    local.rotation = q;
                }
            }
        }
        let src_anim = model_rotations(source.parents(), |i| src_local[i].rotation);
        let mut tgt_model: Vec<Quat> = Vec::with_capacity(target.len());
        for (j, p) in target.parents().iter().enumerate() {
            let parent = p
                .and_then(|p| tgt_model.get(p as usize))
                .copied()
                .unwrap_or(Quat::IDENTITY);
            let model = match src_of[j] {
                Some(s) => {
                    let delta = src_anim[s] * src_rest[s].inverse();
                    let model = (delta * tgt_bind[j]).normalize();
                    let mut local = (parent.inverse() * model).normalize();
                    if let Some(prev) = rot_values[j].last() {
                        if prev.dot(local) < 0.0 {
                            local = -local;
                        }
                    }
                    rot_values[j].push(local);
                    if root_target[j] {
                        let src_parent = source.parents()[s]
                            .map(|p| src_anim[p as usize])
                            .unwrap_or(Quat::IDENTITY);
                        let change = src_parent * (src_local[s].translation - sb[s].translation);
                        let moved = parent.inverse() * (change * leg_scale);
                        trans_values[j].push(tb[j].translation + moved);
                    }
                    model
                }
                None => (parent * tb[j].rotation).normalize(),
            };
            tgt_model.push(model);
        }
    }

    let mut tracks = Vec::new();
    let mut root_joints = Vec::new();
    for (j, name) in target.names().iter().enumerate() {
        if src_of[j].is_none() {
            continue;
        }
        let translation = if root_target[j] {
            root_joints.push(name.clone());
            Curve::new(times.clone(), std::mem::take(&mut trans_values[j]))
        } else {
            Curve::default()
        };
        tracks.push(TrackCurves {
            joint: name.clone(),
            translation,
            rotation: Curve::new(times.clone(), std::mem::take(&mut rot_values[j])),
            scale: Curve::default(),
        });
    }
    Ok(Retargeted {
        clip: SceneClip {
            name: clip.name.clone(),
            duration: clip.duration,
            sample_rate: clip.sample_rate,
            looping: clip.looping,
            additive: false,
            tracks,
        },
        leg_scale,
        leg_lengths: lengths,
        root_joints,
        diagnostics,
    })
}
