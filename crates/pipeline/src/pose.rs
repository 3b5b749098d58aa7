//! Model-space joint poses of a clip at chosen times, computed by the runtime itself: a one-layer
//! [`sinew_core::Animator`] on the decoded [`Asset`], [`Animator::evaluate_palette`] (the call a game
//! and the baker make), then each model matrix split into translation, rotation and scale.
//!
//! # Times
//!
//! A single time is used as given (the runtime wraps a looping clip's time into `[0, duration)` and
//! clamps a non-looping clip's to `[0, duration]`). A range `start..end` at `fps` has
//! `n = ceil((end - start) * fps - 1e-3) + 1` frames: frame `i < n - 1` at `start + i / fps`
//! (f64, rounded to f32), the last exactly at `end`, as [`crate::bake`] counts frames.
//!
//! # Decomposition
//!
//! `translation` is the model matrix's fourth column, bit for bit. `rotation` and `scale` come from
//! glam's `Mat4::to_scale_rotation_translation` (column lengths for scale, the sign of the determinant
//! on x, the normalised columns' quaternion), so they are exact only up to rounding; `matrix` keeps the
//! runtime's matrix itself.

use crate::bake::{check_fps, frame_count, BakeError, MAX_FRAMES};
use sinew_core::format::Asset;
use sinew_core::glam::{Mat4, Quat, Vec3};
use sinew_core::{Animator, AnimatorError, Clip};
use std::sync::Arc;

/// Which times to sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PoseTimes {
    /// One time, seconds.
    At(f32),
    /// `start..=end` seconds at a frame rate (default: the clip's sample rate).
    Range {
        /// First time.
        start: f32,
        /// Last time (included).
        end: f32,
        /// Frames per second, or `None` for the clip's sample rate.
        fps: Option<f32>,
    },
}

/// A request: `CLIP@TIME` or `CLIP@START..END`.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseRequest {
    /// Clip name.
    pub clip: String,
    /// Times.
    pub times: PoseTimes,
}

impl PoseRequest {
    /// Parses `CLIP@TIME` or `CLIP@START..END` (seconds; the clip name is everything before the last
    /// `@`, so names may contain `@`). Times must be finite, and a range's end not before its start.
    pub fn parse(spec: &str, fps: Option<f32>) -> Result<Self, String> {
        let usage = || format!("pose {spec:?}: expected CLIP@TIME or CLIP@START..END (seconds)");
        let (clip, when) = spec.rsplit_once('@').ok_or_else(usage)?;
        if clip.is_empty() || when.is_empty() {
            return Err(usage());
        }
        let num = |s: &str| -> Result<f32, String> {
            let v: f32 = s
                .trim()
                .parse()
                .map_err(|_| format!("pose {spec:?}: time {s:?} is not a number"))?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(format!("pose {spec:?}: time {s:?} is not finite"))
            }
        };
        let times = match when.split_once("..") {
            Some((a, b)) => {
                let (start, end) = (num(a)?, num(b)?);
                if end < start {
                    return Err(format!("pose {spec:?}: the range ends before it starts"));
                }
                PoseTimes::Range { start, end, fps }
            }
            None if fps.is_some() => {
                return Err(format!(
                    "pose {spec:?}: a frame rate applies to a range (CLIP@START..END)"
                ))
            }
            None => PoseTimes::At(num(when)?),
        };
        Ok(Self {
            clip: clip.to_string(),
            times,
        })
    }
}

/// One joint of a posed frame, in model space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointPose {
    /// Translation (the model matrix's fourth column).
    pub translation: Vec3,
    /// Rotation.
    pub rotation: Quat,
    /// Scale.
    pub scale: Vec3,
    /// The runtime's model matrix.
    pub matrix: Mat4,
}

/// One sampled frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseFrame {
    /// Clip time asked for, seconds.
    pub time: f32,
    /// One entry per skeleton joint, in skeleton order.
    pub joints: Vec<JointPose>,
}

/// The poses of a request.
#[derive(Debug, Clone, PartialEq)]
pub struct Poses {
    /// Clip name.
    pub clip: String,
    /// Clip duration, seconds.
    pub duration: f32,
    /// Whether the clip loops.
    pub looping: bool,
    /// Frame rate of a range (`None` for a single time).
    pub fps: Option<f32>,
    /// Frames in time order.
    pub frames: Vec<PoseFrame>,
}

