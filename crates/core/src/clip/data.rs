//! Clip data: curves, tracks, channels and the immutable [`Clip`] built from them (plain or compressed).

use crate::compressed::{Quantized, QuantizedParts};
use crate::rotation::nlerp;
use glam::{Quat, Vec3};

/// Zero floats kept after the last frame (of a clip, or of a sampler's decoded keys), so that the
/// sampler can load any channel's floats four at a time.
pub(super) const FRAME_PAD: usize = 3;

/// A keyed curve: strictly increasing times with one value each, linearly interpolated.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Curve<T> {
    /// Key times, seconds, strictly increasing.
    pub times: Vec<f32>,
    /// One value per key time.
    pub values: Vec<T>,
}

impl<T> Curve<T> {
    /// A curve from parallel arrays.
    pub fn new(times: Vec<f32>, values: Vec<T>) -> Self {
        Self { times, values }
    }
    /// True when the curve has no keys (the channel is not animated by this clip).
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

/// The curves of one joint, as a clip is built.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TrackCurves {
    /// Name of the joint this track drives.
    pub joint: String,
    /// Translation keys; empty when the clip does not drive translation.
    pub translation: Curve<Vec3>,
    /// Rotation keys; empty when the clip does not drive rotation.
    pub rotation: Curve<Quat>,
    /// Scale keys; empty when the clip does not drive scale.
    pub scale: Curve<Vec3>,
}

/// Where a channel's value comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Channel<T> {
    /// Not stored: the joint's bind value (identity difference in an additive clip).
    Bind,
    /// The same value at all times.
    Constant(T),
    /// Animated: the value sits at this float offset inside every frame.
    Animated(u32),
}

/// One joint's channels inside a [`Clip`].
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    /// Name of the joint this track drives.
    pub joint: String,
    /// Translation channel.
    pub translation: Channel<Vec3>,
    /// Rotation channel.
    pub rotation: Channel<Quat>,
    /// Scale channel.
    pub scale: Channel<Vec3>,
}

/// Why a clip could not be built or used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClipError {
    /// A curve's times and values differ in length.
    #[error("track {0:?}: times and values differ in length")]
    LengthMismatch(String),
    /// Key times are not strictly increasing, negative or not finite.
    #[error("track {0:?}: key times must be finite, at or after 0, and strictly increasing")]
    BadTimes(String),
    /// A key value is NaN or infinite.
    #[error("track {0:?}: non-finite key value")]
    NonFinite(String),
    /// Duration negative or not finite, or shorter than the last key.
    #[error("duration {0} is not finite, negative, or before the last key")]
    BadDuration(f32),
    /// Two tracks drive the same joint.
    #[error("two tracks drive joint {0:?}")]
    DuplicateTrack(String),
    /// Frame data does not match the declared layout.
    #[error("frame data holds {got} floats; the layout needs {expected}")]
    FrameSize {
        /// Floats the layout needs.
        expected: usize,
        /// Floats present.
        got: usize,
    },
    /// A channel's offset points outside the frame.
    #[error("track {0:?}: channel offset outside the frame")]
    BadOffset(String),
    /// A buffer given to sampling has the wrong length.
    #[error("output has {got} joints; the skeleton has {expected}")]
    OutputLength {
        /// Joints in the skeleton.
        expected: usize,
        /// Joints in the output.
        got: usize,
    },
    /// The binding was made for another clip or skeleton.
    #[error("binding does not belong to this clip and skeleton")]
    BindingMismatch,
    /// A compressed clip's payload does not match its layout (see [`crate::compressed`]).
    #[error("compressed clip: {0}")]
    BadCompressed(String),
}

