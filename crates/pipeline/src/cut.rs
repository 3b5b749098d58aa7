//! Cutting one timeline into named clips by frame range (`walk=1-30,run=31-50`).
//!
//! Half-Life models and Milkshape files keep every sequence on one timeline. Frame `k` is at time
//! `(k - first_frame_number) / sample_rate` (for MS3D `first_frame_number` is 1: clip time 0 is
//! Milkshape frame 1). A cut clip starts at time 0 at its first frame and lasts
//! `(b - a) / sample_rate`. Keys strictly inside the range are kept exactly (times shifted); the values
//! at the two ends are interpolated the way the clip is sampled (linear, normalised lerp for rotations),
//! so sampling the cut clip at any time gives what the source gives at the same frame.

use sinew_core::clip::nlerp;
use sinew_core::glam::Vec3;
use sinew_core::{Curve, TrackCurves};
use sinew_scene::SceneClip;

/// Why a cut specification could not be applied.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CutError {
    /// The specification is empty.
    #[error("empty cut specification (expected e.g. \"walk=1-30,run=31-50\")")]
    Empty,
    /// An item is not `name=a-b` with whole frame numbers and `a <= b`.
    #[error("cut item {item:?}: {message}")]
    Syntax {
        /// The item as written.
        item: String,
        /// What is wrong.
        message: String,
    },
    /// Two cuts share a name.
    #[error("cut name {0:?} is used twice")]
    DuplicateName(String),
    /// The clip's sample rate is not a positive, finite number.
    #[error("clip {clip:?} has sample rate {rate}; frames cannot be converted to times")]
    BadSampleRate {
        /// Clip name.
        clip: String,
        /// The rate.
        rate: f32,
    },
    /// A frame lies outside the clip.
    #[error("cut {name:?}: frame {frame} is outside the clip's frames {first}-{last}")]
    OutOfRange {
        /// Cut name.
        name: String,
        /// The offending frame.
        frame: u32,
        /// The clip's first frame number.
        first: u32,
        /// The clip's last frame number.
        last: u32,
    },
}

/// One parsed cut: name and inclusive frame range.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CutRange {
    /// Name of the clip to make.
    pub name: String,
    /// First frame (inclusive).
    pub first: u32,
    /// Last frame (inclusive).
    pub last: u32,
}

/// Parses `name=a-b[,name=a-b...]` (spaces around items allowed).
pub fn parse_cut_spec(spec: &str) -> Result<Vec<CutRange>, CutError> {
    let mut out: Vec<CutRange> = Vec::new();
    for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let syntax = |m: &str| CutError::Syntax {
            item: item.to_string(),
            message: m.to_string(),
        };
        let (name, range) = item
            .rsplit_once('=')
            .ok_or_else(|| syntax("expected name=first-last"))?;
        let name = name.trim();
        if name.is_empty() {
            return Err(syntax("the name is empty"));
        }
        let (a, b) = range
            .split_once('-')
            .ok_or_else(|| syntax("expected a frame range first-last"))?;
        let a: u32 = a
            .trim()
            .parse()
            .map_err(|_| syntax("the first frame is not a whole number"))?;
        let b: u32 = b
            .trim()
            .parse()
            .map_err(|_| syntax("the last frame is not a whole number"))?;
        if a > b {
            return Err(syntax("the first frame comes after the last"));
        }
        if out.iter().any(|c| c.name == name) {
            return Err(CutError::DuplicateName(name.to_string()));
        }
        out.push(CutRange {
            name: name.to_string(),
            first: a,
            last: b,
        });
    }
    if out.is_empty() {
        return Err(CutError::Empty);
    }
    Ok(out)
}

