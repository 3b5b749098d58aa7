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
//! rotation.
//!
//! # Root translation
//!
//! The root translation (of each bound joint whose motion joint has translation keys and no bound
//! ancestor with translation keys, normally the hips) is moved by its change from a *standing*
//! reference, rotated from the source parent's model frame into the target parent's, and scaled by
//! the **root scale** `k`:
//!
//! ```text
//! change(t)  = R_src_parent(t) * (t_src_local(t) - t_src_rest_local) + (0, standing_shift, 0)
//! t_tgt(t)   = t_tgt_bind + R_tgt_parent(t)^-1 * (k * change(t))
//! k          = hip_height(rig) / hip_height(motion)           (or the caller's override)
//! hip_height = height (model y) of the root joint above the mapped foot joints (the lower of the two),
//!              in the rest pose (motion) / bind pose (rig)
//! standing_shift = rest root y - (lowest foot y over the clip + hip_height(motion))
//!                = rest foot y - lowest foot y over the clip
//! ```
//!
//! The standing shift is what a motion file's rest pose can get wrong about its floor: a BVH rest
//! pose is the `OFFSET`s (the root at 0, so the feet hang below the origin) while its root channels
//! are absolute heights above the capture floor. Measuring from the lowest the feet reach over the
//! clip puts the motion's standing hips at zero change, so the rig's feet land on its own bind-pose
//! floor in any unit. It is applied only when the rest pose's feet are more than
//! [`STANDING_SHIFT_MIN`] of the motion's hip height away from that lowest point (otherwise 0: the
//! rest pose stands on the clip's floor, and a clip whose feet dip or lift a little keeps its change
//! from rest exactly). When it is applied, the rest pose is not trusted for the vertical either, and
//! the result is **grounded**: after the rotations and the scaled root are transferred, one constant
//! height is added to the root so that the lowest the rig's feet reach over the clip equals their
//! height in the rig's bind pose. This absorbs what the hip heights miss, e.g. a CMU rest pose whose
//! legs splay outwards (its vertical hip height is shorter than the legs the walk straightens).
//! Without a bound pair of feet the lowest joint of each skeleton stands in for them (a
//! `retarget-no-feet` note). Horizontal motion keeps its change from the rest pose, scaled.
//!
//! Assumptions: both skeletons share the model-space axes (+Y up, same forward) and have unit scale;
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

/// Fraction of the motion's hip height by which the rest pose's feet must miss the clip's lowest
/// feet before the standing shift is applied (see the module docs).
pub const STANDING_SHIFT_MIN: f32 = 0.25;

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
    /// The root scale override is not a finite number above 0.
    #[error("root scale {0} is not usable: it must be a finite number above 0")]
    BadRootScale(f32),
}

/// A retargeted clip and the figures behind it.
#[derive(Debug, Clone, PartialEq)]
pub struct Retargeted {
    /// The clip, with tracks named by rig joints: a rotation track for every bound rig joint and a
    /// translation track for each root joint. Not additive; name, duration, rate and looping kept.
    pub clip: SceneClip,
    /// Ratio of the leg chain lengths, target over source (1 when no leg was found); informational
    /// since the root scale (below) took its place.
    pub leg_scale: f32,
    /// Factor applied to the root translation's change: the override, or the ratio of hip heights.
    pub root_scale: f32,
    /// Where `root_scale` came from.
    pub root_scale_source: RootScaleSource,
    /// Hip heights `(motion, rig)` above the feet (or the lowest joint), model units.
    pub hip_heights: Option<(f32, f32)>,
    /// The motion's standing shift (see the module docs), motion units.
    pub standing_shift: f32,
    /// Height added to the root so that the rig's feet reach their bind height (see the module
    /// docs), rig units; 0 when the standing shift is 0.
    pub grounding: f32,
    /// Summed hip-to-foot chain lengths `(source, target)` over the legs found, if any.
    pub leg_lengths: Option<(f32, f32)>,
    /// Rig joints whose translation was transferred (normally the one bound to the hips).
    pub root_joints: Vec<String>,
    /// Notes: no legs found, and so on.
    pub diagnostics: Vec<Diagnostic>,
}

/// Where a root scale came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RootScaleSource {
    /// Ratio of the hip heights above the mapped feet.
    HipHeight,
    /// Ratio of the heights above the lowest joint (no bound pair of feet).
    LowestJoint,
    /// Given by the caller.
    Override,
    /// No usable height: 1.
    None,
}