/// How one channel of a track is stored, for inspection.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChannelEncoding {
    /// Not stored: the bind value (identity difference in an additive clip).
    Bind,
    /// One f32 value.
    Constant,
    /// Plain f32 values in every frame.
    F32,
    /// Quantized components; rotations as the three smallest components plus a 2-bit index.
    Quantized {
        /// Per component, the smallest bit width over all segments.
        min_bits: [u8; 3],
        /// Per component, the largest bit width over all segments.
        max_bits: [u8; 3],
    },
}

/// Shared, immutable animation data. See the module docs for its time semantics.
#[derive(Debug, Clone, PartialEq)]
pub struct Clip {
    pub(super) name: String,
    pub(super) duration: f32,
    pub(super) sample_rate: f32,
    pub(super) looping: bool,
    pub(super) additive: bool,
    pub(super) times: Vec<f32>,
    pub(super) tracks: Vec<Track>,
    pub(super) stride: usize,
    pub(super) frames: Vec<f32>,
    pub(super) quantized: Option<Box<Quantized>>,
    pub(super) id: Identity,
}

pub(super) fn check_curve<T>(
    joint: &str,
    c: &Curve<T>,
    finite: impl Fn(&T) -> bool,
) -> Result<(), ClipError> {
    if c.times.len() != c.values.len() {
        return Err(ClipError::LengthMismatch(joint.into()));
    }
    let mut prev = -1.0f32;
    for &t in &c.times {
        if !t.is_finite() || t < 0.0 || t <= prev {
            return Err(ClipError::BadTimes(joint.into()));
        }
        prev = t;
    }
    if !c.values.iter().all(finite) {
        return Err(ClipError::NonFinite(joint.into()));
    }
    Ok(())
}

/// Value of a linear curve at `t` (clamped at the ends; exact at key times), for times that never
/// decrease from one call to the next: `next` is the number of the curve's keys at or before the
/// previous time, moved forward instead of searched for.
fn curve_walk<T: Copy>(c: &Curve<T>, next: &mut usize, t: f32, lerp: impl Fn(T, T, f32) -> T) -> T {
    while *next < c.times.len() && c.times[*next] <= t {
        *next += 1;
    }
    curve_at_key(c, *next, t, lerp)
}

/// The value at `t` of a curve whose first `k` keys are at or before `t`.
fn curve_at_key<T: Copy>(c: &Curve<T>, k: usize, t: f32, lerp: impl Fn(T, T, f32) -> T) -> T {
    if k == 0 {
        return c.values[0];
    }
    if k >= c.times.len() {
        return c.values[c.values.len() - 1];
    }
    let (t0, t1) = (c.times[k - 1], c.times[k]);
    let a = (t - t0) / (t1 - t0);
    if a <= 0.0 {
        c.values[k - 1]
    } else {
        lerp(c.values[k - 1], c.values[k], a)
    }
}

