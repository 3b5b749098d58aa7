//! Clips for export: each driven joint's translation, rotation and scale as keyed channels that a
//! glTF viewer, interpolating linearly between keys, plays as the runtime plays the clip at any time.
//!
//! The runtime's values are taken from a [`sinew_core::Animator`] playing the clip alone (what `bake`
//! and a game compute, compressed clips decoded by the runtime itself) at the clip's knots: every key
//! time, time 0 and the duration, and for a looping clip the last f32 time before the duration (the
//! runtime wraps at the duration, so a clip whose last key is not its first pose jumps there). Between
//! knots the runtime interpolates linearly (nlerp for rotations), as glTF's `LINEAR` does (slerp);
//! [`super::keys::fit`] keeps the knots a channel needs and adds keys where slerp and nlerp part.

use super::keys::{
    at, fit, Keys, Rotation, Runtime, Scale, Tolerance, Translation, TEST_FRACTIONS,
};
use crate::bake::MAX_FRAMES;
use sinew_core::format::Asset;
use sinew_core::glam::{Mat4, Quat, Vec3};
use sinew_core::{
    local_to_model, Animator, Clip, ClipBinding, ClipId, JointIndex, Skeleton, Transform,
};
use std::sync::Arc;

/// How far each channel may move a point, relative to the model's size: a millionth of the bind-pose
/// diagonal.
pub const BUDGET: f64 = 1e-6;

/// Per joint, the tolerances of an export (see [`reach`]): a translation error moves everything under
/// the joint by itself, so translations are kept within `BUDGET * extent`; a rotation or scale error
/// `e` moves a point at distance `r` from the joint by about `e * r`, so they are kept within
/// `BUDGET * extent / reach` (at most 1e-3), where `reach` is the farthest the joint's vertices
/// and descendants are from it. Each channel then moves no point by more than a millionth of the
/// diagonal.
pub fn tolerances(asset: &Asset) -> Vec<Tolerance> {
    let extent = f64::from(extent(asset));
    let extent = if extent.is_finite() && extent > 0.0 {
        extent
    } else {
        1.0
    };
    reach(asset)
        .into_iter()
        .map(|r| {
            let r = f64::from(r).max(1e-3 * extent);
            Tolerance {
                translation: BUDGET * extent,
                rotation: BUDGET * extent / r,
                scale: BUDGET * extent / r,
            }
        })
        .collect()
}

/// The model's size: the diagonal of the bounding box of every LOD-0 vertex and every joint in the
/// bind pose (0 when there is nothing).
pub fn extent(asset: &Asset) -> f32 {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    let mut add = |p: Vec3| {
        if p.is_finite() {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    };
    for m in &asset.meshes {
        if let Some(l) = m.lods.first() {
            l.positions.iter().for_each(|&p| add(p));
        }
    }
    bind_positions(asset).into_iter().for_each(add);
    if lo.x <= hi.x {
        (hi - lo).length()
    } else {
        0.0
    }
}

/// Model-space bind positions of the joints (empty without a skeleton).
fn bind_positions(asset: &Asset) -> Vec<Vec3> {
    let Some(s) = &asset.skeleton else {
        return Vec::new();
    };
    let mut models = vec![Mat4::IDENTITY; s.len()];
    if local_to_model(s.parents(), s.bind_local(), &mut models).is_err() {
        return Vec::new();
    }
    models.iter().map(|m| m.w_axis.truncate()).collect()
}

/// Per joint, in the bind pose: the largest distance from the joint to a descendant joint or to a
/// LOD-0 vertex weighted to it or to a descendant (a rigid pose keeps these distances).
pub fn reach(asset: &Asset) -> Vec<f32> {
    let Some(s) = &asset.skeleton else {
        return Vec::new();
    };
    let p = bind_positions(asset);
    let mut reach = vec![0.0f32; s.len()];
    if p.len() != s.len() {
        return reach;
    }
    let parents = s.parents();
    let mut widen = |from: usize, q: Vec3| {
        let mut j = Some(from);
        let mut steps = 0;
        while let Some(k) = j {
            if k >= reach.len() || steps > reach.len() {
                break;
            }
            reach[k] = reach[k].max(p[k].distance(q));
            j = parents[k].map(usize::from);
            steps += 1;
        }
    };
    for (k, &q) in p.iter().enumerate() {
        widen(k, q);
    }
    for m in &asset.meshes {
        let Some(l) = m.lods.first() else { continue };
        if !l.is_skinned() {
            continue;
        }
        for ((&q, js), ws) in l.positions.iter().zip(&l.joints).zip(&l.weights) {
            for (&j, &w) in js.iter().zip(ws) {
                if w > 0.0 {
                    widen(usize::from(j), q);
                }
            }
        }
    }
    reach
}

/// Memory the runtime values of one pass may take; more driven joints are done in several passes.
const PASS_BYTES: usize = 128 << 20;

/// One joint's exported channels.
#[derive(Debug, Clone, PartialEq)]
pub struct JointKeys {
    /// Translation keys.
    pub translation: Keys<Vec3>,
    /// Rotation keys, unit, consecutive keys in one hemisphere (an interpolating viewer takes the
    /// short way, as the runtime does).
    pub rotation: Keys<Quat>,
    /// Scale keys.
    pub scale: Keys<Vec3>,
}

/// One clip, keyed for export.
#[derive(Debug, Clone, PartialEq)]
pub struct KeyedClip {
    /// Joints the clip drives, in skeleton order.
    pub joints: Vec<JointIndex>,
    /// Per driven joint (same order as `joints`), its channels.
    pub channels: Vec<JointKeys>,
    /// The runtime's knots (key times, 0, the duration) the channels were fitted to.
    pub knots: usize,
    /// Track names of the clip that are not joints of the skeleton (not exported).
    pub unbound: Vec<String>,
}

impl KeyedClip {
    /// Keys over every channel.
    pub fn key_count(&self) -> usize {
        self.channels
            .iter()
            .map(|c| c.translation.times.len() + c.rotation.times.len() + c.scale.times.len())
            .sum()
    }
}

/// Why a clip could not be keyed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// No track of the clip names a joint of the skeleton.
    #[error("clip {0:?} drives no joint of the skeleton")]
    NothingDriven(String),
    /// Too many key times.
    #[error("clip {0:?} has more than {MAX_FRAMES} key times")]
    TooManyFrames(String),
    /// The runtime refused the clip.
    #[error("clip {0:?}: {1}")]
    Runtime(String, String),
}

