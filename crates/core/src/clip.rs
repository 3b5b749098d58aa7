//! Clips: shared, immutable animation data, bound to skeletons by joint name and sampled with a cursor.
//!
//! # Time and samples
//!
//! A clip stores one strictly increasing array of key times (`times`, seconds, the first at or after 0),
//! shared by every animated channel, and for each key time one *frame*: the values of all animated
//! channels at that time, side by side (time-major). A channel that never changes is stored once as a
//! constant; a channel the clip does not have takes the joint's bind value.
//!
//! Sampling at time `t`:
//! - **Non-looping clip** (`looping == false`): `t` is clamped to `[0, duration]`. Before the first key
//!   the first frame holds; after the last key the last frame holds. Between keys `k` and `k+1` values
//!   are interpolated linearly (translation, scale) or by normalised lerp along the shortest path
//!   (rotation). At a key time the stored value is returned bit for bit. A clip of N frames sampled
//!   uniformly at rate `r` has keys at `0, 1/r, ..., (N-1)/r` and duration `(N-1)/r`: its last frame is
//!   its end.
//! - **Looping clip** (`looping == true`): `t` is wrapped into `[0, duration)` (negative times wrap
//!   too). Between the last key and `duration` the values run from the last frame back to the first,
//!   which is reached again at `duration`. A looping clip of N frames at rate `r` has keys at
//!   `0, ..., (N-1)/r` and duration `N/r`: frame 0 is *not* repeated at the end, and the segment after
//!   frame N-1 interpolates towards frame 0. When a source repeats frame 0 as its last frame, the
//!   wrap segment has length zero and nothing changes.
//!
//! An additive clip stores, per channel, a difference from a reference pose: a translation to add, a
//! rotation to apply before the base rotation (`delta * base`), and a scale factor. Missing channels of an
//! additive clip are the identity difference.

use crate::compressed::{LaneTable, Quantized, QuantizedParts};
use crate::skeleton::{JointIndex, Skeleton};
use crate::soa::{self, PlanBlock};
use crate::Transform;
use glam::{Quat, Vec3};

/// Zero floats kept after the last frame (of a clip, or of a sampler's decoded keys), so that the
/// sampler can load any channel's floats four at a time.
const FRAME_PAD: usize = 3;

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
    name: String,
    duration: f32,
    sample_rate: f32,
    looping: bool,
    additive: bool,
    times: Vec<f32>,
    tracks: Vec<Track>,
    stride: usize,
    frames: Vec<f32>,
    quantized: Option<Box<Quantized>>,
    id: Identity,
}