impl Clip {
    /// Builds a clip from per-joint curves.
    ///
    /// Every key time of every curve becomes a key time of the clip, so sampling the clip at any source
    /// key time gives that source value exactly. A curve whose values are all equal is stored once as a
    /// constant. `sample_rate` is the nominal rate of the source (used by bakes and reports), not a
    /// resampling.
    pub fn from_curves(
        name: impl Into<String>,
        duration: f32,
        sample_rate: f32,
        looping: bool,
        additive: bool,
        tracks: Vec<TrackCurves>,
    ) -> Result<Clip, ClipError> {
        let mut seen = std::collections::HashSet::new();
        for t in &tracks {
            if !seen.insert(t.joint.as_str()) {
                return Err(ClipError::DuplicateTrack(t.joint.clone()));
            }
            check_curve(&t.joint, &t.translation, |v| v.is_finite())?;
            check_curve(&t.joint, &t.rotation, |v| v.is_finite())?;
            check_curve(&t.joint, &t.scale, |v| v.is_finite())?;
        }
        fn constant<T: PartialEq + Copy>(c: &Curve<T>) -> Option<T> {
            let first = *c.values.first()?;
            c.values.iter().all(|v| *v == first).then_some(first)
        }
        // Each animated channel's key times, but for a list the same (bit for bit) as the one
        // before it: most sources key every channel at the same frames.
        let mut lists: Vec<&[f32]> = Vec::new();
        let mut out_tracks = Vec::with_capacity(tracks.len());
        let mut stride = 0usize;
        for t in &tracks {
            let mut channel_t = Channel::Bind;
            let mut channel_r = Channel::Bind;
            let mut channel_s = Channel::Bind;
            if !t.translation.is_empty() {
                channel_t = match constant(&t.translation) {
                    Some(v) => Channel::Constant(v),
                    None => {
                        add_times(&mut lists, &t.translation.times);
                        stride += 3;
                        Channel::Animated((stride - 3) as u32)
                    }
                };
            }
            if !t.rotation.is_empty() {
                channel_r = match constant(&t.rotation) {
                    Some(v) => Channel::Constant(v.normalize()),
                    None => {
                        add_times(&mut lists, &t.rotation.times);
                        stride += 4;
                        Channel::Animated((stride - 4) as u32)
                    }
                };
            }
            if !t.scale.is_empty() {
                channel_s = match constant(&t.scale) {
                    Some(v) => Channel::Constant(v),
                    None => {
                        add_times(&mut lists, &t.scale.times);
                        stride += 3;
                        Channel::Animated((stride - 3) as u32)
                    }
                };
            }
            out_tracks.push(Track {
                joint: t.joint.clone(),
                translation: channel_t,
                rotation: channel_r,
                scale: channel_s,
            });
        }
        let mut times = super::times::union_of_times(&lists);
        if times.is_empty() {
            times.push(0.0);
        }
        let last = times[times.len() - 1];
        if !duration.is_finite() || duration < 0.0 || (stride > 0 && duration < last) {
            return Err(ClipError::BadDuration(duration));
        }
        let mut frames = vec![0.0f32; times.len() * stride];
        for (src, dst) in tracks.iter().zip(&out_tracks) {
            // The clip's times increase, so each curve's key is found by walking forward.
            let (mut next_t, mut next_r, mut next_s) = (0, 0, 0);
            for (f, &time) in times.iter().enumerate() {
                let frame = &mut frames[f * stride..(f + 1) * stride];
                if let Channel::Animated(o) = dst.translation {
                    let v = curve_walk(&src.translation, &mut next_t, time, |a, b, x| a.lerp(b, x));
                    frame[o as usize..o as usize + 3].copy_from_slice(&v.to_array());
                }
                if let Channel::Animated(o) = dst.rotation {
                    let v = curve_walk(&src.rotation, &mut next_r, time, nlerp);
                    frame[o as usize..o as usize + 4].copy_from_slice(&v.to_array());
                }
                if let Channel::Animated(o) = dst.scale {
                    let v = curve_walk(&src.scale, &mut next_s, time, |a, b, x| a.lerp(b, x));
                    frame[o as usize..o as usize + 3].copy_from_slice(&v.to_array());
                }
            }
        }
        Clip::from_parts(
            name.into(),
            duration,
            sample_rate,
            looping,
            additive,
            times,
            out_tracks,
            stride,
            frames,
        )
    }