impl RootScaleSource {
    /// Stable kebab-case name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::HipHeight => "hip-height",
            Self::LowestJoint => "lowest-joint",
            Self::Override => "override",
            Self::None => "none",
        }
    }
}

/// Options of [`retarget_with`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RetargetOptions {
    /// Root scale to use instead of the ratio of hip heights (finite and above 0).
    pub root_scale: Option<f32>,
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

/// Model-space positions of a pose given as locals in parent-before-child order (unit scale).
fn model_positions(parents: &[Option<u16>], locals: &[Transform]) -> Vec<Vec3> {
    let mut rot: Vec<Quat> = Vec::with_capacity(locals.len());
    let mut out: Vec<Vec3> = Vec::with_capacity(locals.len());
    for (i, l) in locals.iter().enumerate() {
        match parents
            .get(i)
            .copied()
            .flatten()
            .map(usize::from)
            .filter(|&p| p < out.len())
        {
            Some(p) => {
                out.push(out[p] + rot[p] * l.translation);
                rot.push((rot[p] * l.rotation).normalize());
            }
            None => {
                out.push(l.translation);
                rot.push(l.rotation.normalize());
            }
        }
    }
    out
}

/// The source's local pose at `t`: bind values replaced by whatever the tracks key.
fn sample_locals(
    bind: &[Transform],
    tracks: &[Option<&TrackCurves>],
    t: f32,
    out: &mut [Transform],
) {
    for (s, local) in out.iter_mut().enumerate() {
        *local = bind[s];
        if let Some(track) = tracks[s] {
            if let Some(v) = sample_vec3(&track.translation, t) {
                local.translation = v;
            }
            if let Some(q) = sample_quat(&track.rotation, t) {
                local.rotation = q;
            }
        }
    }
}

/// The mapped feet `(source joints, target joints)`, or `None` without a bound foot on both sides
/// of at least one pair.
fn mapped_feet(
    source: &Skeleton,
    target: &Skeleton,
    mapping: &Mapping,
) -> Option<(Vec<usize>, Vec<usize>)> {
    let (mut src, mut tgt) = (Vec::new(), Vec::new());
    for e in &mapping.entries {
        if e.slot != Some(Slot::Foot) {
            continue;
        }
        let (Some(t), Some(s)) = (
            target.find(&e.rig),
            e.motion.as_deref().and_then(|m| source.find(m)),
        ) else {
            continue;
        };
        tgt.push(usize::from(t));
        src.push(usize::from(s));
    }
    (!src.is_empty()).then_some((src, tgt))
}

/// Retargets `clip` (tracks named by `source` joints) onto `target` through `mapping` (rig = target,
/// motion = source), with default options. See the module docs for the formulas.
///
/// Keys: one key per distinct key time of the clip's tracks (all curves sampled there). Errors when the
/// mapping names joints the skeletons lack, or the clip is additive.
pub fn retarget(
    clip: &SceneClip,
    source: &Skeleton,
    target: &Skeleton,
    mapping: &Mapping,
) -> Result<Retargeted, RetargetError> {
    retarget_with(clip, source, target, mapping, &RetargetOptions::default())
}

