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
//!
//! # Into a caller's buffers
//!
//! [`matrices_into`] and [`trs_into`] pose a clip at any list of times into flat `f32` buffers (the
//! Python package's `Asset.sample`): the same animator calls as [`sample`], so model-space matrices
//! are the bits `inspect --pose` prints. [`Space::Local`] gives the local transforms the runtime's
//! sampler and blend produce ([`Animator::evaluate`]), as [`Transform::to_mat4`] matrices: the
//! formulas of the runtime's own local matrices (for a root joint, local and model matrices are the
//! same numbers, tested). Matrices are written row by row (`out[r * 4 + c]` is row `r`, column `c`;
//! the translation is column 3), which is numpy's `m[row, col]`; the numbers are the runtime's bits,
//! only arranged. [`check_times`] refuses times outside a clip's `[0, duration]` for callers that
//! want that; the functions themselves accept any finite time and apply the runtime's rule.

use crate::bake::{check_fps, frame_count, BakeError, MAX_FRAMES};
use sinew_core::format::Asset;
use sinew_core::glam::{Mat4, Quat, Vec3};
use sinew_core::{Animator, AnimatorError, Clip, ClipId, Skeleton, Transform};
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
    let clip = &asset.clips[find_clip(asset, &req.clip)?];
    let (ts, fps) = times(clip, req.times)?;
    let mut poser = Poser::new(&Arc::new(skeleton.clone()), &Arc::new(clip.clone()))?;
    let mut frames = Vec::with_capacity(ts.len());
    for t in ts {
        poser.pose(t, Space::Model)?;
        frames.push(PoseFrame {
            time: t,
            joints: poser.models.iter().map(|&m| decompose(m)).collect(),
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

/// The index of the clip named `name` (the error lists the clips the file has).
pub fn find_clip(asset: &Asset, name: &str) -> Result<usize, BakeError> {
    asset
        .clips
        .iter()
        .position(|c| c.name() == name)
        .ok_or_else(|| BakeError::UnknownClip {
            name: name.to_string(),
            available: asset.clips.iter().map(|c| c.name().to_string()).collect(),
        })
}

/// Which transforms [`matrices_into`] and [`trs_into`] write.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Space {
    /// Model space: each joint composed with its parents, the matrices a game skins with.
    Model,
    /// Local space: each joint relative to its parent, as the runtime's sampler and blend give it.
    Local,
}

/// Checks times a caller gives for `clip`: every one finite and inside `[0, duration]`. The first
/// that is not is the error (its index, its value and the clip's duration).
pub fn check_times(clip: &Clip, times: &[f32]) -> Result<(), BakeError> {
    check_finite(times)?;
    let d = clip.duration();
    match times.iter().position(|&t| !(0.0..=d).contains(&t)) {
        Some(index) => Err(BakeError::TimeOutOfRange {
            clip: clip.name().to_string(),
            index,
            time: times[index],
            duration: d,
        }),
        None => Ok(()),
    }
}

fn check_finite(times: &[f32]) -> Result<(), BakeError> {
    match times.iter().position(|t| !t.is_finite()) {
        Some(index) => Err(BakeError::NonFiniteTime {
            index,
            time: times[index],
        }),
        None => Ok(()),
    }
}

/// Checks that a caller's buffer holds exactly `expected` floats.
pub(crate) fn check_len(what: &'static str, expected: usize, got: usize) -> Result<(), BakeError> {
    if expected == got {
        Ok(())
    } else {
        Err(BakeError::BufferLength {
            what,
            expected,
            got,
        })
    }
}

/// Poses `clip` on `skeleton` at each of `times` (seconds, finite; the runtime wraps a looping clip's
/// time and clamps another's) and writes one 4x4 matrix per time and joint into `out`, time-major,
/// row by row (see the module docs): `out` holds `times.len() * joints * 16` floats.
pub fn matrices_into(
    skeleton: &Arc<Skeleton>,
    clip: &Arc<Clip>,
    times: &[f32],
    space: Space,
    out: &mut [f32],
) -> Result<(), BakeError> {
    check_finite(times)?;
    let n = skeleton.len();
    check_len("matrices", times.len() * n * 16, out.len())?;
    if n == 0 {
        return Ok(());
    }
    let mut poser = Poser::new(skeleton, clip)?;
    for (&t, frame) in times.iter().zip(out.chunks_exact_mut(n * 16)) {
        poser.pose(t, space)?;
        for (j, m) in frame.chunks_exact_mut(16).enumerate() {
            let matrix = match space {
                Space::Model => poser.models[j],
                Space::Local => poser.locals[j].to_mat4(),
            };
            m.copy_from_slice(&matrix.transpose().to_cols_array());
        }
    }
    Ok(())
}

/// [`matrices_into`] as translations (`x y z`), rotation quaternions (`x y z w`) and scales (`x y
/// z`), one per time and joint, time-major: `times.len() * joints` times 3, 4 and 3 floats. Local
/// transforms are the runtime's own; model-space ones are its matrices split by [`decompose`], the
/// numbers `inspect --pose` prints.
pub fn trs_into(
    skeleton: &Arc<Skeleton>,
    clip: &Arc<Clip>,
    times: &[f32],
    space: Space,
    translations: &mut [f32],
    rotations: &mut [f32],
    scales: &mut [f32],
) -> Result<(), BakeError> {
    check_finite(times)?;
    let n = skeleton.len();
    let count = times.len() * n;
    check_len("translations", count * 3, translations.len())?;
    check_len("rotations", count * 4, rotations.len())?;
    check_len("scales", count * 3, scales.len())?;
    if n == 0 {
        return Ok(());
    }
    let mut poser = Poser::new(skeleton, clip)?;
    let frames = translations
        .chunks_exact_mut(n * 3)
        .zip(rotations.chunks_exact_mut(n * 4))
        .zip(scales.chunks_exact_mut(n * 3));
    for (&t, ((tr, ro), sc)) in times.iter().zip(frames) {
        poser.pose(t, space)?;
        for j in 0..n {
            let (translation, rotation, scale) = match space {
                Space::Model => {
                    let p = decompose(poser.models[j]);
                    (p.translation, p.rotation, p.scale)
                }
                Space::Local => {
                    let l = poser.locals[j];
                    (l.translation, l.rotation, l.scale)
                }
            };
            tr[j * 3..j * 3 + 3].copy_from_slice(&translation.to_array());
            ro[j * 4..j * 4 + 4].copy_from_slice(&rotation.to_array());
            sc[j * 3..j * 3 + 3].copy_from_slice(&scale.to_array());
        }
    }
    Ok(())
}

/// One clip played alone by one animator, posed at any time with the runtime's own calls: model
/// space through [`Animator::evaluate_palette`] (the call a game and the baker make), local space
/// through [`Animator::evaluate`].
struct Poser {
    animator: Animator,
    layer: ClipId,
    clip: String,
    models: Vec<Mat4>,
    palette: Vec<Mat4>,
    locals: Vec<Transform>,
}

impl Poser {
    fn new(skeleton: &Arc<Skeleton>, clip: &Arc<Clip>) -> Result<Self, BakeError> {
        let mut animator = Animator::new(skeleton.clone());
        let layer = animator.add_clip(clip.clone());
        animator.activate(layer)?;
        let n = skeleton.len();
        Ok(Self {
            animator,
            layer,
            clip: clip.name().to_string(),
            models: vec![Mat4::IDENTITY; n],
            palette: vec![Mat4::IDENTITY; n],
            locals: vec![Transform::IDENTITY; n],
        })
    }

    /// Poses the clip at `t` into `models` (model space) or `locals` (local space).
    fn pose(&mut self, t: f32, space: Space) -> Result<(), BakeError> {
        self.animator.set_time(self.layer, t)?;
        let result = match space {
            Space::Model => self
                .animator
                .evaluate_palette(&mut self.models, &mut self.palette),
            Space::Local => self.animator.evaluate(&mut self.locals),
        };
        result.map_err(|e| match e {
            AnimatorError::Clip(source) => BakeError::Clip {
                clip: self.clip.clone(),
                source,
            },
            other => BakeError::Animator(other),
        })
    }
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