    /// Assembles a clip from its stored layout (what the `.sinew` reader holds), checking every part.
    #[allow(clippy::too_many_arguments)]
    pub fn from_parts(
        name: String,
        duration: f32,
        sample_rate: f32,
        looping: bool,
        additive: bool,
        times: Vec<f32>,
        tracks: Vec<Track>,
        stride: usize,
        frames: Vec<f32>,
    ) -> Result<Clip, ClipError> {
        let curve = Curve {
            times: times.clone(),
            values: vec![(); times.len()],
        };
        check_curve(&name, &curve, |_| true)?;
        if times.is_empty() {
            return Err(ClipError::BadTimes(name));
        }
        if !duration.is_finite()
            || duration < 0.0
            || (stride > 0 && duration < times[times.len() - 1])
        {
            return Err(ClipError::BadDuration(duration));
        }
        let expected = times
            .len()
            .checked_mul(stride)
            .ok_or(ClipError::FrameSize {
                expected: usize::MAX,
                got: frames.len(),
            })?;
        if frames.len() != expected {
            return Err(ClipError::FrameSize {
                expected,
                got: frames.len(),
            });
        }
        if !frames.iter().all(|v| v.is_finite()) {
            return Err(ClipError::NonFinite(name));
        }
        let mut seen = std::collections::HashSet::new();
        for t in &tracks {
            if !seen.insert(t.joint.as_str()) {
                return Err(ClipError::DuplicateTrack(t.joint.clone()));
            }
            let ok = |c: Option<u32>, n: usize| c.is_none_or(|o| (o as usize) + n <= stride);
            let off = |c: &Channel<Vec3>| match c {
                Channel::Animated(o) => Some(*o),
                _ => None,
            };
            let off_r = match t.rotation {
                Channel::Animated(o) => Some(o),
                _ => None,
            };
            if !ok(off(&t.translation), 3) || !ok(off_r, 4) || !ok(off(&t.scale), 3) {
                return Err(ClipError::BadOffset(t.joint.clone()));
            }
            let finite = match (t.translation, t.rotation, t.scale) {
                (Channel::Constant(v), _, _) if !v.is_finite() => false,
                (_, Channel::Constant(q), _) if !q.is_finite() => false,
                (_, _, Channel::Constant(v)) if !v.is_finite() => false,
                _ => true,
            };
            if !finite {
                return Err(ClipError::NonFinite(t.joint.clone()));
            }
        }
        let mut frames = frames;
        frames.extend([0.0; FRAME_PAD]);
        Ok(Clip {
            name,
            duration,
            sample_rate,
            looping,
            additive,
            times,
            tracks,
            stride,
            frames,
            quantized: None,
            id: Identity::new(),
        })
    }

    /// Assembles a compressed clip: key times and tracks as in [`Clip::from_parts`], but every animated
    /// channel is numbered by its first component in [`crate::compressed`]'s order (components are
    /// numbered consecutively over the tracks' translation, rotation and scale channels), and the values
    /// come from `parts`. Every part is checked; a bad payload is [`ClipError::BadCompressed`].
    #[allow(clippy::too_many_arguments)]
    pub fn from_quantized(
        name: String,
        duration: f32,
        sample_rate: f32,
        looping: bool,
        additive: bool,
        times: Vec<f32>,
        tracks: Vec<Track>,
        parts: QuantizedParts,
    ) -> Result<Clip, ClipError> {
        let starts = rotation_starts(&tracks).map_err(ClipError::BadOffset)?;
        let keys = times.len();
        let mut clip = Clip::from_parts(
            name,
            duration,
            sample_rate,
            looping,
            additive,
            times,
            tracks
                .iter()
                .map(|t| Track {
                    joint: t.joint.clone(),
                    translation: plain_only(t.translation),
                    rotation: plain_only(t.rotation),
                    scale: plain_only(t.scale),
                })
                .collect(),
            0,
            Vec::new(),
        )?;
        if !starts.is_empty() && clip.duration < clip.times[clip.times.len() - 1] {
            return Err(ClipError::BadDuration(clip.duration));
        }
        clip.tracks = tracks;
        clip.quantized = Some(Box::new(
            Quantized::new(parts, keys, &starts).map_err(ClipError::BadCompressed)?,
        ));
        Ok(clip)
    }

    /// True when the clip's animated channels are quantized (see [`crate::compressed`]).
    pub fn is_compressed(&self) -> bool {
        self.quantized.is_some()
    }

    /// The compressed payload, for writers and inspection.
    pub fn quantized_parts(&self) -> Option<&QuantizedParts> {
        self.quantized.as_deref().map(|q| &q.parts)
    }