/// The times of a request on a clip (see the module docs).
pub fn times(clip: &Clip, times: PoseTimes) -> Result<(Vec<f32>, Option<f32>), BakeError> {
    match times {
        PoseTimes::At(t) => Ok((vec![t], None)),
        PoseTimes::Range { start, end, fps } => {
            let fps = match fps {
                Some(f) => check_fps(f, "")?,
                None => check_fps(
                    clip.sample_rate(),
                    " (the clip's own sample rate; give --fps)",
                )?,
            };
            let n = frame_count(end - start, fps);
            if n > MAX_FRAMES {
                return Err(BakeError::TooManyFrames(n));
            }
            let ts = (0..n)
                .map(|i| {
                    if i + 1 == n && i > 0 {
                        end
                    } else {
                        (f64::from(start) + i as f64 / f64::from(fps)) as f32
                    }
                })
                .collect();
            Ok((ts, Some(fps)))
        }
    }
}

/// Samples the request on a decoded asset (see the module docs).
pub fn sample(asset: &Asset, req: &PoseRequest) -> Result<Poses, BakeError> {
    let skeleton = asset.skeleton.as_ref().ok_or(BakeError::NoSkeleton)?;
    let clip = asset
        .clips
        .iter()
        .find(|c| c.name() == req.clip)
        .ok_or_else(|| BakeError::UnknownClip {
            name: req.clip.clone(),
            available: asset.clips.iter().map(|c| c.name().to_string()).collect(),
        })?;
    let (ts, fps) = times(clip, req.times)?;
    let mut animator = Animator::new(Arc::new(skeleton.clone()));
    let layer = animator.add_clip(Arc::new(clip.clone()));
    animator.activate(layer)?;
    let n = skeleton.len();
    let mut models = vec![Mat4::IDENTITY; n];
    let mut palette = vec![Mat4::IDENTITY; n];
    let mut frames = Vec::with_capacity(ts.len());
    for t in ts {
        animator.set_time(layer, t)?;
        animator
            .evaluate_palette(&mut models, &mut palette)
            .map_err(|e| match e {
                AnimatorError::Clip(source) => BakeError::Clip {
                    clip: req.clip.clone(),
                    source,
                },
                other => BakeError::Animator(other),
            })?;
        frames.push(PoseFrame {
            time: t,
            joints: models.iter().map(|&m| decompose(m)).collect(),
        });
    }
    Ok(Poses {
        clip: req.clip.clone(),
        duration: clip.duration(),
        looping: clip.looping(),
        fps,
        frames,
    })
}

/// Splits a model matrix (see the module docs).
pub fn decompose(matrix: Mat4) -> JointPose {
    let (scale, rotation, _) = matrix.to_scale_rotation_translation();
    JointPose {
        translation: matrix.w_axis.truncate(),
        rotation,
        scale,
        matrix,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_times_and_ranges() {
        let r = PoseRequest::parse("walk@0.5", None).unwrap();
        assert_eq!(r.clip, "walk");
        assert_eq!(r.times, PoseTimes::At(0.5));
        let r = PoseRequest::parse("a@b@1..2", Some(10.0)).unwrap();
        assert_eq!(r.clip, "a@b");
        assert_eq!(
            r.times,
            PoseTimes::Range {
                start: 1.0,
                end: 2.0,
                fps: Some(10.0)
            }
        );
        assert!(PoseRequest::parse("walk@1", Some(30.0)).is_err());
        for bad in [
            "walk",
            "@1",
            "walk@",
            "walk@x",
            "walk@2..1",
            "walk@inf",
            "walk@1..nan",
        ] {
            assert!(PoseRequest::parse(bad, None).is_err(), "{bad}");
        }
    }

    #[test]
    fn decompose_keeps_the_translation_bits() {
        let m = Mat4::from_scale_rotation_translation(
            Vec3::new(1.0, 2.0, 0.5),
            Quat::from_rotation_y(0.7),
            Vec3::new(0.1, -3.3, 7.0),
        );
        let p = decompose(m);
        assert_eq!(p.translation, Vec3::new(0.1, -3.3, 7.0));
        assert!((p.scale - Vec3::new(1.0, 2.0, 0.5)).abs().max_element() < 1e-6);
        assert!(p.rotation.angle_between(Quat::from_rotation_y(0.7)) < 1e-5);
        assert_eq!(p.matrix, m);
    }
}