/// [`retarget`] with options (a root scale override).
pub fn retarget_with(
    clip: &SceneClip,
    source: &Skeleton,
    target: &Skeleton,
    mapping: &Mapping,
    options: &RetargetOptions,
) -> Result<Retargeted, RetargetError> {
    if clip.additive {
        return Err(RetargetError::Additive(clip.name.clone()));
    }
    if let Some(k) = options.root_scale {
        if !k.is_finite() || k <= 0.0 {
            return Err(RetargetError::BadRootScale(k));
        }
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
        _ => 1.0,
    };

    // Root scale and standing shift (module docs).
    let src_rest_pos = bind_positions(source);
    let tgt_bind_pos = bind_positions(target);
    let (src_feet, tgt_feet, landmark) = match mapped_feet(source, target, mapping) {
        Some((s, t)) => (s, t, RootScaleSource::HipHeight),
        None => {
            diagnostics.push(Diagnostic::info(
                "retarget-no-feet",
                "no bound foot joints; hip heights are measured above each skeleton's lowest joint",
            ));
            (
                (0..source.len()).collect(),
                (0..target.len()).collect(),
                RootScaleSource::LowestJoint,
            )
        }
    };
    let lowest = |pos: &[Vec3], joints: &[usize]| {
        joints
            .iter()
            .filter_map(|&j| pos.get(j))
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min)
    };
    let src_foot_rest = lowest(&src_rest_pos, &src_feet);
    let tgt_foot_bind = lowest(&tgt_bind_pos, &tgt_feet);
    let mut src_local: Vec<Transform> = sb.to_vec();
    let mut foot_min = f32::INFINITY;
    for &t in &times {
        sample_locals(sb, &src_tracks, t, &mut src_local);
        foot_min = foot_min.min(lowest(
            &model_positions(source.parents(), &src_local),
            &src_feet,
        ));
    }
    let first_root = (0..target.len()).find(|&j| root_target[j]);
    let hip_heights = first_root.and_then(|j| {
        let s = src_of[j]?;
        let hm = src_rest_pos[s].y - src_foot_rest;
        let hr = tgt_bind_pos[j].y - tgt_foot_bind;
        (hm.is_finite() && hr.is_finite() && hm > 1e-6 && hr > 1e-6).then_some((hm, hr))
    });
    let (root_scale, root_scale_source) = match (options.root_scale, hip_heights) {
        (Some(k), _) => (k, RootScaleSource::Override),
        (None, Some((hm, hr))) => (hr / hm, landmark),
        (None, None) => {
            if first_root.is_some() {
                diagnostics.push(Diagnostic::warning(
                    "retarget-no-root-scale",
                    "the root's height above the feet is zero or unknown on one side; root \
                     translation is not scaled (give --root-scale)",
                ));
            }
            (1.0, RootScaleSource::None)
        }
    };
    // Per source root joint: how far its rest height is above its standing height on the clip's floor.
    let standing_shift_of = |s: usize| -> f32 {
        let rest_feet = src_foot_rest - foot_min;
        let h = src_rest_pos[s].y - src_foot_rest;
        if rest_feet.is_finite() && h.is_finite() && rest_feet.abs() > STANDING_SHIFT_MIN * h.abs()
        {
            rest_feet
        } else {
            0.0
        }
    };
    let standing_shift = first_root
        .and_then(|j| src_of[j])
        .map_or(0.0, standing_shift_of);

    let mut rot_values: Vec<Vec<Quat>> = vec![Vec::with_capacity(times.len()); target.len()];
    let mut trans_values: Vec<Vec<Vec3>> = vec![Vec::new(); target.len()];
    // Per root joint and key, its parent's animated model rotation (for grounding, below).
    let mut root_parent_rot: Vec<Vec<Quat>> = vec![Vec::new(); target.len()];
    for &t in &times {
        sample_locals(sb, &src_tracks, t, &mut src_local);
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
                        let change = src_parent * (src_local[s].translation - sb[s].translation)
                            + Vec3::Y * standing_shift_of(s);
                        let moved = parent.inverse() * (change * root_scale);
                        trans_values[j].push(tb[j].translation + moved);
                        root_parent_rot[j].push(parent);
                    }
                    model
                }
                None => (parent * tb[j].rotation).normalize(),
            };
            tgt_model.push(model);
        }
    }

    // Grounding: when the motion's rest pose does not stand on its floor, the rig's feet are put as
    // low over the clip as they are in its bind pose (module docs).
    let mut grounding = 0.0f32;
    if standing_shift != 0.0 {
        let mut rig_foot_min = f32::INFINITY;
        let mut locals: Vec<Transform> = tb.to_vec();
        for k in 0..times.len() {
            for (j, local) in locals.iter_mut().enumerate() {
                *local = tb[j];
                if let Some(&q) = rot_values[j].get(k) {
                    local.rotation = q;
                }
                if let Some(&v) = trans_values[j].get(k) {
                    local.translation = v;
                }
            }
            rig_foot_min = rig_foot_min.min(lowest(
                &model_positions(target.parents(), &locals),
                &tgt_feet,
            ));
        }
        let c = tgt_foot_bind - rig_foot_min;
        if c.is_finite() {
            grounding = c;
            for (values, rots) in trans_values.iter_mut().zip(&root_parent_rot) {
                for (v, r) in values.iter_mut().zip(rots) {
                    *v += r.inverse() * (Vec3::Y * c);
                }
            }
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
        root_scale,
        root_scale_source,
        hip_heights,
        standing_shift,
        grounding,
        leg_lengths: lengths,
        root_joints,
        diagnostics,
    })
}