/// The knots of `clip`: its key times inside `[0, duration]`, 0 and the duration, and for a looping
/// clip the f32 time just before the duration.
pub fn knots(clip: &Clip) -> Vec<f32> {
    let d = clip.duration();
    let mut k: Vec<f32> = std::iter::once(0.0)
        .chain(clip.times().iter().copied().filter(|&t| t > 0.0 && t < d))
        .collect();
    if clip.looping() && d > 0.0 {
        let before = f32::from_bits(d.to_bits() - 1);
        if before > k[k.len() - 1] {
            k.push(before);
        }
    }
    if d > 0.0 {
        k.push(d);
    }
    k
}

/// The clip playing alone, posed at any time.
struct Player {
    animator: Animator,
    id: ClipId,
    pose: Vec<Transform>,
    name: String,
}

impl Player {
    fn at(&mut self, t: f32) -> Result<&[Transform], SampleError> {
        let runtime =
            |e: sinew_core::AnimatorError| SampleError::Runtime(self.name.clone(), e.to_string());
        self.animator.set_time(self.id, t).map_err(runtime)?;
        self.animator.evaluate(&mut self.pose).map_err(runtime)?;
        Ok(&self.pose)
    }
}

/// Keys `clip` on `skeleton`: every driven joint's channels fitted within its tolerance (`tol[joint]`,
/// see [`tolerances`]; a joint past the end uses the last, or a millionth where there is none).
pub fn key_clip(
    skeleton: &Arc<Skeleton>,
    clip: &Clip,
    tol: &[Tolerance],
) -> Result<KeyedClip, SampleError> {
    let fallback = Tolerance {
        translation: BUDGET,
        rotation: BUDGET,
        scale: BUDGET,
    };
    let name = clip.name().to_string();
    let binding = ClipBinding::new(clip, skeleton);
    let mut joints: Vec<JointIndex> = binding.driven().to_vec();
    joints.sort_unstable();
    joints.dedup();
    if joints.is_empty() {
        return Err(SampleError::NothingDriven(name));
    }
    let unbound = binding.unmatched().to_vec();
    let knots = knots(clip);
    if knots.len() > MAX_FRAMES {
        return Err(SampleError::TooManyFrames(name));
    }
    let mut animator = Animator::new(Arc::clone(skeleton));
    let id = animator.add_clip(Arc::new(clip.clone()));
    animator
        .activate(id)
        .map_err(|e| SampleError::Runtime(name.clone(), e.to_string()))?;
    let mut player = Player {
        animator,
        id,
        pose: skeleton.bind_local().to_vec(),
        name,
    };
    // Every time the runtime is asked for: the knots, then each interval's test points.
    let mut times = knots.clone();
    for w in knots.windows(2) {
        times.extend(TEST_FRACTIONS.iter().map(|&f| at(w[0], w[1], f)));
    }
    let per_joint = times.len() * std::mem::size_of::<Transform>();
    let batch = (PASS_BYTES / per_joint.max(1)).max(1);
    let nk = knots.len();
    let mut channels = Vec::with_capacity(joints.len());
    for group in joints.chunks(batch) {
        // values[t * group.len() + g]
        let mut values = Vec::with_capacity(times.len() * group.len());
        for &t in &times {
            let pose = player.at(t)?;
            values.extend(group.iter().map(|&j| pose[j as usize]));
        }
        for (g, &j) in group.iter().enumerate() {
            let track: Vec<Transform> = values
                .iter()
                .skip(g)
                .step_by(group.len())
                .copied()
                .collect();
            let (at_knots, tests) = track.split_at(nk);
            let mut failed = None;
            let mut eval = |t: f32| match player.at(t) {
                Ok(p) => p[j as usize],
                Err(e) => {
                    failed = Some(e);
                    Transform::IDENTITY
                }
            };
            let tol = tol
                .get(usize::from(j))
                .or(tol.last())
                .copied()
                .unwrap_or(fallback);
            let translation = fit_channel(
                &knots,
                at_knots,
                tests,
                &tol,
                Translation,
                |x| x.translation,
                &mut eval,
            );
            let rotation = fit_channel(
                &knots,
                at_knots,
                tests,
                &tol,
                Rotation,
                |x| x.rotation,
                &mut eval,
            );
            let scale = fit_channel(&knots, at_knots, tests, &tol, Scale, |x| x.scale, &mut eval);
            if let Some(e) = failed {
                return Err(e);
            }
            channels.push(JointKeys {
                translation: Keys {
                    times: translation.times,
                    values: translation.values.into_iter().map(|v| v.0).collect(),
                },
                rotation: one_hemisphere(Keys {
                    times: rotation.times,
                    values: rotation.values.into_iter().map(|v| unit(v.0)).collect(),
                }),
                scale: Keys {
                    times: scale.times,
                    values: scale.values.into_iter().map(|v| v.0).collect(),
                },
            });
        }
    }
    Ok(KeyedClip {
        joints,
        channels,
        knots: nk,
        unbound,
    })
}