    /// How each channel (translation, rotation, scale) of track `track` is stored.
    pub fn channel_encodings(&self, track: usize) -> Option<[ChannelEncoding; 3]> {
        let t = self.tracks.get(track)?;
        let enc = |c: Option<u32>, constant: bool| match (c, &self.quantized) {
            (None, _) if constant => ChannelEncoding::Constant,
            (None, _) => ChannelEncoding::Bind,
            (Some(_), None) => ChannelEncoding::F32,
            (Some(first), Some(q)) => {
                let mut min_bits = [0; 3];
                let mut max_bits = [0; 3];
                for i in 0..3 {
                    (min_bits[i], max_bits[i]) = q.bit_range(first as usize + i);
                }
                ChannelEncoding::Quantized { min_bits, max_bits }
            }
        };
        Some([
            enc(
                animated(t.translation),
                matches!(t.translation, Channel::Constant(_)),
            ),
            enc(
                animated(t.rotation),
                matches!(t.rotation, Channel::Constant(_)),
            ),
            enc(animated(t.scale), matches!(t.scale, Channel::Constant(_))),
        ])
    }

    /// The same clip with plain f32 frames: every key decoded (a plain clip is returned as a copy).
    pub fn to_plain(&self) -> Clip {
        let Some(q) = &self.quantized else {
            return self.clone();
        };
        let mut stride = 0u32;
        let mut tracks = Vec::with_capacity(self.tracks.len());
        let mut next = |c: Option<u32>, n: u32| {
            c.map(|_| {
                stride += n;
                stride - n
            })
        };
        for t in &self.tracks {
            let at = |c: Channel<Vec3>, o: Option<u32>| o.map_or(c, Channel::Animated);
            let ot = next(animated(t.translation), 3);
            let or = next(animated(t.rotation), 4);
            let os = next(animated(t.scale), 3);
            tracks.push(Track {
                joint: t.joint.clone(),
                translation: at(t.translation, ot),
                rotation: or.map_or(t.rotation, Channel::Animated),
                scale: at(t.scale, os),
            });
        }
        let stride = stride as usize;
        let mut frames = vec![0.0f32; stride * self.times.len() + FRAME_PAD];
        for (k, frame) in frames[..stride * self.times.len()]
            .chunks_exact_mut(stride.max(1))
            .enumerate()
        {
            let key = q.key(k);
            for (src, dst) in self.tracks.iter().zip(&tracks) {
                if let (Channel::Animated(c), Channel::Animated(o)) =
                    (src.translation, dst.translation)
                {
                    frame[o as usize..o as usize + 3]
                        .copy_from_slice(&key.vec3(c as usize).to_array());
                }
                if let (Channel::Animated(c), Channel::Animated(o)) = (src.rotation, dst.rotation) {
                    frame[o as usize..o as usize + 4]
                        .copy_from_slice(&key.quat(c as usize).to_array());
                }
                if let (Channel::Animated(c), Channel::Animated(o)) = (src.scale, dst.scale) {
                    frame[o as usize..o as usize + 3]
                        .copy_from_slice(&key.vec3(c as usize).to_array());
                }
            }
        }
        Clip {
            tracks,
            stride,
            frames,
            quantized: None,
            id: Identity::new(),
            ..self.clone()
        }
    }