/// Cuts `clip` into one clip per item of `spec` (`"walk=1-30,run=31-50"`); see the module docs.
pub fn cut_clips(
    clip: &SceneClip,
    spec: &str,
    first_frame_number: u32,
) -> Result<Vec<SceneClip>, CutError> {
    let ranges = parse_cut_spec(spec)?;
    let rate = clip.sample_rate;
    if !(rate.is_finite() && rate > 0.0) {
        return Err(CutError::BadSampleRate {
            clip: clip.name.clone(),
            rate,
        });
    }
    let frames_in_clip = (clip.duration as f64 * rate as f64).round().max(0.0);
    let last_frame = (first_frame_number as f64 + frames_in_clip).min(u32::MAX as f64) as u32;
    let time_of = |k: u32| ((k - first_frame_number) as f64 / rate as f64) as f32;
    let mut out = Vec::with_capacity(ranges.len());
    for r in ranges {
        for frame in [r.first, r.last] {
            if frame < first_frame_number || frame > last_frame {
                return Err(CutError::OutOfRange {
                    name: r.name.clone(),
                    frame,
                    first: first_frame_number,
                    last: last_frame,
                });
            }
        }
        let (t0, t1) = (time_of(r.first), time_of(r.last));
        let tracks = clip
            .tracks
            .iter()
            .map(|t| TrackCurves {
                joint: t.joint.clone(),
                translation: cut_curve(&t.translation, t0, t1, |a, b, x| a.lerp(b, x)),
                rotation: cut_curve(&t.rotation, t0, t1, nlerp),
                scale: cut_curve(&t.scale, t0, t1, |a, b, x: f32| -> Vec3 { a.lerp(b, x) }),
            })
            .collect();
        out.push(SceneClip {
            name: r.name,
            duration: t1 - t0,
            sample_rate: rate,
            looping: false,
            additive: clip.additive,
            tracks,
        });
    }
    Ok(out)
}

/// Keys closer than this (relative to the time) to a range end count as being at the end.
fn snap(t: f32) -> f32 {
    1e-6 * t.abs().max(1.0)
}

/// The curve's value at `t`: clamped outside the keys, exact at (or within [`snap`] of) a key.
fn curve_at<T: Copy>(c: &Curve<T>, t: f32, lerp: impl Fn(T, T, f32) -> T) -> Option<T> {
    let n = c.times.len().min(c.values.len());
    if n == 0 {
        return None;
    }
    let eps = snap(t);
    if let Some(i) = c.times[..n].iter().position(|&k| (k - t).abs() <= eps) {
        return Some(c.values[i]);
    }
    if t <= c.times[0] {
        return Some(c.values[0]);
    }
    if t >= c.times[n - 1] {
        return Some(c.values[n - 1]);
    }
    let i = c.times[..n].partition_point(|&k| k <= t).saturating_sub(1);
    let (a, b) = (c.times[i], c.times[i + 1]);
    let x = (t - a) / (b - a);
    Some(lerp(c.values[i], c.values[i + 1], x))
}