fn check_curve<T>(joint: &str, c: &Curve<T>, finite: impl Fn(&T) -> bool) -> Result<(), ClipError> {
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

/// Value of a linear curve at `t` (clamped at the ends); exact at key times.
fn curve_at<T: Copy>(c: &Curve<T>, t: f32, lerp: impl Fn(T, T, f32) -> T) -> T {
    let k = c.times.partition_point(|&x| x <= t);
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

/// The runtime's normalisation of a rotation: `q * (1 / |q|)`, the length summed as glam's `dot` sums
/// (`(x*x + z*z) + (y*y + w*w)`). Sampling and blending normalise this way, four joints at a time
/// with the same per-lane operations (one division per four rotations instead of four); the result is
/// within an ulp of `q / |q|`.
#[inline]
pub fn normalize_rotation(q: Quat) -> Quat {
    q * q.length_recip()
}

/// Normalised lerp along the shortest path: `b` is negated when `a · b < 0`, then
/// `a * (1 - alpha) + b * alpha` is normalised with [`normalize_rotation`]. The sampler does exactly
/// this, four joints at a time.
#[inline]
pub fn nlerp(a: Quat, b: Quat, alpha: f32) -> Quat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    normalize_rotation(a * (1.0 - alpha) + b * alpha)
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
        let mut times: Vec<f32> = Vec::new();
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
                        times.extend_from_slice(&t.translation.times);
                        stride += 3;
                        Channel::Animated((stride - 3) as u32)
                    }
                };
            }
            if !t.rotation.is_empty() {
                channel_r = match constant(&t.rotation) {
                    Some(v) => Channel::Constant(v.normalize()),
                    None => {
                        times.extend_from_slice(&t.rotation.times);
                        stride += 4;
                        Channel::Animated((stride - 4) as u32)
                    }
                };
            }
            if !t.scale.is_empty() {
                channel_s = match constant(&t.scale) {
                    Some(v) => Channel::Constant(v),
                    None => {
                        times.extend_from_slice(&t.scale.times);
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
        times.sort_by(f32::total_cmp);
        times.dedup();
        if times.is_empty() {
            times.push(0.0);
        }
        let last = times[times.len() - 1];
        if !duration.is_finite() || duration < 0.0 || (stride > 0 && duration < last) {
            return Err(ClipError::BadDuration(duration));
        }
        let mut frames = vec![0.0f32; times.len() * stride];
        for (src, dst) in tracks.iter().zip(&out_tracks) {
            for (f, &time) in times.iter().enumerate() {
                let frame = &mut frames[f * stride..(f + 1) * stride];
                if let Channel::Animated(o) = dst.translation {
                    let v = curve_at(&src.translation, time, |a, b, x| a.lerp(b, x));
                    frame[o as usize..o as usize + 3].copy_from_slice(&v.to_array());
                }
                if let Channel::Animated(o) = dst.rotation {
                    let v = curve_at(&src.rotation, time, nlerp);
                    frame[o as usize..o as usize + 4].copy_from_slice(&v.to_array());
                }
                if let Channel::Animated(o) = dst.scale {
                    let v = curve_at(&src.scale, time, |a, b, x| a.lerp(b, x));
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
        clip.quantized = Some(Box::new(Quantized::new(parts, keys, &starts)?));
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
    fn frame_offset(&self, o: u32) -> usize {
        match &self.quantized {
            None => o as usize,
            Some(q) => q
                .group_dest
                .get(o as usize / 3)
                .map_or(usize::MAX / 2, |&d| d as usize),
        }
    }

    /// Floats per frame the sampler reads (plain stride, or a decoded key's size).
    fn frame_stride(&self) -> usize {
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

/// A process-unique identity for the sampler's key cache: clones share it (they hold the same data),
/// and it takes no part in equality.
#[derive(Debug, Clone, Copy)]
struct Identity(u64);

impl Identity {
    fn new() -> Self {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        Identity(NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed))
    }
}

impl PartialEq for Identity {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// A clip bound to a skeleton: for each track, the joint it drives. Made once, reused every frame.
///
/// Besides the joint of each track it holds the sampler's *plan*: the blocks of four skeleton joints
/// the clip drives (structure-of-arrays blocks), per block and channel kind which lanes are animated and the
/// values of the others (constants, bind values), and for every animated component of a driven joint
/// where it sits in a (decoded) frame and where it goes in a block. Sampling then needs no per-joint
/// matching and runs four joints per instruction.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipBinding {
    joint_of_track: Vec<Option<JointIndex>>,
    unmatched: Vec<String>,
    driven: Vec<JointIndex>,
    skeleton_len: usize,
    /// Floats per frame of the layout the plan's offsets point into.
    frame_stride: usize,
    plan: Vec<PlanBlock>,
    /// `(offset in a frame, float index in the plan's blocks)` for every animated component of a
    /// driven joint, by offset.
    gather: Vec<(u32, u32)>,
    /// `gather` as the sampler loads keys: whole blocks by transposition where every driven joint of
    /// the block has the same animated channels, single vectors elsewhere.
    blocks: Vec<GatherBlock>,
    vectors: Vec<GatherVector>,
    /// For a compressed clip (whose keys load without `blocks` and `vectors`): per plan block and
    /// animated kind, the channel each lane decodes, in plan order.
    decode: Vec<DecodeBlock>,
    id: Identity,
}

/// Four lanes of one plan block that a compressed key decodes straight into, one channel kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct DecodeBlock {
    /// Vector index inside a key slot of the kind's first component.
    first: u32,
    /// Per lane: the compressed channel (component / 3) decoded into it, where `lanes` is set.
    channel: [u32; 4],
    /// The animated lanes (the others keep their fixed values).
    lanes: u8,
    rotation: bool,
}

/// The [`DecodeBlock`]s of `plan`: `channel_of(joint, kind)` names the compressed channel animating a
/// joint's kind (translation, rotation, scale) in the lanes the plan marks animated.
fn decode_plan(plan: &[PlanBlock], channel_of: impl Fn(usize, usize) -> u32) -> Vec<DecodeBlock> {
    let mut out = Vec::new();
    for (p, pb) in plan.iter().enumerate() {
        for (kind, first) in [soa::T, soa::R, soa::S].into_iter().enumerate() {
            let lanes = pb.animated[kind] & pb.driven;
            if lanes != 0 {
                out.push(DecodeBlock {
                    first: (p * soa::COMPONENTS + first) as u32,
                    channel: [0, 1, 2, 3].map(|l| channel_of(pb.block * 4 + l, kind)),
                    lanes,
                    rotation: kind == 1,
                });
            }
        }
    }
    out
}

/// A block of a key slot loaded by transposition: lane `l`'s animated floats are contiguous in a frame
/// from `base[l]` (lanes of joints the clip does not drive borrow a driven lane's), and float `k` of
/// every lane goes to block component `components[k]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct GatherBlock {
    /// Vector index of the block's first component inside a slot.
    first: u32,
    base: [u32; 4],
    components: [u8; soa::COMPONENTS],
    floats: u8,
}

/// Splits `gather` into whole blocks that load by transposition and the remaining vectors.
fn gather_plan(plan: &[PlanBlock], gather: &[(u32, u32)]) -> (Vec<GatherBlock>, Vec<GatherVector>) {
    let per_block = (soa::COMPONENTS * 4) as u32;
    let mut moves: Vec<(u32, u32)> = gather.iter().map(|&(s, d)| (d, s)).collect();
    moves.sort_unstable();
    let mut blocks = Vec::new();
    let mut rest = Vec::new();
    let mut start = 0;
    while start < moves.len() {
        let pos = moves[start].0 / per_block;
        let end = start + moves[start..].partition_point(|&(d, _)| d / per_block == pos);
        let group = &moves[start..end];
        start = end;
        // Per lane: (component, source) in component order.
        let mut lanes: [Vec<(u8, u32)>; 4] = Default::default();
        for &(d, s) in group {
            let within = d % per_block;
            lanes[(within % 4) as usize].push(((within / 4) as u8, s));
        }
        let driven = plan.get(pos as usize).map_or(0, |pb| pb.driven);
        let reference = lanes.iter().find(|l| !l.is_empty());
        let whole = reference.is_some_and(|r| {
            (0..4).all(|l| {
                let lane = &lanes[l];
                let same = lane.len() == r.len()
                    && lane.iter().zip(r).all(|(a, b)| a.0 == b.0)
                    && lane.windows(2).all(|w| w[1].1 == w[0].1 + 1);
                same || (lane.is_empty() && driven & (1 << l) == 0)
            })
        });
        match reference {
            Some(r) if whole => {
                let mut components = [0u8; soa::COMPONENTS];
                for (k, &(c, _)) in r.iter().enumerate().take(soa::COMPONENTS) {
                    components[k] = c;
                }
                let base = [0, 1, 2, 3].map(|l| lanes[l].first().unwrap_or(&r[0]).1);
                blocks.push(GatherBlock {
                    first: pos * soa::COMPONENTS as u32,
                    base,
                    components,
                    floats: r.len().min(soa::COMPONENTS) as u8,
                });
            }
            _ => rest.extend(gather_vectors(
                &group.iter().map(|&(d, s)| (s, d)).collect::<Vec<_>>(),
            )),
        }
    }
    (blocks, rest)
}

/// One vector of a key slot that holds animated lanes: the frame offset of each lane (0 for lanes that
/// keep their fixed value) and which lanes are animated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct GatherVector {
    /// Vector index inside a slot.
    dst: u32,
    src: [u32; 4],
    lanes: u8,
}

/// Groups `(src, dst)` float moves by destination vector (four floats), in destination order.
fn gather_vectors(gather: &[(u32, u32)]) -> Vec<GatherVector> {
    let mut by_dst: Vec<GatherVector> = Vec::new();
    let mut moves: Vec<(u32, u32)> = gather.iter().map(|&(s, d)| (d, s)).collect();
    moves.sort_unstable();
    for (d, s) in moves {
        let (vector, lane) = (d / 4, (d % 4) as usize);
        match by_dst.last_mut() {
            Some(v) if v.dst == vector => {
                v.src[lane] = s;
                v.lanes |= 1 << lane;
            }
            _ => {
                let mut src = [0; 4];
                src[lane] = s;
                by_dst.push(GatherVector {
                    dst: vector,
                    src,
                    lanes: 1 << lane,
                });
            }
        }
    }
    by_dst
}

impl ClipBinding {
    /// Binds the clip's tracks to the skeleton's joints by exact name.
    pub fn new(clip: &Clip, skeleton: &Skeleton) -> ClipBinding {
        let mut joint_of_track = Vec::with_capacity(clip.tracks.len());
        let mut unmatched = Vec::new();
        let mut driven = Vec::new();
        // Per skeleton block: the block being built (None until a driven joint falls in it).
        let mut blocks: Vec<Option<PlanBlock>> = vec![None; soa::block_count(skeleton.len())];
        // (frame offset, joint, component within the block) before blocks get their plan positions.
        let mut gather: Vec<(usize, usize, usize)> = Vec::new();
        let identity = Transform::IDENTITY;
        // Per joint and kind: the compressed channel animating it.
        let mut channel_of = vec![[0u32; 3]; skeleton.len()];
        for t in &clip.tracks {
            let j = skeleton.find(&t.joint);
            joint_of_track.push(j);
            let Some(j) = j else {
                unmatched.push(t.joint.clone());
                continue;
            };
            driven.push(j);
            let ju = j as usize;
            let (b, lane) = (ju / 4, ju % 4);
            let Some(block) = blocks.get_mut(b) else {
                continue;
            };
            let pb = block.get_or_insert_with(|| PlanBlock {
                block: b,
                driven: 0,
                animated: [0; 3],
                source: [soa::Source::Fixed; 3],
                fixed: soa::from_transforms(&[identity; 4])
                    .try_into()
                    .unwrap_or([glam::Vec4::ZERO; soa::COMPONENTS]),
            });
            pb.driven |= 1 << lane;
            let bind = if clip.additive {
                identity
            } else {
                skeleton.bind_local().get(ju).copied().unwrap_or(identity)
            };
            let kinds: [(Option<u32>, [f32; 4], usize, usize); 3] = [
                (
                    animated(t.translation),
                    fixed3(t.translation, bind.translation),
                    soa::T,
                    3,
                ),
                (
                    animated(t.rotation),
                    match t.rotation {
                        Channel::Constant(q) => q.to_array(),
                        _ => bind.rotation.to_array(),
                    },
                    soa::R,
                    4,
                ),
                (animated(t.scale), fixed3(t.scale, bind.scale), soa::S, 3),
            ];
            for (kind, (anim, fixed, first, n)) in kinds.into_iter().enumerate() {
                for (c, &v) in fixed.iter().enumerate().take(n) {
                    pb.fixed[first + c][lane] = v;
                }
                if let Some(o) = anim {
                    pb.animated[kind] |= 1 << lane;
                    if let Some(c) = channel_of.get_mut(ju) {
                        c[kind] = o / 3;
                    }
                    let at = clip.frame_offset(o);
                    for c in 0..n {
                        gather.push((at.saturating_add(c), ju, first + c));
                    }
                }
            }
        }
        driven.sort_unstable();
        let mut position = vec![usize::MAX; blocks.len()];
        let mut plan = Vec::new();
        for (b, block) in blocks.into_iter().enumerate() {
            if let Some(mut pb) = block {
                pb.set_sources();
                position[b] = plan.len();
                plan.push(pb);
            }
        }
        let mut gather: Vec<(u32, u32)> = gather
            .into_iter()
            .filter_map(|(src, j, c)| {
                let pos = *position.get(j / 4)?;
                let dst = (pos * soa::COMPONENTS + c) * 4 + j % 4;
                Some((u32::try_from(src).ok()?, u32::try_from(dst).ok()?))
            })
            .collect();
        gather.sort_unstable();
        let (blocks, vectors, decode) = if clip.quantized.is_some() {
            let decode = decode_plan(&plan, |j, kind| channel_of.get(j).map_or(0, |c| c[kind]));
            (Vec::new(), Vec::new(), decode)
        } else {
            let (blocks, vectors) = gather_plan(&plan, &gather);
            (blocks, vectors, Vec::new())
        };
        ClipBinding {
            decode,
            joint_of_track,
            unmatched,
            driven,
            skeleton_len: skeleton.len(),
            frame_stride: clip.frame_stride(),
            blocks,
            vectors,
            plan,
            gather,
            id: Identity::new(),
        }
    }

    /// The same binding with every channel of the joints `keep` rejects left out: those joints are
    /// neither sampled nor listed in [`ClipBinding::driven`]. The [`crate::Animator`] samples a masked
    /// layer through such a binding (joints whose mask is zero), so a partial-body layer costs only the
    /// joints it reaches. Track-to-joint mapping and unmatched names are those of `self`.
    pub fn restricted(&self, mut keep: impl FnMut(JointIndex) -> bool) -> ClipBinding {
        let mut keep = |j: usize| keep(j as JointIndex);
        let identity = soa::from_transforms(&[Transform::IDENTITY]);
        let mut position = vec![usize::MAX; self.plan.len()];
        let mut plan = Vec::new();
        for (i, pb) in self.plan.iter().enumerate() {
            let mut pb = pb.clone();
            for lane in 0..4 {
                if pb.driven & (1 << lane) != 0 && !keep(pb.block * 4 + lane) {
                    pb.driven &= !(1 << lane);
                    for k in &mut pb.animated {
                        *k &= !(1 << lane);
                    }
                    // Lanes nobody reads still hold finite values (the identity).
                    for (c, v) in identity.iter().enumerate().take(soa::COMPONENTS) {
                        pb.fixed[c][lane] = v[0];
                    }
                }
            }
            if pb.driven != 0 {
                pb.set_sources();
                position[i] = plan.len();
                plan.push(pb);
            }
        }
        let block_floats = soa::COMPONENTS * 4;
        let gather: Vec<(u32, u32)> = self
            .gather
            .iter()
            .filter_map(|&(src, dst)| {
                let (old, within) = (dst as usize / block_floats, dst as usize % block_floats);
                let pos = *position.get(old)?;
                let pb = plan.get(pos)?;
                (pb.driven & (1 << (within % 4)) != 0)
                    .then(|| (src, (pos * block_floats + within) as u32))
            })
            .collect();
        let (blocks, vectors, decode) = if self.decode.is_empty() {
            let (blocks, vectors) = gather_plan(&plan, &gather);
            (blocks, vectors, Vec::new())
        } else {
            // The same channels, in the kept lanes of the kept blocks.
            let mut channel_of = vec![[0u32; 3]; self.skeleton_len];
            for d in &self.decode {
                let (p, c) = (
                    d.first as usize / soa::COMPONENTS,
                    d.first as usize % soa::COMPONENTS,
                );
                let kind = usize::from(c >= soa::R) + usize::from(c >= soa::S);
                let Some(pb) = self.plan.get(p) else { continue };
                for (l, &ch) in d.channel.iter().enumerate() {
                    if let Some(slot) = channel_of.get_mut(pb.block * 4 + l) {
                        slot[kind] = ch;
                    }
                }
            }
            let decode = decode_plan(&plan, |j, kind| channel_of.get(j).map_or(0, |c| c[kind]));
            (Vec::new(), Vec::new(), decode)
        };
        ClipBinding {
            decode,
            joint_of_track: self.joint_of_track.clone(),
            unmatched: self.unmatched.clone(),
            driven: self
                .driven
                .iter()
                .copied()
                .filter(|&j| keep(j as usize))
                .collect(),
            skeleton_len: self.skeleton_len,
            frame_stride: self.frame_stride,
            blocks,
            vectors,
            plan,
            gather,
            id: Identity::new(),
        }
    }

    /// The clip's track names that matched no joint.
    pub fn unmatched(&self) -> &[String] {
        &self.unmatched
    }
    /// The skeleton joints this clip drives, ascending.
    pub fn driven(&self) -> &[JointIndex] {
        &self.driven
    }
    /// For each track of the clip, the joint it drives.
    pub fn joint_of_track(&self) -> &[Option<JointIndex>] {
        &self.joint_of_track
    }
    /// The blocks of four joints this binding samples, ascending.
    pub(crate) fn plan(&self) -> &[PlanBlock] {
        &self.plan
    }
}

/// The fixed value of a translation or scale channel: its constant, or `bind` (padded to four).
fn fixed3(c: Channel<Vec3>, bind: Vec3) -> [f32; 4] {
    let v = match c {
        Channel::Constant(v) => v,
        _ => bind,
    };
    [v.x, v.y, v.z, 0.0]
}

/// Per-character sampling state: a cursor into a clip's key times so that playing forward never searches
/// from the first key, and the two most recently used keys laid out as the binding's blocks (made on
/// first use for a clip and binding and reused, so playing forward gathers or decodes a key only when
/// the cursor passes it).
#[derive(Debug, Clone, Default)]
pub struct Sampler {
    cursor: usize,
    cache: KeyCache,
}

/// Equality compares the cursor only: the key cache is a memo that never changes results.
impl PartialEq for Sampler {
    fn eq(&self, other: &Self) -> bool {
        self.cursor == other.cursor
    }
}
impl Eq for Sampler {}

/// Two keys of one clip, in one binding's block layout.
#[derive(Debug, Clone, Default)]
struct KeyCache {
    /// Identities of the clip and binding the slots belong to.
    owner: Option<(u64, u64)>,
    /// The key held by each slot (`usize::MAX` = empty).
    keys: [usize; 2],
    /// Two slots of `plan.len() * COMPONENTS` vectors: fixed values, animated lanes from the key.
    slots: Vec<glam::Vec4>,
    /// For a compressed clip: the segment whose decode tables `tables` holds (`usize::MAX` = none),
    /// and one table per [`DecodeBlock`] of the binding. Made when the cursor enters a segment.
    table_segment: usize,
    tables: Vec<LaneTable>,
}

impl KeyCache {
    /// The slots holding keys `k0` and `k1`, loading whichever is missing.
    #[inline(always)]
    fn slots(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        k0: usize,
        k1: usize,
    ) -> (usize, usize) {
        let len = binding.plan.len() * soa::COMPONENTS;
        let owner = Some((clip.id.0, binding.id.0));
        if self.owner != owner || self.slots.len() != 2 * len {
            self.owner = owner;
            self.keys = [usize::MAX; 2];
            self.table_segment = usize::MAX;
            self.slots.clear();
            for _ in 0..2 {
                for pb in &binding.plan {
                    self.slots.extend_from_slice(&pb.fixed);
                }
            }
        }
        let find = |k: usize| self.keys.iter().position(|&x| x == k);
        let (s0, s1) = match (find(k0), find(k1)) {
            (Some(a), Some(b)) => return (a, b),
            (Some(a), None) => (a, 1 - a),
            (None, Some(b)) => (1 - b, b),
            (None, None) => (0, if k0 == k1 { 0 } else { 1 }),
        };
        for (slot, k) in [(s0, k0), (s1, k1)] {
            if self.keys[slot] != k {
                self.load(clip, binding, k, slot * len);
                self.keys[slot] = k;
            }
        }
        (s0, s1)
    }

    /// Gathers key `k`'s animated components into the slot starting at vector `base`.
    #[inline(always)]
    fn load(&mut self, clip: &Clip, binding: &ClipBinding, k: usize, base: usize) {
        let frame: &[f32] = match &clip.quantized {
            None => {
                // The frame and the floats after it (the next frame or the padding): runs are read
                // four floats at a time.
                let s = clip.stride;
                clip.frames
                    .get(k * s..(k + 1) * s + FRAME_PAD)
                    .unwrap_or_default()
            }
            Some(q) => {
                // Decoded four lanes at a time straight into the slot.
                let Some((segment, bit)) = q.key_start(k) else {
                    return;
                };
                if self.table_segment != segment {
                    self.tables.clear();
                    self.tables.extend(
                        binding
                            .decode
                            .iter()
                            .map(|d| q.lane_table(segment, d.channel, d.lanes)),
                    );
                    self.table_segment = segment;
                }
                decode_key(q, bit, &binding.decode, &self.tables, &mut self.slots, base);
                return;
            }
        };
        // Whole vectors are built in registers and stored once (scalar stores into a vector that is
        // read right after would defeat store-to-load forwarding).
        let slots = &mut self.slots;
        let row = |i: usize| {
            frame
                .get(i..i + 4)
                .map_or(glam::Vec4::ZERO, glam::Vec4::from_slice)
        };
        for g in &binding.blocks {
            let first = base + g.first as usize;
            let Some(Ok(block)) = slots
                .get_mut(first..first + soa::COMPONENTS)
                .map(<&mut soa::Block>::try_from)
            else {
                continue;
            };
            let [b0, b1, b2, b3] = g.base.map(|b| b as usize);
            for k in (0..g.floats as usize).step_by(4) {
                // Four floats of each lane's run, transposed into one vector per component.
                let t = glam::Mat4::from_cols(row(b0 + k), row(b1 + k), row(b2 + k), row(b3 + k))
                    .transpose();
                for (i, v) in [t.x_axis, t.y_axis, t.z_axis, t.w_axis]
                    .into_iter()
                    .enumerate()
                {
                    if k + i < g.floats as usize {
                        if let Some(slot) = block.get_mut(g.components[k + i] as usize) {
                            *slot = v;
                        }
                    }
                }
            }
        }
        let f = |i: u32| frame.get(i as usize).copied().unwrap_or(0.0);
        for g in &binding.vectors {
            if let Some(slot) = slots.get_mut(base + g.dst as usize) {
                let v = glam::Vec4::new(f(g.src[0]), f(g.src[1]), f(g.src[2]), f(g.src[3]));
                *slot = if g.lanes == 0b1111 {
                    v
                } else {
                    glam::Vec4::select(soa::lanes(g.lanes), v, *slot)
                };
            }
        }
    }
}

crate::cpu::dispatch_avx2! {
    /// Decodes the compressed key record starting at `bit` into the key slot starting at vector
    /// `base`: each [`DecodeBlock`] with its table, four lanes at a time.
    fn decode_key(
        q: &Quantized,
        bit: usize,
        decode: &[DecodeBlock],
        tables: &[LaneTable],
        slots: &mut [glam::Vec4],
        base: usize,
    ) -> () => decode_key_portable, decode_key_avx2;
}

#[inline(always)]
fn decode_key_portable(
    q: &Quantized,
    bit: usize,
    decode: &[DecodeBlock],
    tables: &[LaneTable],
    slots: &mut [glam::Vec4],
    base: usize,
) {
    for (d, table) in decode.iter().zip(tables) {
        store_lanes(d, q.decode_lanes(bit, table, d.rotation), slots, base);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn decode_key_avx2(
    q: &Quantized,
    bit: usize,
    decode: &[DecodeBlock],
    tables: &[LaneTable],
    slots: &mut [glam::Vec4],
    base: usize,
) {
    for (d, table) in decode.iter().zip(tables) {
        let values = if table.one_load {
            q.decode_lanes_avx2(bit, table, d.rotation)
        } else {
            q.decode_lanes(bit, table, d.rotation)
        };
        store_lanes(d, values, slots, base);
    }
}

/// Stores a [`DecodeBlock`]'s decoded values in its animated lanes of the slot at vector `base`.
#[inline(always)]
fn store_lanes(d: &DecodeBlock, values: [glam::Vec4; 4], slots: &mut [glam::Vec4], base: usize) {
    let first = base + d.first as usize;
    let n = if d.rotation { 4 } else { 3 };
    if let Some(dst) = slots.get_mut(first..first + n) {
        let keep = soa::lanes(d.lanes);
        for (o, v) in dst.iter_mut().zip(values) {
            *o = glam::Vec4::select(keep, v, *o);
        }
    }
}

impl Sampler {
    /// A sampler at the first key.
    pub fn new() -> Self {
        Self::default()
    }

    /// Finds the key pair around `t` (already mapped by [`Clip::local_time`]) and the blend factor.
    /// Returns `(k0, k1, alpha)`; `alpha == 0` means frame `k0` exactly.
    #[inline]
    pub fn locate(&mut self, clip: &Clip, t: f32) -> (usize, usize, f32) {
        let times = &clip.times;
        let n = times.len();
        if n <= 1 || t <= times[0] {
            self.cursor = 0;
            if clip.looping && n > 1 && t < times[0] {
                // Before the first key of a looping clip: coming from the last frame around the wrap.
                let span = times[0] + (clip.duration - times[n - 1]);
                if span > 0.0 {
                    let a = (t + clip.duration - times[n - 1]) / span;
                    return (n - 1, 0, a.clamp(0.0, 1.0));
                }
            }
            return (0, 0, 0.0);
        }
        let mut c = self.cursor.min(n - 1);
        if times[c] > t {
            c = times.partition_point(|&x| x <= t) - 1;
        } else {
            let mut steps = 0;
            while c + 1 < n && times[c + 1] <= t {
                c += 1;
                steps += 1;
                if steps == 8 {
                    c = times.partition_point(|&x| x <= t) - 1;
                    break;
                }
            }
        }
        self.cursor = c;
        if c + 1 >= n {
            if clip.looping {
                let span = clip.duration - times[c] + times[0];
                if span > 0.0 {
                    return (c, 0, ((t - times[c]) / span).clamp(0.0, 1.0));
                }
            }
            return (c, c, 0.0);
        }
        let a = (t - times[c]) / (times[c + 1] - times[c]);
        (c, c + 1, a)
    }

    /// Samples the clip at playback time `t` into `out` (one transform per skeleton joint), writing only
    /// the joints the clip drives. Missing channels take the joint's bind value; for an additive clip they
    /// take the identity difference. Rotations are normalised ([`nlerp`] between keys).
    pub fn sample(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        skeleton: &Skeleton,
        t: f32,
        out: &mut [Transform],
    ) -> Result<(), ClipError> {
        self.sample_transforms(clip, binding, skeleton, t, soa::Rotations::Normalized, out)
    }

    /// [`Sampler::sample`] for a normal layer of a blend: the same translations and scales, and
    /// rotations as interpolated, the shortest-path weighted sum of the two keys (a key as stored),
    /// not normalised, because the blend normalises the sum of its layers once (see [`crate::blend`]).
    /// This is what the [`crate::Animator`] blends, so [`crate::BlendBuffers`] fed with it gives the
    /// animator's pose bit for bit.
    pub fn sample_layer(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        skeleton: &Skeleton,
        t: f32,
        out: &mut [Transform],
    ) -> Result<(), ClipError> {
        self.sample_transforms(
            clip,
            binding,
            skeleton,
            t,
            soa::Rotations::Interpolated,
            out,
        )
    }

    fn sample_transforms(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        skeleton: &Skeleton,
        t: f32,
        rotations: soa::Rotations,
        out: &mut [Transform],
    ) -> Result<(), ClipError> {
        if out.len() != skeleton.len() {
            return Err(ClipError::OutputLength {
                expected: skeleton.len(),
                got: out.len(),
            });
        }
        if binding.skeleton_len != skeleton.len() {
            return Err(ClipError::BindingMismatch);
        }
        self.sample_each(clip, binding, t, rotations, |pb, block| {
            soa::write_transforms(
                block,
                pb.driven,
                out.get_mut(pb.block * 4..).unwrap_or_default(),
            );
        })
    }

    /// Samples the clip at playback time `t` into `out`, one block of [`soa::COMPONENTS`] vectors per
    /// block of the binding's plan (`out` is resized to that). Lanes of joints the clip does not drive
    /// hold unspecified finite values.
    #[inline(always)]
    pub(crate) fn sample_blocks(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        t: f32,
        out: &mut Vec<glam::Vec4>,
    ) -> Result<(), ClipError> {
        let len = binding.plan.len() * soa::COMPONENTS;
        if out.len() != len {
            out.resize(len, glam::Vec4::ZERO);
        }
        let mut blocks = out.chunks_exact_mut(soa::COMPONENTS);
        self.sample_each(clip, binding, t, soa::Rotations::Normalized, |_, block| {
            if let Some(o) = blocks.next() {
                o.copy_from_slice(block);
            }
        })
    }

    /// Samples the clip at playback time `t` block by block, handing each block of the binding's plan
    /// to `f` as it is made (in plan order). Lanes of joints the clip does not drive hold unspecified
    /// finite values.
    #[inline(always)]
    pub(crate) fn sample_each(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        t: f32,
        rotations: soa::Rotations,
        mut f: impl FnMut(&PlanBlock, &soa::Block),
    ) -> Result<(), ClipError> {
        if binding.joint_of_track.len() != clip.tracks.len()
            || binding.frame_stride != clip.frame_stride()
        {
            return Err(ClipError::BindingMismatch);
        }
        let len = binding.plan.len() * soa::COMPONENTS;
        let t = clip.local_time(t);
        let (k0, k1, a) = self.locate(clip, t);
        let (s0, s1) = self.cache.slots(clip, binding, k0, k1);
        let slots = &self.cache.slots;
        let (c0, c1) = (
            slots.get(s0 * len..(s0 + 1) * len).unwrap_or_default(),
            slots.get(s1 * len..(s1 + 1) * len).unwrap_or_default(),
        );
        let raw = clip.quantized.is_some();
        let blocks = c0
            .chunks_exact(soa::COMPONENTS)
            .zip(c1.chunks_exact(soa::COMPONENTS));
        let mut block = [glam::Vec4::ZERO; soa::COMPONENTS];
        for (pb, (b0, b1)) in binding.plan.iter().zip(blocks) {
            if let (Ok(b0), Ok(b1)) = (<&soa::Block>::try_from(b0), <&soa::Block>::try_from(b1)) {
                soa::sample_block(pb, b0, b1, a, raw, rotations, &mut block);
                f(pb, &block);
            }
        }
        Ok(())
    }
}

fn animated<T>(c: Channel<T>) -> Option<u32> {
    match c {
        Channel::Animated(o) => Some(o),
        _ => None,
    }
}

fn plain_only<T>(c: Channel<T>) -> Channel<T> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compressed::SegmentComponent;
    use crate::skeleton::JointDesc;

    fn skeleton() -> Skeleton {
        Skeleton::from_unordered(vec![
            JointDesc {
                name: "root".into(),
                parent: None,
                bind_local: Transform::from_translation(Vec3::new(0.0, 1.0, 0.0)),
                inverse_bind: None,
            },
            JointDesc {
                name: "arm".into(),
                parent: Some("root".into()),
                bind_local: Transform::from_translation(Vec3::new(1.0, 0.0, 0.0)),
                inverse_bind: None,
            },
        ])
        .unwrap()
        .0
    }

    fn walk(looping: bool) -> Clip {
        // Root x goes 0, 1, 4 at times 0, 0.5, 1.0; the arm rotates 0 -> 90 degrees about z.
        let duration = if looping { 1.5 } else { 1.0 };
        Clip::from_curves(
            "walk",
            duration,
            2.0,
            looping,
            false,
            vec![
                TrackCurves {
                    joint: "root".into(),
                    translation: Curve::new(
                        vec![0.0, 0.5, 1.0],
                        vec![Vec3::ZERO, Vec3::X, Vec3::X * 4.0],
                    ),
                    ..Default::default()
                },
                TrackCurves {
                    joint: "arm".into(),
                    rotation: Curve::new(
                        vec![0.0, 1.0],
                        vec![
                            Quat::IDENTITY,
                            Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
                        ],
                    ),
                    scale: Curve::new(vec![0.0], vec![Vec3::splat(2.0)]),
                    ..Default::default()
                },
                TrackCurves {
                    joint: "tail".into(),
                    translation: Curve::new(vec![0.0], vec![Vec3::ONE]),
                    ..Default::default()
                },
            ],
        )
        .unwrap()
    }

    fn sample(clip: &Clip, t: f32) -> Vec<Transform> {
        let s = skeleton();
        let b = ClipBinding::new(clip, &s);
        let mut out = vec![Transform::IDENTITY; s.len()];
        Sampler::new().sample(clip, &b, &s, t, &mut out).unwrap();
        out
    }

    #[test]
    fn layout_is_union_of_key_times_and_constants_stored_once() {
        let c = walk(false);
        assert_eq!(c.times(), [0.0, 0.5, 1.0]);
        // root translation (3) + arm rotation (4); the arm's scale is a constant.
        assert_eq!(c.stride(), 7);
        assert_eq!(c.tracks()[1].scale, Channel::Constant(Vec3::splat(2.0)));
        assert_eq!(c.tracks()[0].rotation, Channel::Bind);
        // The arm rotation at 0.5 (not one of its keys) was filled in by interpolation: 45 degrees.
        let q = Quat::from_slice(&c.frames()[7 + 3..7 + 7]);
        assert!(q.angle_between(Quat::from_rotation_z(std::f32::consts::FRAC_PI_4)) < 1e-5);
    }

    #[test]
    fn samples_exact_at_keys_and_linear_between() {
        let c = walk(false);
        assert_eq!(sample(&c, 0.5)[0].translation, Vec3::X);
        assert_eq!(sample(&c, 1.0)[0].translation, Vec3::X * 4.0);
        let mid = sample(&c, 0.75)[0].translation;
        assert!((mid - Vec3::X * 2.5).length() < 1e-6);
        // Bind value fills the root's rotation and scale; the arm keeps its bind translation.
        let p = sample(&c, 0.25);
        assert_eq!(p[0].rotation, Quat::IDENTITY);
        assert_eq!(p[1].translation, Vec3::X);
        assert_eq!(p[1].scale, Vec3::splat(2.0));
    }

    #[test]
    fn non_looping_clamps_before_zero_and_after_end() {
        let c = walk(false);
        assert_eq!(sample(&c, -3.0)[0].translation, Vec3::ZERO);
        assert_eq!(sample(&c, 7.0)[0].translation, Vec3::X * 4.0);
    }

    #[test]
    fn looping_wraps_and_interpolates_back_to_first_frame() {
        let c = walk(true);
        // Duration 1.5: from the last key (1.0, x=4) back to frame 0 (x=0) at 1.5.
        let p = sample(&c, 1.25)[0].translation;
        assert!((p - Vec3::X * 2.0).length() < 1e-6, "{p}");
        // 2.0 wraps to 0.5.
        assert_eq!(sample(&c, 2.0)[0].translation, Vec3::X);
        // -0.25 wraps to 1.25.
        let n = sample(&c, -0.25)[0].translation;
        assert!((n - Vec3::X * 2.0).length() < 1e-6, "{n}");
    }

    #[test]
    fn binding_lists_unmatched_names_and_leaves_other_joints_alone() {
        let c = walk(false);
        let s = skeleton();
        let b = ClipBinding::new(&c, &s);
        assert_eq!(b.unmatched(), ["tail"]);
        assert_eq!(b.driven(), [0, 1]);
        let partial = Clip::from_curves(
            "arm only",
            1.0,
            1.0,
            false,
            false,
            vec![TrackCurves {
                joint: "arm".into(),
                translation: Curve::new(vec![0.0], vec![Vec3::Y]),
                ..Default::default()
            }],
        )
        .unwrap();
        let b = ClipBinding::new(&partial, &s);
        let marker = Transform::from_translation(Vec3::splat(9.0));
        let mut out = vec![marker; 2];
        Sampler::new()
            .sample(&partial, &b, &s, 0.3, &mut out)
            .unwrap();
        assert_eq!(out[0], marker);
        assert_eq!(out[1].translation, Vec3::Y);
    }

    #[test]
    fn cursor_moves_forward_and_recovers_on_jumps_back() {
        let c = walk(false);
        let mut s = Sampler::new();
        assert_eq!(s.locate(&c, 0.1).0, 0);
        assert_eq!(s.locate(&c, 0.6).0, 1);
        assert_eq!(s.cursor, 1);
        assert_eq!(s.locate(&c, 0.2).0, 0);
        assert_eq!(s.locate(&c, 1.0), (2, 2, 0.0));
    }

    #[test]
    fn rejects_bad_curves() {
        let bad = |curve: Curve<Vec3>| {
            Clip::from_curves(
                "x",
                1.0,
                1.0,
                false,
                false,
                vec![TrackCurves {
                    joint: "a".into(),
                    translation: curve,
                    ..Default::default()
                }],
            )
        };
        assert!(matches!(
            bad(Curve::new(vec![0.0, 0.0], vec![Vec3::ZERO, Vec3::X])),
            Err(ClipError::BadTimes(_))
        ));
        assert!(matches!(
            bad(Curve::new(vec![0.0], vec![Vec3::NAN])),
            Err(ClipError::NonFinite(_))
        ));
        assert!(matches!(
            bad(Curve::new(vec![0.0, 2.0], vec![Vec3::ZERO, Vec3::X])),
            Err(ClipError::BadDuration(_))
        ));
        assert!(matches!(
            bad(Curve::new(vec![0.0], vec![])),
            Err(ClipError::LengthMismatch(_))
        ));
    }

    /// The sampler as it was before the work lists and the key cache, kept as the reference the new
    /// loops must match bit for bit.
    fn reference(clip: &Clip, b: &ClipBinding, sk: &Skeleton, t: f32, out: &mut [Transform]) {
        let t = clip.local_time(t);
        let (k0, k1, a) = Sampler::new().locate(clip, t);
        let bind = sk.bind_local();
        let lerp3 = |f0: &[f32], f1: &[f32], o: usize| {
            let v0 = Vec3::new(f0[o], f0[o + 1], f0[o + 2]);
            if a == 0.0 {
                v0
            } else {
                v0.lerp(Vec3::new(f1[o], f1[o + 1], f1[o + 2]), a)
            }
        };
        for (track, joint) in clip.tracks.iter().zip(&b.joint_of_track) {
            let Some(j) = *joint else { continue };
            let j = j as usize;
            let d = if clip.additive {
                Transform::IDENTITY
            } else {
                bind[j]
            };
            if let Some(q) = &clip.quantized {
                let (f0, f1) = (q.key(k0), q.key(k1));
                let v = |c: Channel<Vec3>, d: Vec3| match c {
                    Channel::Bind => d,
                    Channel::Constant(v) => v,
                    Channel::Animated(o) if a == 0.0 => f0.vec3(o as usize),
                    Channel::Animated(o) => f0.vec3(o as usize).lerp(f1.vec3(o as usize), a),
                };
                out[j] = Transform {
                    translation: v(track.translation, d.translation),
                    rotation: match track.rotation {
                        Channel::Bind => d.rotation,
                        Channel::Constant(r) => r,
                        Channel::Animated(o) if a == 0.0 => {
                            normalize_rotation(f0.quat_raw(o as usize))
                        }
                        Channel::Animated(o) => {
                            nlerp(f0.quat_raw(o as usize), f1.quat_raw(o as usize), a)
                        }
                    },
                    scale: v(track.scale, d.scale),
                };
                continue;
            }
            let s = clip.stride;
            let (f0, f1) = (
                &clip.frames[k0 * s..(k0 + 1) * s],
                &clip.frames[k1 * s..(k1 + 1) * s],
            );
            let v = |c: Channel<Vec3>, d: Vec3| match c {
                Channel::Bind => d,
                Channel::Constant(v) => v,
                Channel::Animated(o) => lerp3(f0, f1, o as usize),
            };
            out[j] = Transform {
                translation: v(track.translation, d.translation),
                rotation: match track.rotation {
                    Channel::Bind => d.rotation,
                    Channel::Constant(r) => r,
                    Channel::Animated(o) => {
                        let o = o as usize;
                        let q0 = Quat::from_slice(&f0[o..o + 4]);
                        if a == 0.0 {
                            q0
                        } else {
                            nlerp(q0, Quat::from_slice(&f1[o..o + 4]), a)
                        }
                    }
                },
                scale: v(track.scale, d.scale),
            };
        }
    }

    fn bits(p: &[Transform]) -> Vec<u32> {
        p.iter()
            .flat_map(|t| {
                let mut v = t.translation.to_array().to_vec();
                v.extend(t.rotation.to_array());
                v.extend(t.scale.to_array());
                v
            })
            .map(f32::to_bits)
            .collect()
    }

    /// A compressed clip built by hand: root translation (3 components), arm rotation (3) and arm scale
    /// (3), 5 keys in segments of 2, pseudo-random quantized values.
    fn compressed(looping: bool, additive: bool) -> Clip {
        compressed_with(compressed_tracks(), looping, additive, &[0, 3, 7, 12, 16])
    }

    /// Both joints animate translation and rotation (and scale with `scale`): every block of the key
    /// slots loads by transposition.
    fn compressed_uniform(scale: bool, bits: &[u8]) -> Clip {
        let per = if scale { 9 } else { 6 };
        let tracks = ["root", "arm"]
            .iter()
            .enumerate()
            .map(|(i, n)| Track {
                joint: (*n).into(),
                translation: Channel::Animated((i * per) as u32),
                rotation: Channel::Animated((i * per + 3) as u32),
                scale: if scale {
                    Channel::Animated((i * per + 6) as u32)
                } else {
                    Channel::Bind
                },
            })
            .collect();
        compressed_with(tracks, true, false, bits)
    }

    fn compressed_tracks() -> Vec<Track> {
        vec![
            Track {
                joint: "root".into(),
                translation: Channel::Animated(0),
                rotation: Channel::Constant(Quat::from_rotation_y(0.3)),
                scale: Channel::Bind,
            },
            Track {
                joint: "arm".into(),
                translation: Channel::Bind,
                rotation: Channel::Animated(3),
                scale: Channel::Animated(6),
            },
            Track {
                joint: "tail".into(),
                translation: Channel::Animated(9),
                rotation: Channel::Bind,
                scale: Channel::Bind,
            },
        ]
    }

    /// A compressed clip built by hand over `tracks`: 5 keys in segments of 2, bit widths cycling
    /// through `bits`, pseudo-random quantized values and rotation indices.
    fn compressed_with(tracks: Vec<Track>, looping: bool, additive: bool, bits: &[u8]) -> Clip {
        let starts = rotation_starts(&tracks).unwrap();
        let keys = 5;
        let comps = starts.len();
        let rotations = starts.iter().filter(|&&r| r).count();
        let segs: Vec<SegmentComponent> = (0..3 * comps)
            .map(|i| SegmentComponent {
                bits: bits[i % bits.len()],
                min: (i * 13 % 40) as u8,
                extent: 200,
            })
            .collect();
        let mut x = 0x9e37_79b9u32;
        let mut q = Vec::new();
        for k in 0..keys {
            for c in 0..comps {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                let bits = segs[(k / 2) * comps + c].bits;
                q.push(if bits == 0 { 0 } else { x % (1 << bits) });
            }
        }
        let index: Vec<u8> = (0..keys * rotations)
            .map(|i| [0u8, 3, 1, 2, 3][i % 5])
            .collect();
        let data = crate::compressed::pack(keys, 2, &segs, &starts, &q, &index);
        let mut ranges = vec![[-0.5f32, 1.0]; comps];
        ranges[0] = [-3.0, 7.5];
        Clip::from_quantized(
            "c".into(),
            if looping { 1.25 } else { 1.0 },
            4.0,
            looping,
            additive,
            vec![0.0, 0.25, 0.5, 0.75, 1.0],
            tracks,
            QuantizedParts {
                segment_len: 2,
                ranges,
                segments: segs,
                data,
            },
        )
        .unwrap()
    }

    #[test]
    fn work_lists_and_key_cache_match_the_reference_bit_for_bit() {
        let sk = skeleton();
        let mut clips = vec![walk(false), walk(true)];
        // Both joints animate translation and rotation (one block loads by transposition), in either
        // track order, so that each joint's run ends the frame once; and with scale too.
        for names in [["root", "arm"], ["arm", "root"]] {
            for with_scale in [false, true] {
                let times = vec![0.0, 0.3, 0.45, 1.0];
                let tracks = names
                    .iter()
                    .enumerate()
                    .map(|(i, n)| {
                        let f = i as f32 + 1.0;
                        let scale = if with_scale {
                            Curve::new(
                                times.clone(),
                                times.iter().map(|&t| Vec3::splat(1.0 + t * f)).collect(),
                            )
                        } else {
                            Curve::default()
                        };
                        TrackCurves {
                            joint: (*n).into(),
                            translation: Curve::new(
                                times.clone(),
                                times.iter().map(|&t| Vec3::new(t, -f * t, 2.0)).collect(),
                            ),
                            rotation: Curve::new(
                                times.clone(),
                                times
                                    .iter()
                                    .map(|&t| Quat::from_rotation_y(t * f * 2.0))
                                    .collect(),
                            ),
                            scale,
                        }
                    })
                    .collect();
                clips.push(Clip::from_curves("uniform", 1.0, 4.0, true, false, tracks).unwrap());
            }
        }
        for (l, a) in [(false, false), (true, false), (false, true)] {
            let c = compressed(l, a);
            clips.push(c.to_plain());
            clips.push(c);
        }
        // Uniform channels (whole blocks by transposition); the last with channels too wide for
        // one 8-byte read.
        for (scale, bits) in [
            (false, &[0u8, 3, 7, 12, 16][..]),
            (true, &[5, 9, 14][..]),
            (true, &[24, 23, 24, 1][..]),
        ] {
            let c = compressed_uniform(scale, bits);
            clips.push(c.to_plain());
            clips.push(c);
        }
        // Forward at 60 Hz past the end, keys exactly, backwards, jumps and negative times.
        let mut times: Vec<f32> = (0..100).map(|i| i as f32 / 60.0).collect();
        times.extend([
            0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 0.9, 0.1, -0.3, 2.6, 0.5, 0.5, 7.0,
        ]);
        times.extend((0..40).map(|i| 1.5 - i as f32 / 30.0));
        for clip in &clips {
            let b = ClipBinding::new(clip, &sk);
            let mut sampler = Sampler::new();
            for &t in &times {
                let marker = Transform::from_translation(Vec3::splat(9.0));
                let mut got = vec![marker; sk.len()];
                let mut want = vec![marker; sk.len()];
                sampler.sample(clip, &b, &sk, t, &mut got).unwrap();
                reference(clip, &b, &sk, t, &mut want);
                assert_eq!(bits(&got), bits(&want), "{} at {t}", clip.name());
            }
        }
        // At a key time the stored value comes back exactly (compressed: the decoded key, normalised).
        let c = compressed(false, false);
        let q = c.quantized.as_deref().unwrap();
        let mut out = vec![Transform::IDENTITY; sk.len()];
        Sampler::new()
            .sample(&c, &ClipBinding::new(&c, &sk), &sk, 0.5, &mut out)
            .unwrap();
        assert_eq!(out[0].translation, q.key(2).vec3(0));
        assert_eq!(out[1].rotation, q.key(2).quat(3));
        assert_eq!(out[1].scale, q.key(2).vec3(6));
    }

    #[test]
    fn compressed_keys_decode_to_the_same_bits_four_lanes_at_a_time_on_every_instruction_set() {
        // Ten joints in a chain (blocks of four: full, full, half), nine of them driven; one without
        // an animated rotation and two with scale, so blocks have full, partial and mixed lanes.
        let joints = (0..10)
            .map(|i| JointDesc {
                name: format!("j{i}"),
                parent: (i > 0).then(|| format!("j{}", i - 1)),
                bind_local: Transform::from_translation(Vec3::new(0.0, 1.0, i as f32 * 0.1)),
                inverse_bind: None,
            })
            .collect();
        let sk = Skeleton::from_unordered(joints).unwrap().0;
        let mut next = 0u32;
        let mut take = || {
            next += 3;
            next - 3
        };
        let tracks: Vec<Track> = (0..9)
            .map(|i| Track {
                joint: format!("j{i}"),
                translation: Channel::Animated(take()),
                rotation: if i == 5 {
                    Channel::Bind
                } else {
                    Channel::Animated(take())
                },
                scale: if i == 2 || i == 7 {
                    Channel::Animated(take())
                } else {
                    Channel::Bind
                },
            })
            .collect();
        // Narrow widths (one 8-byte read per lane) and, in some segments, channels too wide for one.
        let mut one_load_seen = [false; 2];
        for widths in [&[0u8, 3, 7, 12, 16, 1][..], &[24, 5, 23, 24, 9, 24, 2][..]] {
            let clip = compressed_with(tracks.clone(), true, false, widths);
            let b = ClipBinding::new(&clip, &sk);
            assert_eq!(
                b.decode.iter().map(|d| d.lanes.count_ones()).sum::<u32>(),
                9 + 8 + 2
            );
            let (mut fast, mut portable) = (Sampler::new(), Sampler::new());
            for i in 0..90 {
                let t = i as f32 / 60.0;
                let marker = Transform::from_translation(Vec3::splat(9.0));
                let mut want = vec![marker; sk.len()];
                reference(&clip, &b, &sk, t, &mut want);
                let mut got = vec![marker; sk.len()];
                fast.sample(&clip, &b, &sk, t, &mut got).unwrap();
                assert_eq!(bits(&got), bits(&want), "{t}");
                let mut got = vec![marker; sk.len()];
                crate::cpu::baseline(|| portable.sample(&clip, &b, &sk, t, &mut got)).unwrap();
                assert_eq!(bits(&got), bits(&want), "portable {t}");
                for table in &fast.cache.tables {
                    one_load_seen[usize::from(table.one_load)] = true;
                }
            }
        }
        assert_eq!(one_load_seen, [true, true]);
    }

    #[test]
    fn a_restricted_binding_decodes_only_its_channels_and_samples_the_same_values() {
        let sk = skeleton();
        for c in [
            compressed(false, false),
            compressed(true, false),
            compressed(false, true),
        ] {
            let full = ClipBinding::new(&c, &sk);
            for keep in [0u16, 1] {
                let part = full.restricted(|j| j == keep);
                let lanes = |b: &ClipBinding| -> u32 {
                    b.decode.iter().map(|d| d.lanes.count_ones()).sum()
                };
                assert!(lanes(&part) < lanes(&full));
                let (mut a, mut b) = (Sampler::new(), Sampler::new());
                for i in 0..40 {
                    let t = i as f32 * 0.037;
                    let marker = Transform::from_translation(Vec3::splat(9.0));
                    let mut want = vec![marker; sk.len()];
                    let mut got = vec![marker; sk.len()];
                    a.sample(&c, &full, &sk, t, &mut want).unwrap();
                    b.sample(&c, &part, &sk, t, &mut got).unwrap();
                    let j = keep as usize;
                    assert_eq!(bits(&got[j..j + 1]), bits(&want[j..j + 1]), "{t}");
                    // The other joint is not written.
                    assert_eq!(got[1 - j], marker);
                }
            }
        }
    }

    #[test]
    fn key_cache_decodes_only_when_the_cursor_passes_a_key() {
        let c = compressed(false, false);
        let sk = skeleton();
        let b = ClipBinding::new(&c, &sk);
        let mut out = vec![Transform::IDENTITY; sk.len()];
        let mut s = Sampler::new();
        s.sample(&c, &b, &sk, 0.1, &mut out).unwrap();
        assert_eq!(s.cache.keys, [0, 1]);
        s.sample(&c, &b, &sk, 0.3, &mut out).unwrap();
        // Key 1 stays in its slot; key 2 replaces key 0.
        assert_eq!(s.cache.keys, [2, 1]);
        assert_eq!(s.cache.owner, Some((c.id.0, b.id.0)));
        // Another clip (same layout, new payload) invalidates the cache.
        let other = compressed(false, false);
        let ob = ClipBinding::new(&other, &sk);
        s.sample(&other, &ob, &sk, 0.3, &mut out).unwrap();
        assert_eq!(s.cache.owner, Some((other.id.0, ob.id.0)));
        assert_ne!(other.id.0, c.id.0);
        assert_eq!(s.cache.keys, [1, 2]);
        // So does another binding of the same clip (a restricted one has its own plan).
        let half = b.restricted(|j| j == 0);
        s.sample(&c, &half, &sk, 0.3, &mut out).unwrap();
        assert_eq!(s.cache.owner, Some((c.id.0, half.id.0)));
    }
}