    /// Clip name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Duration in seconds.
    pub fn duration(&self) -> f32 {
        self.duration
    }
    /// Nominal sample rate of the source, frames per second.
    pub fn sample_rate(&self) -> f32 {
        self.sample_rate
    }
    /// Whether time wraps around (see the module docs).
    pub fn looping(&self) -> bool {
        self.looping
    }
    /// Whether the clip holds differences from a reference pose.
    pub fn additive(&self) -> bool {
        self.additive
    }
    /// Key times shared by every animated channel.
    pub fn times(&self) -> &[f32] {
        &self.times
    }
    /// Tracks, one per driven joint.
    pub fn tracks(&self) -> &[Track] {
        &self.tracks
    }
    /// Floats per frame.
    pub fn stride(&self) -> usize {
        self.stride
    }
    /// All frames, time-major: frame `k` is `frames[k * stride .. (k + 1) * stride]`.
    pub fn frames(&self) -> &[f32] {
        &self.frames[..self.frames.len() - FRAME_PAD]
    }
    /// Returns a copy with another name.
    pub fn renamed(&self, name: impl Into<String>) -> Clip {
        Clip {
            name: name.into(),
            ..self.clone()
        }
    }
    /// Returns a copy with another looping flag.
    pub fn with_looping(&self, looping: bool) -> Clip {
        Clip {
            looping,
            ..self.clone()
        }
    }

    /// Where an animated channel's values start in a frame the sampler reads: the plain frame offset, or
    /// for a compressed clip the offset inside a key decoded to f32 (see [`Quantized::decode_lanes`]).
    pub(super) fn frame_offset(&self, o: u32) -> usize {
        match &self.quantized {
            None => o as usize,
            Some(q) => q
                .group_dest
                .get(o as usize / 3)
                .map_or(usize::MAX / 2, |&d| d as usize),
        }
    }

    /// Floats per frame the sampler reads (plain stride, or a decoded key's size).
    pub(super) fn frame_stride(&self) -> usize {
        match &self.quantized {
            None => self.stride,
            Some(q) => q.decoded_stride,
        }
    }

    /// Maps a playback time to the clip's own time, per the looping rule.
    #[inline]
    pub fn local_time(&self, t: f32) -> f32 {
        if !t.is_finite() {
            return 0.0;
        }
        if self.looping && self.duration > 0.0 {
            if t >= 0.0 && t < self.duration {
                // Already wrapped (the animator keeps its times so): `rem_euclid` would return `t`
                // itself, at the cost of a library call.
                return t;
            }
            let r = t.rem_euclid(self.duration);
            if r >= self.duration {
                0.0
            } else {
                r
            }
        } else {
            t.clamp(0.0, self.duration)
        }
    }
}

/// Appends a curve's key times to `times` unless they are bit for bit the ones appended last.
fn add_times<'a>(lists: &mut Vec<&'a [f32]>, curve: &'a [f32]) {
    let same = lists.last().is_some_and(|last| {
        curve.len() == last.len()
            && curve
                .iter()
                .zip(last.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits())
    });
    if !same {
        lists.push(curve);
    }
}

pub(super) fn animated<T>(c: Channel<T>) -> Option<u32> {
    match c {
        Channel::Animated(o) => Some(o),
        _ => None,
    }
}

pub(super) fn plain_only<T>(c: Channel<T>) -> Channel<T> {
    match c {
        Channel::Animated(_) => Channel::Bind,
        other => other,
    }
}

/// The component layout of compressed tracks: for each component, whether it starts a rotation.
/// Fails (naming the joint) unless animated channels are numbered consecutively in track order.
pub(crate) fn rotation_starts(tracks: &[Track]) -> Result<Vec<bool>, String> {
    let mut starts = Vec::new();
    for t in tracks {
        for (c, rot) in [
            (animated(t.translation), false),
            (animated(t.rotation), true),
            (animated(t.scale), false),
        ] {
            if let Some(first) = c {
                if first as usize != starts.len() {
                    return Err(t.joint.clone());
                }
                starts.extend([rot, false, false]);
            }
        }
    }
    Ok(starts)
}

/// A process-unique identity for the sampler's key cache: clones share it (they hold the same data),
/// and it takes no part in equality.
#[derive(Debug, Clone, Copy)]
pub(super) struct Identity(pub(super) u64);

impl Identity {
    pub(super) fn new() -> Self {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        Identity(NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed))
    }
}

impl PartialEq for Identity {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}
