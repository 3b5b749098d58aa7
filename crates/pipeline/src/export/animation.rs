//! Clips sampled through the runtime for export: every frame of a clip at its own rate, posed by a
//! [`sinew_core::Animator`] playing that clip alone (what `bake` and a game compute), and kept per
//! driven joint as translation, rotation and scale tracks.

use crate::bake::{frame_count, frame_time, MAX_FPS, MAX_FRAMES};
use sinew_core::glam::Quat;
use sinew_core::{Animator, Clip, ClipBinding, JointIndex, Skeleton, Transform};
use std::sync::Arc;

/// Frame rate used for a clip whose own rate is not usable (not finite, not above 0, above
/// [`MAX_FPS`]).
pub const FALLBACK_FPS: f32 = 30.0;

/// One clip sampled at every frame.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledClip {
    /// Frame times in seconds, increasing; the last is the clip's duration.
    pub times: Vec<f32>,
    /// The frame rate used.
    pub fps: f32,
    /// Joints the clip drives, in skeleton order.
    pub joints: Vec<JointIndex>,
    /// Per driven joint (same order as `joints`), per frame: the local transform. Rotations of
    /// consecutive frames are kept in one hemisphere (q and -q are the same rotation; an interpolating
    /// viewer takes the short way).
    pub poses: Vec<Vec<Transform>>,
    /// Track names of the clip that are not joints of the skeleton (not exported).
    pub unbound: Vec<String>,
}

/// Why a clip could not be sampled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// No track of the clip names a joint of the skeleton.
    #[error("clip {0:?} drives no joint of the skeleton")]
    NothingDriven(String),
    /// Too many frames.
    #[error("clip {0:?} would have more than {MAX_FRAMES} frames")]
    TooManyFrames(String),
    /// The runtime refused the clip.
    #[error("clip {0:?}: {1}")]
    Runtime(String, String),
}

/// Samples `clip` on `skeleton` at the clip's rate (or [`FALLBACK_FPS`]).
pub fn sample_clip(skeleton: &Arc<Skeleton>, clip: &Clip) -> Result<SampledClip, SampleError> {
    let name = clip.name().to_string();
    let binding = ClipBinding::new(clip, skeleton);
    let mut joints: Vec<JointIndex> = binding.driven().to_vec();
    joints.sort_unstable();
    joints.dedup();
    if joints.is_empty() {
        return Err(SampleError::NothingDriven(name));
    }
    let unbound = binding.unmatched().to_vec();
    let rate = clip.sample_rate();
    let fps = if rate.is_finite() && rate > 0.0 && rate <= MAX_FPS {
        rate
    } else {
        FALLBACK_FPS
    };
    let n = frame_count(clip.duration(), fps);
    if n > MAX_FRAMES {
        return Err(SampleError::TooManyFrames(name));
    }
    let runtime = |e: sinew_core::AnimatorError| SampleError::Runtime(name.clone(), e.to_string());
    let mut animator = Animator::new(Arc::clone(skeleton));
    let id = animator.add_clip(Arc::new(clip.clone()));
    animator.activate(id).map_err(runtime)?;
    let mut pose = skeleton.bind_local().to_vec();
    let mut times = Vec::with_capacity(n);
    let mut poses: Vec<Vec<Transform>> = vec![Vec::with_capacity(n); joints.len()];
    for i in 0..n {
        let t = frame_time(i, n, clip.duration(), fps);
        animator.set_time(id, t).map_err(runtime)?;
        animator.evaluate(&mut pose).map_err(runtime)?;
        times.push(t);
        for (track, &j) in poses.iter_mut().zip(&joints) {
            let mut x = pose[j as usize];
            if let Some(prev) = track.last() {
                if prev.rotation.dot(x.rotation) < 0.0 {
                    x.rotation = -x.rotation;
                }
            }
            track.push(x);
        }
    }
    Ok(SampledClip {
        times,
        fps,
        joints,
        poses,
        unbound,
    })
}

/// The translations of one joint's track as flat `[x, y, z, ...]`.
pub fn translations(track: &[Transform]) -> Vec<f32> {
    track
        .iter()
        .flat_map(|t| t.translation.to_array())
        .collect()
}

/// The rotations of one joint's track as flat `[x, y, z, w, ...]`, each normalised.
pub fn rotations(track: &[Transform]) -> Vec<f32> {
    track
        .iter()
        .flat_map(|t| unit(t.rotation).to_array())
        .collect()
}

/// The scales of one joint's track as flat `[x, y, z, ...]`.
pub fn scales(track: &[Transform]) -> Vec<f32> {
    track.iter().flat_map(|t| t.scale.to_array()).collect()
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
    use sinew_core::glam::Vec3;
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

    fn clip(rate: f32) -> Clip {
        let mut tc = TrackCurves {
            joint: "arm".into(),
            ..Default::default()
        };
        tc.rotation = Curve::new(
            vec![0.0, 1.0],
            vec![
                Quat::IDENTITY,
                Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
            ],
        );
        let mut ghost = TrackCurves {
            joint: "ghost".into(),
            ..Default::default()
        };
        ghost.translation = Curve::new(vec![0.0], vec![Vec3::ONE]);
        Clip::from_curves("wave", 1.0, rate, false, false, vec![tc, ghost]).expect("clip")
    }

    #[test]
    fn samples_every_frame_at_the_clip_rate() {
        let s = sample_clip(&skeleton(), &clip(4.0)).expect("sampled");
        assert_eq!(s.times, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        assert_eq!(s.joints, vec![1]);
        assert_eq!(s.unbound, vec!["ghost".to_string()]);
        let mid = s.poses[0][2];
        let angle = mid.rotation.angle_between(Quat::IDENTITY);
        assert!(
            (angle - std::f32::consts::FRAC_PI_4).abs() < 1e-5,
            "{angle}"
        );
        assert_eq!(mid.translation, Vec3::X);
    }

    #[test]
    fn unusable_rate_falls_back() {
        let s = sample_clip(&skeleton(), &clip(0.0)).expect("sampled");
        assert_eq!(s.fps, FALLBACK_FPS);
        assert_eq!(s.times.len(), 31);
    }

    #[test]
    fn rotations_stay_in_one_hemisphere() {
        // A half turn and a bit more: the runtime's nlerp goes the short way, and the exported
        // quaternions must not jump to the other sign between frames.
        let mut tc = TrackCurves {
            joint: "arm".into(),
            ..Default::default()
        };
        tc.rotation = Curve::new(
            vec![0.0, 1.0, 2.0],
            vec![
                Quat::IDENTITY,
                Quat::from_rotation_z(3.0),
                Quat::from_rotation_z(6.0),
            ],
        );
        let c = Clip::from_curves("spin", 2.0, 10.0, false, false, vec![tc]).expect("clip");
        let s = sample_clip(&skeleton(), &c).expect("sampled");
        for w in s.poses[0].windows(2) {
            assert!(w[0].rotation.dot(w[1].rotation) >= 0.0);
        }
    }
}