fn cut_curve<T: Copy>(c: &Curve<T>, t0: f32, t1: f32, lerp: impl Fn(T, T, f32) -> T) -> Curve<T> {
    let Some(v0) = curve_at(c, t0, &lerp) else {
        return Curve::new(Vec::new(), Vec::new());
    };
    let mut times = vec![0.0];
    let mut values = vec![v0];
    if t1 > t0 {
        let (lo, hi) = (t0 + snap(t0), t1 - snap(t1));
        for (&k, &v) in c.times.iter().zip(&c.values) {
            if k > lo && k < hi {
                let shifted = k - t0;
                if shifted > times[times.len() - 1] {
                    times.push(shifted);
                    values.push(v);
                }
            }
        }
        if let Some(v1) = curve_at(c, t1, &lerp) {
            let end = t1 - t0;
            if end > times[times.len() - 1] {
                times.push(end);
                values.push(v1);
            }
        }
    }
    Curve::new(times, values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sinew_core::glam::Quat;

    fn clip() -> SceneClip {
        // 30 fps, frames 1..=11 (duration 10/30 s); translation x = frame number, keys every 2 frames
        // (frames 1, 3, ..., 11); rotation a 90-degree turn about y over the whole clip in 2 keys.
        let rate = 30.0;
        let tt: Vec<f32> = (0..=5).map(|i| (2 * i) as f32 / rate).collect();
        let tv: Vec<Vec3> = (0..=5)
            .map(|i| Vec3::new((1 + 2 * i) as f32, 0.0, 0.0))
            .collect();
        SceneClip {
            name: "all".into(),
            duration: 10.0 / rate,
            sample_rate: rate,
            looping: false,
            additive: false,
            tracks: vec![TrackCurves {
                joint: "root".into(),
                translation: Curve::new(tt, tv),
                rotation: Curve::new(
                    vec![0.0, 10.0 / rate],
                    vec![
                        Quat::IDENTITY,
                        Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
                    ],
                ),
                scale: Curve::default(),
            }],
        }
    }

    #[test]
    fn cuts_keep_inner_keys_and_interpolate_the_ends() {
        let cuts = cut_clips(&clip(), "a=2-6, b=7-11", 1).unwrap();
        assert_eq!(cuts.len(), 2);
        let a = &cuts[0];
        assert_eq!(a.name, "a");
        assert!((a.duration - 4.0 / 30.0).abs() < 1e-7);
        let tr = &a.tracks[0].translation;
        // Frame 2 (interpolated, x = 2), keys at frames 3 and 5 (exact), frame 6 (interpolated, x = 6).
        let xs: Vec<f32> = tr.values.iter().map(|v| v.x).collect();
        assert_eq!(xs.len(), 4);
        for (x, want) in xs.iter().zip([2.0, 3.0, 5.0, 6.0]) {
            assert!((x - want).abs() < 1e-5, "{xs:?}");
        }
        assert_eq!(tr.times[0], 0.0);
        assert!((tr.times[1] - 1.0 / 30.0).abs() < 1e-6);
        // Frame 3's key kept bit for bit.
        assert_eq!(tr.values[1], Vec3::new(3.0, 0.0, 0.0));
        let b = &cuts[1];
        let tr = &b.tracks[0].translation;
        assert_eq!(tr.values.first().unwrap().x, 7.0);
        assert_eq!(tr.values.last().unwrap().x, 11.0);
        assert_eq!(tr.times.len(), 3); // keys at frames 7, 9, 11: 7 and 11 are the ends, 9 inside.
                                       // Rotation at frame 11 (the end) is the last key exactly.
        let r = &b.tracks[0].rotation;
        assert_eq!(
            *r.values.last().unwrap(),
            Quat::from_rotation_y(std::f32::consts::FRAC_PI_2)
        );
        assert_eq!(r.times.len(), 2);
    }

    #[test]
    fn single_frame_cut_has_one_key() {
        let cuts = cut_clips(&clip(), "pose=4-4", 1).unwrap();
        assert_eq!(cuts[0].duration, 0.0);
        assert_eq!(cuts[0].tracks[0].translation.times, vec![0.0]);
        assert!((cuts[0].tracks[0].translation.values[0].x - 4.0).abs() < 1e-5);
    }

    #[test]
    fn bad_specs_are_errors() {
        let c = clip();
        assert_eq!(cut_clips(&c, "", 1), Err(CutError::Empty));
        assert!(matches!(
            cut_clips(&c, "walk", 1),
            Err(CutError::Syntax { .. })
        ));
        assert!(matches!(
            cut_clips(&c, "walk=5-2", 1),
            Err(CutError::Syntax { .. })
        ));
        assert!(matches!(
            cut_clips(&c, "=1-2", 1),
            Err(CutError::Syntax { .. })
        ));
        assert_eq!(
            cut_clips(&c, "a=1-2,a=3-4", 1),
            Err(CutError::DuplicateName("a".into()))
        );
        assert_eq!(
            cut_clips(&c, "a=1-12", 1),
            Err(CutError::OutOfRange {
                name: "a".into(),
                frame: 12,
                first: 1,
                last: 11
            })
        );
        assert!(matches!(
            cut_clips(&c, "a=0-2", 1),
            Err(CutError::OutOfRange { frame: 0, .. })
        ));
        let mut bad = c.clone();
        bad.sample_rate = 0.0;
        assert!(matches!(
            cut_clips(&bad, "a=1-2", 1),
            Err(CutError::BadSampleRate { .. })
        ));
    }
}