/// Fits one channel (`part` picks it out of a transform, `wrap` makes it a fitted value).
fn fit_channel<P, V: super::keys::Value>(
    knots: &[f32],
    at_knots: &[Transform],
    tests: &[Transform],
    tol: &Tolerance,
    wrap: impl Fn(P) -> V,
    part: impl Fn(&Transform) -> P,
    eval: &mut impl FnMut(f32) -> Transform,
) -> Keys<V> {
    let values: Vec<V> = at_knots.iter().map(|x| wrap(part(x))).collect();
    let tests: Vec<V> = tests.iter().map(|x| wrap(part(x))).collect();
    let rt = Runtime {
        knots,
        values: &values,
        tests: &tests,
    };
    fit(&rt, tol, |t| wrap(part(&eval(t))))
}

/// Flips rotations so that consecutive keys have a non-negative dot product (q and -q are the same
/// rotation; a viewer that does not pick the short way itself then still does).
fn one_hemisphere(mut k: Keys<Quat>) -> Keys<Quat> {
    for i in 1..k.values.len() {
        if k.values[i - 1].dot(k.values[i]) < 0.0 {
            k.values[i] = -k.values[i];
        }
    }
    k
}

/// `q` normalised, or the identity when it has no direction.
pub fn unit(q: Quat) -> Quat {
    let n = q.normalize();
    if n.is_finite() {
        n
    } else {
        Quat::IDENTITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sinew_core::skeleton::inverse_bind_from_locals;
    use sinew_core::{Curve, TrackCurves};

    fn skeleton() -> Arc<Skeleton> {
        let parents = vec![None, Some(0)];
        let locals = vec![Transform::IDENTITY, Transform::from_translation(Vec3::X)];
        let ib = inverse_bind_from_locals(&parents, &locals);
        Arc::new(
            Skeleton::new(vec!["root".into(), "arm".into()], parents, locals, ib)
                .expect("skeleton"),
        )
    }

    /// The arm turning about z through `angles` at `times`, and a track for a joint the skeleton
    /// does not have (its one key at `ghost_time`, which the clip's key times then include).
    fn clip(
        times: Vec<f32>,
        angles: &[f32],
        looping: bool,
        duration: f32,
        ghost_time: f32,
    ) -> Clip {
        let mut tc = TrackCurves {
            joint: "arm".into(),
            ..Default::default()
        };
        tc.rotation = Curve::new(
            times,
            angles.iter().map(|&a| Quat::from_rotation_z(a)).collect(),
        );
        let mut ghost = TrackCurves {
            joint: "ghost".into(),
            ..Default::default()
        };
        ghost.translation = Curve::new(vec![ghost_time], vec![Vec3::ONE]);
        Clip::from_curves("wave", duration, 4.0, looping, false, vec![tc, ghost]).expect("clip")
    }

    fn tol() -> Vec<Tolerance> {
        vec![
            Tolerance {
                translation: 1e-6,
                rotation: 1e-6,
                scale: 1e-6,
            };
            2
        ]
    }

    #[test]
    fn keys_are_the_runtime_keys_and_still_channels_take_two() {
        // Uneven key times (not on any frame grid), a corner at 0.3; small turns that need no cuts.
        let c = clip(vec![0.0, 0.3, 1.0], &[0.0, 0.02, 0.025], false, 1.0, 0.0);
        let k = key_clip(&skeleton(), &c, &tol()).expect("keyed");
        assert_eq!(k.joints, vec![1]);
        assert_eq!(k.unbound, vec!["ghost".to_string()]);
        assert_eq!(k.knots, 3);
        let r = &k.channels[0].rotation;
        assert_eq!(r.times, vec![0.0, 0.3, 1.0]);
        assert!(r.values[1].abs_diff_eq(Quat::from_rotation_z(0.02), 1e-7));
        // Translation is the bind value throughout: two keys, at 0 and at the duration.
        let t = &k.channels[0].translation;
        assert_eq!(t.times, vec![0.0, 1.0]);
        assert_eq!(t.values, vec![Vec3::X, Vec3::X]);
        assert_eq!(k.key_count(), 3 + 2 + 2);
    }

    #[test]
    fn a_looping_clip_that_does_not_close_jumps_at_its_end() {
        // Keys 0 .. 1 with duration 1: the runtime plays the last key's value up to just before 1,
        // and the first pose at 1 (it wraps). The export keeps both.
        let c = clip(vec![0.0, 0.5, 1.0], &[0.0, 0.02, 0.04], true, 1.0, 0.0);
        let k = key_clip(&skeleton(), &c, &tol()).expect("keyed");
        let r = &k.channels[0].rotation;
        let n = r.times.len();
        assert_eq!(r.times[n - 1], 1.0);
        assert_eq!(r.times[n - 2], f32::from_bits(1.0f32.to_bits() - 1));
        assert!(r.values[n - 1].abs_diff_eq(Quat::IDENTITY, 1e-7));
        assert!(r.values[n - 2].abs_diff_eq(Quat::from_rotation_z(0.04), 1e-6));
    }

    #[test]
    fn a_looping_clip_starting_late_gets_its_wrap_value_at_zero() {
        // First key at 0.25 of a 1 s loop: at 0 the runtime is a quarter of the way... from the last
        // key (0.75) to the first (at 1.25): 0.25 / 0.5 of the way.
        let c = clip(vec![0.25, 0.75], &[0.0, 0.04], true, 1.0, 0.25);
        let k = key_clip(&skeleton(), &c, &tol()).expect("keyed");
        let r = &k.channels[0].rotation;
        assert_eq!(r.times[0], 0.0);
        let want = sinew_core::clip::nlerp(Quat::from_rotation_z(0.04), Quat::IDENTITY, 0.5);
        assert!(r.values[0].abs_diff_eq(want, 1e-7), "{:?}", r.values[0]);
        assert!(want.abs_diff_eq(Quat::from_rotation_z(0.02), 1e-6));
    }

    #[test]
    fn nothing_driven_is_an_error() {
        let mut ghost = TrackCurves {
            joint: "ghost".into(),
            ..Default::default()
        };
        ghost.translation = Curve::new(vec![0.0, 1.0], vec![Vec3::ONE, Vec3::ZERO]);
        let c = Clip::from_curves("g", 1.0, 30.0, false, false, vec![ghost]).expect("clip");
        assert_eq!(
            key_clip(&skeleton(), &c, &tol()),
            Err(SampleError::NothingDriven("g".into()))
        );
    }

    #[test]
    fn rotations_stay_in_one_hemisphere() {
        // More than a half turn over the clip: the exported quaternions must not change sign between
        // keys.
        let c = clip(vec![0.0, 1.0, 2.0], &[0.0, 3.0, 6.0], false, 2.0, 0.0);
        let k = key_clip(&skeleton(), &c, &tol()).expect("keyed");
        let r = &k.channels[0].rotation;
        assert!(r.times.len() > 3, "3-radian steps need cuts");
        for w in r.values.windows(2) {
            assert!(w[0].dot(w[1]) >= 0.0);
        }
    }
}
