//! Error-bounded keyframe compression of clips (the encoder of [`sinew_core::compressed`]) and the
//! error metric it is bounded by.
//!
//! # The error metric
//!
//! For every joint and every key time of the source clip, three points are attached rigidly to the
//! joint, one along each of its local axes, `error_distance` model units away from it in the bind pose.
//! Each point is carried to model space through the whole chain of parents, once with the source
//! clip and once with the compressed clip; the error of that joint at that time is the largest of the
//! three distances. Joints a clip does not drive take their bind values (so they move with their
//! parents). Without a skeleton every track is a root of its own.
//!
//! # What the encoder does, in order
//!
//! 1. Channels that one value (their middle value, or the bind value when a skeleton is given and the
//!    clip is not additive; the identity difference for additive clips) reproduces within a quarter of
//!    the tolerance are stored as constants or not at all.
//! 2. Keys that linear interpolation between their neighbours reproduces are dropped (whole keys, so
//!    the runtime still reads one record per key: time-major), once for each key budget of
//!    `KEY_BUDGETS` (fractions of the tolerance; the rest is left to quantization).
//! 3. Every remaining animated channel is quantized: rotations as three components plus the 2-bit
//!    index of the dropped one (the same index from key to key while that component stays large, so
//!    the stored components do not jump), translations and scales as three components; each
//!    component is range-reduced over the clip and over segments of keys. Rotations are quantized
//!    with *chain compensation*: parents first, each joint storing the local rotation that, under its
//!    parent's quantized rotation, gives its source model-space rotation, so orientation errors do not
//!    accumulate down the chain (when every scale of the source poses is positive and uniform, so that
//!    model-space rotations are products of local ones; otherwise, or if nothing meets the limits
//!    with it, without compensation).
//! 4. Bit widths, per component and segment: first the largest uniform error budget whose a-priori
//!    widths measure within the limits, then one bit at a time off each component of each segment
//!    for as long as the measured error (kept up to date incrementally) stays within the limits.
//! 5. Steps 3 and 4 run for every set of kept keys from step 2 and several segment lengths (16, 32,
//!    and for short clips 64 and lengths that split the clip into 1 to 4 equal segments); the few
//!    smallest after the first widths get step 4's refinement, and the smallest result that the
//!    runtime sampler measures within the limits is kept.
//!
//! The limits are per joint: the tolerance less a margin for f32 noise (a few ulps of the joint's
//! model-space coordinates), so that an independent measurement against the source data also stays
//! within the tolerance on models far from the origin.
//!
//! Key times are kept as the source has them (no resampling), so every source key is honoured in time.

use sinew_core::clip::{nlerp, normalize_rotation};
use sinew_core::compressed::{
    dequant_params, pack, smallest_three, three_without, QuantizedParts, SegmentComponent, MAX_BITS,
};
use sinew_core::format::clip_record_size;
use sinew_core::glam::{Affine3A, Quat, Vec3};
use sinew_core::skeleton::inverse_bind_from_locals;
use sinew_core::{Channel, Clip, ClipBinding, Sampler, Skeleton, Track, Transform};

/// Default tolerance as a fraction of the skeleton's extent (its bind-pose bounding-box diagonal):
/// 0.0005, so 0.001 units on a 2-unit figure, 0.036 on a 72-unit Half-Life model.
pub const DEFAULT_RELATIVE_TOLERANCE: f32 = 0.0005;
/// Default error distance as a fraction of the skeleton's extent: 0.05 (0.1 units on a 2-unit figure).
pub const DEFAULT_RELATIVE_DISTANCE: f32 = 0.05;
/// How many of the candidate layouts (smallest first, with their first bit widths) are refined.
const DESCENDED: usize = 4;
/// Clips with more source keys x joints than this refine only their best candidate layout (the
/// refinement's cost grows with both).
const LARGE_CLIP: usize = 20_000;
/// Clips with more kept keys than this try only segments of 16 and 32 keys.
const SHORT_CLIP: usize = 256;
/// Key-reduction budgets tried for each clip, as fractions of the tolerance (the rest is left to
/// quantization); the smallest result is kept.
const KEY_BUDGETS: [f32; 4] = [0.3, 0.5, 0.7, 0.85];

/// Options of [`compress_clip`].
#[derive(Debug, Clone, PartialEq)]
pub struct CompressOptions {
    /// Largest allowed error, model units. `None`: [`DEFAULT_RELATIVE_TOLERANCE`] x the extent.
    pub tolerance: Option<f32>,
    /// Distance of the error points from their joint, model units. `None`:
    /// [`DEFAULT_RELATIVE_DISTANCE`] x the extent.
    pub error_distance: Option<f32>,
    /// Drop keys that interpolation reproduces (step 2 of the module docs).
    pub key_reduction: bool,
}

impl Default for CompressOptions {
    fn default() -> Self {
        Self {
            tolerance: None,
            error_distance: None,
            key_reduction: true,
        }
    }
}

impl CompressOptions {
    /// The peers' settings (ozz-animation, ACL): 0.001 units at 0.1 units.
    pub fn peers() -> Self {
        Self {
            tolerance: Some(0.001),
            error_distance: Some(0.1),
            key_reduction: true,
        }
    }
}

/// What compressing one clip reached.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClipCompressionReport {
    /// Clip name.
    pub clip: String,
    /// Raw size: 40 bytes (10 f32: translation 3, rotation 4, scale 3) per animated joint per source key.
    pub raw_bytes: usize,
    /// Size of the plain (f32) clip record in the `.sinew` file.
    pub plain_bytes: usize,
    /// Size of the compressed clip record in the `.sinew` file (joint names excluded: string table).
    pub compressed_bytes: usize,
    /// `raw_bytes / compressed_bytes`.
    pub ratio: f32,
    /// Largest measured error over all joints and source key times, model units.
    pub max_error: f32,
    /// 99th percentile of the same errors.
    pub p99_error: f32,
    /// Tolerance used, model units.
    pub tolerance: f32,
    /// Error distance used, model units.
    pub error_distance: f32,
    /// Tracks with at least one animated channel in the source.
    pub animated_joints: usize,
    /// Source key count.
    pub samples: usize,
    /// Keys kept after key reduction.
    pub kept_keys: usize,
    /// `compressed_bytes / (animated_joints * samples)`.
    pub bytes_per_joint_sample: f32,
    /// False when the compressed form was not smaller and the plain clip was kept.
    pub compressed: bool,
}

/// The joints the error is measured on: the skeleton's, then one root per track it lacks.
struct Rig {
    skeleton: Skeleton,
    /// Per joint: the local offsets of its three error points.
    points: Vec<[Vec3; 3]>,
    /// Per joint: how far its error points and descendants reach from it in the bind pose.
    reach: Vec<f32>,
    /// Per joint: how far its error points and its children reach from it in the bind pose (what
    /// its rotation error moves once its children compensate it: see [`Eval`]).
    lever: Vec<f32>,
    /// Per joint: the model-space scale of its parent (1 for roots).
    parent_scale: Vec<f32>,
}

fn model_scale(a: &Affine3A) -> f32 {
    let m = a.matrix3;
    m.x_axis
        .length()
        .max(m.y_axis.length())
        .max(m.z_axis.length())
}

fn fk(parents: &[Option<u16>], local: &[Transform], out: &mut Vec<Affine3A>) {
    out.clear();
    for (j, t) in local.iter().enumerate() {
        let a = t.to_affine();
        let m = match parents.get(j).copied().flatten() {
            Some(p) => out.get(p as usize).copied().unwrap_or(Affine3A::IDENTITY) * a,
            None => a,
        };
        out.push(m);
    }
}

/// The skeleton's extent: bind-pose bounding-box diagonal of the joint positions (1 when degenerate).
pub fn skeleton_extent(skeleton: &Skeleton) -> f32 {
    let mut m = Vec::new();
    fk(skeleton.parents(), skeleton.bind_local(), &mut m);
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for a in &m {
        let p = Vec3::from(a.translation);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let d = (hi - lo).length();
    if d.is_finite() && d > 1e-6 {
        d
    } else {
        1.0
    }
}

fn clip_extent(clip: &Clip) -> f32 {
    let mut r: f32 = 0.0;
    let p = clip.to_plain();
    for t in p.tracks() {
        if let Channel::Constant(v) = t.translation {
            r = r.max(v.length());
        }
        if let Channel::Animated(o) = t.translation {
            for f in p.frames().chunks_exact(p.stride().max(1)) {
                let o = o as usize;
                r = r.max(Vec3::new(f[o], f[o + 1], f[o + 2]).length());
            }
        }
    }
    if r.is_finite() && r > 1e-6 {
        2.0 * r
    } else {
        1.0
    }
}

impl Rig {
    fn new(clip: &Clip, skeleton: Option<&Skeleton>, distance: f32) -> Option<Rig> {
        let (mut names, mut parents, mut bind) = match skeleton {
            Some(s) => (
                s.names().to_vec(),
                s.parents().to_vec(),
                s.bind_local().to_vec(),
            ),
            None => (Vec::new(), Vec::new(), Vec::new()),
        };
        for t in clip.tracks() {
            if !names.contains(&t.joint) {
                names.push(t.joint.clone());
                parents.push(None);
                bind.push(Transform::IDENTITY);
            }
        }
        let inv = inverse_bind_from_locals(&parents, &bind);
        let skeleton = Skeleton::new(names, parents.clone(), bind.clone(), inv).ok()?;
        let mut m = Vec::new();
        fk(&parents, &bind, &mut m);
        let n = parents.len();
        let scale: Vec<f32> = m.iter().map(|a| model_scale(a).max(1e-12)).collect();
        let points = scale
            .iter()
            .map(|s| [Vec3::X, Vec3::Y, Vec3::Z].map(|a| a * (distance / s)))
            .collect();
        let mut reach = vec![distance; n];
        let mut lever = vec![distance; n];
        // Children come after parents: walk backwards, pushing reach up the chain.
        for j in (0..n).rev() {
            if let Some(p) = parents[j] {
                let p = p as usize;
                let d = (Vec3::from(m[j].translation) - Vec3::from(m[p].translation)).length();
                reach[p] = reach[p].max(reach[j] + d);
                lever[p] = lever[p].max(distance + d);
            }
        }
        let parent_scale = parents
            .iter()
            .map(|p| p.map_or(1.0, |p| scale[p as usize]))
            .collect();
        Some(Rig {
            skeleton,
            points,
            reach,
            lever,
            parent_scale,
        })
    }

    /// Model-space error points of every joint for a local pose.
    fn points_of(&self, local: &[Transform], m: &mut Vec<Affine3A>, out: &mut Vec<[Vec3; 3]>) {
        fk(self.skeleton.parents(), local, m);
        out.clear();
        for (a, p) in m.iter().zip(&self.points) {
            out.push(p.map(|x| a.transform_point3(x)));
        }
    }

    /// Local poses of `clip` at each time (joints not driven keep their bind values).
    fn poses(&self, clip: &Clip, times: &[f32]) -> Vec<Vec<Transform>> {
        let binding = ClipBinding::new(clip, &self.skeleton);
        let mut sampler = Sampler::new();
        let defaults: Vec<Transform> = if clip.additive() {
            vec![Transform::IDENTITY; self.skeleton.len()]
        } else {
            self.skeleton.bind_local().to_vec()
        };
        times
            .iter()
            .map(|&t| {
                let mut pose = defaults.clone();
                // The output length matches the skeleton and the binding was made for it.
                let _ = sampler.sample(clip, &binding, &self.skeleton, t, &mut pose);
                pose
            })
            .collect()
    }

    /// Error points for each pose.
    fn all_points(&self, poses: &[Vec<Transform>]) -> Vec<Vec<[Vec3; 3]>> {
        let mut m = Vec::new();
        poses
            .iter()
            .map(|p| {
                let mut out = Vec::new();
                self.points_of(p, &mut m, &mut out);
                out
            })
            .collect()
    }
}

fn point_error<'a>(a: &'a [[Vec3; 3]], b: &'a [[Vec3; 3]]) -> impl Iterator<Item = f32> + 'a {
    a.iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|i| p[i].distance(q[i])).fold(0.0f32, f32::max))
}

/// Errors (one per joint per key time of `source`, time-major) of `candidate` against `source`, by the
/// metric of the module docs. Empty when the joints cannot form a skeleton (more than 65535).
pub fn measure(
    source: &Clip,
    candidate: &Clip,
    skeleton: Option<&Skeleton>,
    error_distance: f32,
) -> Vec<f32> {
    let Some(rig) = Rig::new(source, skeleton, error_distance) else {
        return Vec::new();
    };
    let times = source.times();
    let a = rig.all_points(&rig.poses(source, times));
    let b = rig.all_points(&rig.poses(candidate, times));
    a.iter()
        .zip(&b)
        .flat_map(|(x, y)| point_error(x, y).collect::<Vec<_>>())
        .collect()
}

fn max_error_of(src: &[Vec<[Vec3; 3]>], rig: &Rig, clip: &Clip, times: &[f32], limit: f32) -> f32 {
    let mut worst = 0.0f32;
    runtime_points(rig, clip, times, |k, pts| {
        for e in point_error(&src[k], pts) {
            worst = worst.max(e);
        }
        worst > limit
    });
    worst
}

/// True when `clip`, sampled by the runtime at `times`, keeps every joint's error within its limit.
fn within(src: &[Vec<[Vec3; 3]>], rig: &Rig, clip: &Clip, times: &[f32], limits: &[f32]) -> bool {
    let mut ok = true;
    runtime_points(rig, clip, times, |k, pts| {
        ok = !point_error(&src[k], pts)
            .zip(limits)
            .any(|(e, &l)| exceeds(e, l));
        !ok
    });
    ok
}

/// Samples `clip` with the runtime's sampler at each of `times` (over the bind pose, or the identity
/// for an additive clip) and calls `stop` with the time's index and the rig's model-space points,
/// until `stop` returns true.
fn runtime_points(
    rig: &Rig,
    clip: &Clip,
    times: &[f32],
    mut stop: impl FnMut(usize, &[[Vec3; 3]]) -> bool,
) {
    let binding = ClipBinding::new(clip, &rig.skeleton);
    let mut sampler = Sampler::new();
    let defaults: Vec<Transform> = if clip.additive() {
        vec![Transform::IDENTITY; rig.skeleton.len()]
    } else {
        rig.skeleton.bind_local().to_vec()
    };
    let mut pose = defaults.clone();
    let (mut m, mut pts) = (Vec::new(), Vec::new());
    for (k, &t) in times.iter().enumerate() {
        pose.copy_from_slice(&defaults);
        let _ = sampler.sample(clip, &binding, &rig.skeleton, t, &mut pose);
        rig.points_of(&pose, &mut m, &mut pts);
        if stop(k, &pts) {
            return;
        }
    }
}

/// True when `error` is above `limit` or not a number.
fn exceeds(error: f32, limit: f32) -> bool {
    error.is_nan() || error > limit
}

/// How far f32 arithmetic alone may move a model-space point, per unit of its largest coordinate,
/// as a multiple of `f32::EPSILON`: a one-ulp difference in a local rotation or translation, carried
/// through a chain of parents, moves a point far from the origin by a few ulps of its coordinates
/// (measured on the corpus: up to 4 ulps between the compiled clip and its source curves).
const NOISE_ULPS: f32 = 8.0;

/// Per joint: the error the encoder allows, the tolerance less the f32 noise of the joint's error
/// points ([`NOISE_ULPS`] x epsilon x their largest coordinate over the clip), so that the error
/// measured against the source by another computation stays within the tolerance. At least half
/// the tolerance.
fn joint_limits(src: &[Vec<[Vec3; 3]>], joints: usize, tolerance: f32) -> Vec<f32> {
    let mut mag = vec![0.0f32; joints];
    for key in src {
        for (m, p) in mag.iter_mut().zip(key) {
            for x in p {
                *m = m.max(x.abs().max_element());
            }
        }
    }
    mag.iter()
        .map(|m| (tolerance - NOISE_ULPS * f32::EPSILON * m).max(0.5 * tolerance))
        .collect()
}

/// A clip's channel values per key, ready to rebuild clips from.
#[derive(Clone)]
struct Work {
    times: Vec<f32>,
    tracks: Vec<WTrack>,
}

#[derive(Clone)]
struct WTrack {
    joint: String,
    t: WChan<Vec3>,
    r: WChan<Quat>,
    s: WChan<Vec3>,
}

#[derive(Clone)]
enum WChan<T> {
    Bind,
    Constant(T),
    Keys(Vec<T>),
}

impl<T: Copy> WChan<T> {
    fn channel(&self, o: &mut u32, n: u32) -> Channel<T> {
        match self {
            WChan::Bind => Channel::Bind,
            WChan::Constant(v) => Channel::Constant(*v),
            WChan::Keys(_) => {
                *o += n;
                Channel::Animated(*o - n)
            }
        }
    }
}

impl Work {
    fn from_plain(p: &Clip) -> Work {
        let stride = p.stride().max(1);
        let frames: Vec<&[f32]> = p.frames().chunks_exact(stride).collect();
        let v3 = |c: Channel<Vec3>| match c {
            Channel::Bind => WChan::Bind,
            Channel::Constant(v) => WChan::Constant(v),
            Channel::Animated(o) => {
                let o = o as usize;
                WChan::Keys(
                    frames
                        .iter()
                        .map(|f| Vec3::from_slice(&f[o..o + 3]))
                        .collect(),
                )
            }
        };
        let tracks = p
            .tracks()
            .iter()
            .map(|t| WTrack {
                joint: t.joint.clone(),
                t: v3(t.translation),
                r: match t.rotation {
                    Channel::Bind => WChan::Bind,
                    Channel::Constant(q) => WChan::Constant(q),
                    Channel::Animated(o) => {
                        let o = o as usize;
                        WChan::Keys(
                            frames
                                .iter()
                                .map(|f| Quat::from_slice(&f[o..o + 4]))
                                .collect(),
                        )
                    }
                },
                s: v3(t.scale),
            })
            .collect();
        Work {
            times: p.times().to_vec(),
            tracks,
        }
    }

    /// The clip tracks of these values, with animated channels numbered in track order, and the
    /// number of animated components: a rotation stores `rotation_components` (4 as plain floats, 3
    /// quantized).
    fn clip_tracks(&self, rotation_components: u32) -> (Vec<Track>, u32) {
        let mut o = 0;
        let tracks = self
            .tracks
            .iter()
            .map(|t| Track {
                joint: t.joint.clone(),
                translation: t.t.channel(&mut o, 3),
                rotation: t.r.channel(&mut o, rotation_components),
                scale: t.s.channel(&mut o, 3),
            })
            .collect();
        (tracks, o)
    }

    /// A plain clip with these values.
    fn plain(&self, like: &Clip) -> Option<Clip> {
        let (tracks, o) = self.clip_tracks(4);
        let mut frames = Vec::with_capacity(o as usize * self.times.len());
        for k in 0..self.times.len() {
            for t in &self.tracks {
                if let WChan::Keys(v) = &t.t {
                    frames.extend_from_slice(&v[k].to_array());
                }
                if let WChan::Keys(v) = &t.r {
                    frames.extend_from_slice(&v[k].to_array());
                }
                if let WChan::Keys(v) = &t.s {
                    frames.extend_from_slice(&v[k].to_array());
                }
            }
        }
        Clip::from_parts(
            like.name().to_owned(),
            like.duration(),
            like.sample_rate(),
            like.looping(),
            like.additive(),
            self.times.clone(),
            tracks,
            o as usize,
            frames,
        )
        .ok()
    }

    fn keep(&mut self, keys: &[usize]) {
        self.times = keys.iter().map(|&k| self.times[k]).collect();
        for t in &mut self.tracks {
            if let WChan::Keys(v) = &mut t.t {
                *v = keys.iter().map(|&k| v[k]).collect();
            }
            if let WChan::Keys(v) = &mut t.r {
                *v = keys.iter().map(|&k| v[k]).collect();
            }
            if let WChan::Keys(v) = &mut t.s {
                *v = keys.iter().map(|&k| v[k]).collect();
            }
        }
    }
}

fn mid3(v: &[Vec3]) -> Vec3 {
    let (lo, hi) = v.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(a, b), x| (a.min(*x), b.max(*x)),
    );
    (lo + hi) * 0.5
}

fn mean_quat(v: &[Quat]) -> Quat {
    let first = v.first().copied().unwrap_or(Quat::IDENTITY);
    let mut acc = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    for q in v {
        acc += if q.dot(first) < 0.0 { -*q } else { *q };
    }
    if acc.length() > 1e-6 {
        acc.normalize()
    } else {
        first
    }
}

/// Step 1: channels that one value reproduces become constants or bind.
fn simplify_channels(
    work: &mut Work,
    like: &Clip,
    rig: &Rig,
    src: &[Vec<[Vec3; 3]>],
    src_times: &[f32],
    budget: f32,
    bind_allowed: bool,
) {
    let defaults: Vec<Option<Transform>> = work
        .tracks
        .iter()
        .map(|t| {
            if like.additive() {
                Some(Transform::IDENTITY)
            } else if bind_allowed {
                rig.skeleton
                    .find(&t.joint)
                    .map(|j| rig.skeleton.bind_local()[j as usize])
            } else {
                None
            }
        })
        .collect();
    #[allow(clippy::needless_range_loop)] // `work` is replaced inside the loop
    for i in 0..work.tracks.len() {
        for ch in 0..3 {
            let mut candidates: Vec<Work> = Vec::new();
            let tr = &work.tracks[i];
            let mut with = |f: &dyn Fn(&mut WTrack)| {
                let mut w = work.clone();
                f(&mut w.tracks[i]);
                candidates.push(w);
            };
            let d = defaults[i];
            match ch {
                0 => {
                    if let WChan::Keys(v) = &tr.t {
                        if d.is_some() {
                            with(&|t: &mut WTrack| t.t = WChan::Bind);
                        }
                        let c = mid3(v);
                        with(&move |t: &mut WTrack| t.t = WChan::Constant(c));
                    }
                }
                1 => {
                    if let WChan::Keys(v) = &tr.r {
                        if d.is_some() {
                            with(&|t: &mut WTrack| t.r = WChan::Bind);
                        }
                        let c = mean_quat(v);
                        with(&move |t: &mut WTrack| t.r = WChan::Constant(c));
                    }
                }
                _ => {
                    if let WChan::Keys(v) = &tr.s {
                        if d.is_some() {
                            with(&|t: &mut WTrack| t.s = WChan::Bind);
                        }
                        let c = mid3(v);
                        with(&move |t: &mut WTrack| t.s = WChan::Constant(c));
                    }
                }
            }
            for w in candidates {
                let Some(c) = w.plain(like) else { continue };
                if max_error_of(src, rig, &c, src_times, budget) <= budget {
                    *work = w;
                    break;
                }
            }
        }
    }
}

/// Step 2: greedy key reduction. Returns the kept key indices.
fn reduce_keys(
    work: &Work,
    like: &Clip,
    rig: &Rig,
    src: &[Vec<[Vec3; 3]>],
    budget: f32,
) -> Vec<usize> {
    let n = work.times.len();
    if n <= 2 {
        return (0..n).collect();
    }
    let Some(plain) = work.plain(like) else {
        return (0..n).collect();
    };
    let poses = rig.poses(&plain, &work.times);
    let (mut m, mut pts) = (Vec::new(), Vec::new());
    let mut lerped = poses[0].clone();
    let mut ok = |a: usize, b: usize| -> bool {
        let (ta, tb) = (work.times[a], work.times[b]);
        for (k, src_k) in src.iter().enumerate().take(b).skip(a + 1) {
            let x = (work.times[k] - ta) / (tb - ta);
            for (j, out) in lerped.iter_mut().enumerate() {
                let (p, q) = (poses[a][j], poses[b][j]);
                *out = Transform {
                    translation: p.translation.lerp(q.translation, x),
                    rotation: nlerp(p.rotation, q.rotation, x),
                    scale: p.scale.lerp(q.scale, x),
                };
            }
            rig.points_of(&lerped, &mut m, &mut pts);
            if point_error(src_k, &pts).any(|e| e > budget) {
                return false;
            }
        }
        true
    };
    let mut kept = vec![0];
    let mut a = 0;
    while a + 1 < n {
        let mut b = a + 1;
        while b + 1 < n && b + 1 - a <= 128 && ok(a, b + 1) {
            b += 1;
        }
        kept.push(b);
        a = b;
    }
    kept
}

/// Which channel of a track a component belongs to.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    T,
    R,
    S,
}

/// One quantized component: its values at the kept keys and where it comes from.
struct Comp {
    vals: Vec<f32>,
    /// A-priori error per unit of value, model units (used for the first bit widths only).
    gain: f32,
    track: usize,
    kind: Kind,
    axis: usize,
    /// For rotation components: the rotation's number (component order).
    rot: usize,
}

/// Smallest magnitude a dropped quaternion component may have: the largest of four unit components
/// is at least 0.5, so dropping any component of at least this size rebuilds it no less precisely
/// than dropping the largest could in the worst case.
const MIN_DROPPED: f32 = 0.5;

/// Splits a rotation track into per-key (index, three components). The dropped component stays the
/// same from key to key while its magnitude is at least [`MIN_DROPPED`] (switching to the largest
/// otherwise), so the stored components do not jump where two components trade places as the
/// largest; of the four possible first indices (and the plain largest-per-key split) the one whose
/// component ranges are narrowest (sum of log2 of the ranges) is kept.
fn split_rotations(v: &[Quat]) -> Vec<(u8, [f32; 3])> {
    let largest: Vec<(u8, [f32; 3])> = v.iter().map(|q| smallest_three(*q)).collect();
    let cost = |s: &[(u8, [f32; 3])]| -> f32 {
        (0..3)
            .map(|i| {
                let lo = s.iter().map(|x| x.1[i]).fold(f32::MAX, f32::min);
                let hi = s.iter().map(|x| x.1[i]).fold(f32::MIN, f32::max);
                ((hi - lo).max(0.0) + 1e-6).log2()
            })
            .sum()
    };
    let mut best_cost = cost(&largest);
    let mut best = largest;
    for start in 0..4u8 {
        let mut cur = start;
        let mut out = Vec::with_capacity(v.len());
        for q in v {
            if q.to_array()[usize::from(cur)].abs() < MIN_DROPPED {
                cur = smallest_three(*q).0;
            }
            out.push((cur, three_without(*q, cur)));
        }
        let c = cost(&out);
        if c < best_cost {
            best_cost = c;
            best = out;
        }
    }
    best
}

/// Step 3's fixed part for one set of kept keys and one segment length: components, clip ranges
/// and segment sub-ranges. The bit widths and stored integers are chosen by [`Eval`].
struct Layout {
    keys: usize,
    seg_len: usize,
    seg_count: usize,
    comps: Vec<Comp>,
    starts: Vec<bool>,
    /// Per rotation, per key: the index of the dropped quaternion component.
    index: Vec<Vec<u8>>,
    ranges: Vec<[f32; 2]>,
    /// Per segment, per component (segment-major): the sub-range (`bits` is set later).
    sub: Vec<SegmentComponent>,
}

/// How one component of one segment is quantized: `value = bias + scale * q`, `q <= top`.
#[derive(Clone, Copy)]
struct Quant {
    scale: f32,
    bias: f32,
    top: u32,
}

impl Quant {
    /// The stored integer nearest to `v` and the value it decodes to (as the decoder computes it).
    fn quantize(self, v: f32) -> (u32, f32) {
        // Round to nearest (halves up) by truncation, which needs no libm call.
        let y = if self.scale > 0.0 {
            (v - self.bias) / self.scale
        } else {
            0.0
        };
        let q = if y > 0.0 {
            ((y + 0.5) as u32).min(self.top)
        } else {
            0
        };
        (q, self.bias + self.scale * q as f32)
    }
}

/// The segment sub-range of values `keys` inside the clip range `lo .. lo + ext`: the 8-bit
/// fractions `min` and `extent` whose decoded range covers every value.
fn sub_range(range: [f32; 2], keys: &[f32]) -> SegmentComponent {
    let [lo, ext] = range;
    let mut e = SegmentComponent::default();
    if ext <= 0.0 || keys.is_empty() {
        return e;
    }
    let smin = keys.iter().copied().fold(f32::MAX, f32::min);
    let smax = keys.iter().copied().fold(f32::MIN, f32::max);
    let a = (((smin - lo) / ext) * 255.0).floor().clamp(0.0, 255.0) as u8;
    e.min = a;
    let mut b = ((((smax - lo) / ext) * 255.0).ceil() as i32 - i32::from(a)).clamp(0, 255);
    loop {
        e.extent = b as u8;
        let (_, seg_lo) = dequant_params(range, SegmentComponent { bits: 1, ..e });
        let seg_ext = ext * (f32::from(e.extent) / 255.0);
        if seg_lo + seg_ext >= smax || b >= 255 - i32::from(a) {
            break;
        }
        b += 1;
    }
    e
}

impl Layout {
    fn new(work: &Work, rig: &Rig, seg_len: usize, compensate: bool) -> Layout {
        let n = work.times.len();
        let seg_len = seg_len.clamp(1, n.max(1));
        let mut comps: Vec<Comp> = Vec::new();
        let mut starts: Vec<bool> = Vec::new();
        let mut index: Vec<Vec<u8>> = Vec::new();
        for (track, t) in work.tracks.iter().enumerate() {
            let j = rig.skeleton.find(&t.joint).map_or(0, usize::from);
            let reach = rig.reach.get(j).copied().unwrap_or(1.0);
            let lever = if compensate {
                rig.lever.get(j).copied().unwrap_or(1.0)
            } else {
                reach
            };
            let ps = rig.parent_scale.get(j).copied().unwrap_or(1.0);
            let mut push = |vals: Vec<f32>, gain: f32, kind: Kind, axis: usize, rot: usize| {
                comps.push(Comp {
                    vals,
                    gain,
                    track,
                    kind,
                    axis,
                    rot,
                });
                starts.push(kind == Kind::R && axis == 0);
            };
            if let WChan::Keys(v) = &t.t {
                for i in 0..3 {
                    push(v.iter().map(|x| x[i]).collect(), ps * 1.8, Kind::T, i, 0);
                }
            }
            if let WChan::Keys(v) = &t.r {
                let split = split_rotations(v);
                index.push(split.iter().map(|s| s.0).collect());
                let rot = index.len() - 1;
                for i in 0..3 {
                    let vals = split.iter().map(|s| s.1[i]).collect();
                    push(vals, 4.0 * lever, Kind::R, i, rot);
                }
            }
            if let WChan::Keys(v) = &t.s {
                for i in 0..3 {
                    push(
                        v.iter().map(|x| x[i]).collect(),
                        ps * reach * 1.8,
                        Kind::S,
                        i,
                        0,
                    );
                }
            }
        }
        let nc = comps.len();
        let seg_count = n.div_ceil(seg_len);
        let ranges: Vec<[f32; 2]> = comps
            .iter()
            .map(|c| {
                let lo = c.vals.iter().copied().fold(f32::MAX, f32::min);
                let hi = c.vals.iter().copied().fold(f32::MIN, f32::max);
                if n == 0 {
                    [0.0, 0.0]
                } else {
                    [lo, (hi - lo).max(0.0)]
                }
            })
            .collect();
        let mut sub = vec![SegmentComponent::default(); seg_count * nc];
        for s in 0..seg_count {
            let keys = s * seg_len..((s + 1) * seg_len).min(n);
            for (c, comp) in comps.iter().enumerate() {
                sub[s * nc + c] = sub_range(ranges[c], &comp.vals[keys.clone()]);
            }
        }
        Layout {
            keys: n,
            seg_len,
            seg_count,
            comps,
            starts,
            index,
            ranges,
            sub,
        }
    }

    fn seg_keys(&self, s: usize) -> std::ops::Range<usize> {
        s * self.seg_len..((s + 1) * self.seg_len).min(self.keys)
    }

    /// The quantization parameters of component `c` in segment `s` at `bits`.
    fn params(&self, s: usize, c: usize, bits: u8) -> Quant {
        let e = SegmentComponent {
            bits,
            ..self.sub[s * self.comps.len() + c]
        };
        let (scale, bias) = dequant_params(self.ranges[c], e);
        Quant {
            scale,
            bias,
            top: ((1u64 << bits) - 1) as u32,
        }
    }

    /// First bit widths (per segment, per component): the fewest whose a-priori error bound
    /// (`gain` x half a quantization step) stays within `budget` model units.
    fn first_bits(&self, budget: f32) -> Vec<u8> {
        let nc = self.comps.len();
        let mut bits = vec![0u8; self.sub.len()];
        for (i, e) in self.sub.iter().enumerate() {
            let c = i % nc.max(1);
            let allowed = budget / self.comps[c].gain.max(1e-12);
            let seg_ext = self.ranges[c][1] * (f32::from(e.extent) / 255.0);
            let mut b = 0u8;
            while b < MAX_BITS {
                let err = if b == 0 {
                    seg_ext * 0.5
                } else {
                    seg_ext / ((1u32 << b) - 1) as f32 * 0.5
                };
                if err <= allowed {
                    break;
                }
                b += 1;
            }
            bits[i] = b;
        }
        bits
    }

    /// The compressed clip with these bit widths and stored integers (per component, per key).
    fn encode(&self, bits: &[u8], qi: &[Vec<u32>], work: &Work, like: &Clip) -> Option<Clip> {
        let n = self.keys;
        let nc = self.comps.len();
        let mut segments = self.sub.clone();
        for (e, &b) in segments.iter_mut().zip(bits) {
            e.bits = b;
        }
        let mut q = vec![0u32; n * nc];
        for (c, list) in qi.iter().enumerate() {
            for (k, &x) in list.iter().enumerate() {
                q[k * nc + c] = x;
            }
        }
        let rotations = self.index.len();
        let mut idx = vec![0u8; n * rotations];
        for (r, list) in self.index.iter().enumerate() {
            for (k, &i) in list.iter().enumerate() {
                idx[k * rotations + r] = i;
            }
        }
        let data = pack(n, self.seg_len, &segments, &self.starts, &q, &idx);
        let (tracks, _) = work.clip_tracks(3);
        Clip::from_quantized(
            like.name().to_owned(),
            like.duration(),
            like.sample_rate(),
            like.looping(),
            like.additive(),
            work.times.clone(),
            tracks,
            QuantizedParts {
                segment_len: self.seg_len as u32,
                ranges: self.ranges.clone(),
                segments,
                data,
            },
        )
        .ok()
    }
}

/// The rotation the decoder rebuilds from a smallest-three split, before normalisation (the same
/// arithmetic as `sinew_core::compressed`).
fn raw_rotation(index: u8, v: [f32; 3]) -> Quat {
    const PERM: [[usize; 4]; 4] = [[3, 0, 1, 2], [0, 3, 1, 2], [0, 1, 3, 2], [0, 1, 2, 3]];
    let w = (1.0 - v[0] * v[0] - v[1] * v[1] - v[2] * v[2])
        .max(0.0)
        .sqrt();
    let src = [v[0], v[1], v[2], w];
    let p = PERM[usize::from(index & 3)];
    Quat::from_xyzw(src[p[0]], src[p[1]], src[p[2]], src[p[3]])
}

/// Where the sampler reads a clip with these key times at time `t`: `(k0, k1, alpha)`, as
/// [`Clip::local_time`] and [`Sampler::locate`] compute it.
fn locate(like: &Clip, times: &[f32], t: f32) -> (usize, usize, f32) {
    let t = like.local_time(t);
    let n = times.len();
    if n <= 1 || t <= times[0] {
        if like.looping() && n > 1 && t < times[0] {
            let span = times[0] + (like.duration() - times[n - 1]);
            if span > 0.0 {
                let a = (t + like.duration() - times[n - 1]) / span;
                return (n - 1, 0, a.clamp(0.0, 1.0));
            }
        }
        return (0, 0, 0.0);
    }
    let c = times.partition_point(|&x| x <= t).saturating_sub(1);
    if c + 1 >= n {
        if like.looping() {
            let span = like.duration() - times[c] + times[0];
            if span > 0.0 {
                return (c, 0, ((t - times[c]) / span).clamp(0.0, 1.0));
            }
        }
        return (c, c, 0.0);
    }
    (c, c + 1, (t - times[c]) / (times[c + 1] - times[c]))
}

/// What every quantization of one clip is measured against.
struct Ctx<'a> {
    rig: &'a Rig,
    like: &'a Clip,
    /// Source key times.
    times: &'a [f32],
    /// Per source time, per joint: the source's error points.
    src: Vec<Vec<[Vec3; 3]>>,
    /// Per source time, per joint: the source's model-space rotation (the product of the local
    /// rotations down the chain).
    src_rot: Vec<Vec<Quat>>,
    /// Per joint: the largest error allowed.
    limits: Vec<f32>,
    /// Every scale of the source poses is positive and uniform, so that model-space rotations are
    /// the products of the local rotations (what chain compensation relies on).
    uniform: bool,
}

impl<'a> Ctx<'a> {
    fn new(rig: &'a Rig, like: &'a Clip, times: &'a [f32], tolerance: f32) -> Ctx<'a> {
        let poses = rig.poses(like, times);
        let src = rig.all_points(&poses);
        let parents = rig.skeleton.parents();
        let src_rot = poses
            .iter()
            .map(|pose| {
                let mut out: Vec<Quat> = Vec::with_capacity(pose.len());
                for (j, t) in pose.iter().enumerate() {
                    let p = parents.get(j).copied().flatten().map(usize::from);
                    let pr = p.and_then(|p| out.get(p).copied());
                    out.push(pr.map_or(t.rotation, |pr| pr * t.rotation));
                }
                out
            })
            .collect();
        let limits = joint_limits(&src, rig.skeleton.len(), tolerance);
        let uniform = poses.iter().flatten().all(|t| {
            let (lo, hi) = (t.scale.min_element(), t.scale.max_element());
            lo > 0.0 && hi <= lo * (1.0 + 1e-4)
        });
        Ctx {
            rig,
            like,
            times,
            src,
            src_rot,
            limits,
            uniform,
        }
    }
}

/// Undo records of one tentative change of [`Eval`].
#[derive(Default)]
struct Undo {
    bits: Option<(usize, u8)>,
    comps: Vec<(usize, usize, u32, f32)>,
    key_rot: Vec<(usize, usize, Quat)>,
    poses: Vec<(usize, usize, Transform, Affine3A, Affine3A)>,
}

/// A quantized clip under construction, with its measured error kept up to date while bit widths
/// change one at a time.
///
/// Rotations are quantized with *chain compensation*: at every key, joints are quantized parents
/// first, and a joint's stored rotation is not its source local rotation but the one that, under
/// its parent's already quantized model rotation, gives the joint's source model rotation. So a
/// joint's orientation error does not pass to its descendants' orientations (only to their
/// positions, through its own bone), and far-reaching joints need fewer bits.
///
/// Changing a component of one segment requantizes only that segment's keys of the joint's subtree,
/// and re-measures only the source times that read those keys.
struct Eval<'a> {
    ctx: &'a Ctx<'a>,
    layout: &'a Layout,
    compensate: bool,
    /// Per source time: the keys and blend factor the sampler uses.
    at: Vec<(usize, usize, f32)>,
    /// Per key: its source time.
    key_src: Vec<Option<usize>>,
    /// Per track: its joint. Per joint: its track.
    joint: Vec<usize>,
    track_of: Vec<Option<usize>>,
    /// Per track and channel kind (T, R, S): the first component, if quantized.
    first: Vec<[Option<usize>; 3]>,
    /// Per joint: itself, then its descendants in skeleton order.
    subtree: Vec<Vec<usize>>,
    /// Per joint: its local transform where the clip does not animate it.
    base: Vec<Transform>,
    /// Per segment, per component: bit width, and the quantization parameters it gives.
    bits: Vec<u8>,
    params: Vec<Quant>,
    /// Per component, per key: the stored integer and the value it decodes to.
    qi: Vec<Vec<u32>>,
    dec: Vec<Vec<f32>>,
    /// Per key, per joint: the quantized clip's model rotation at that key.
    key_rot: Vec<Vec<Quat>>,
    /// Per source time, per joint: local pose and model transform of the quantized clip.
    local: Vec<Vec<Transform>>,
    /// Per source time, per joint: `local` as an affine transform.
    local_aff: Vec<Vec<Affine3A>>,
    model: Vec<Vec<Affine3A>>,
    /// Per segment: the source times that read one of its keys.
    seg_times: Vec<Vec<usize>>,
    undo: Undo,
    /// Per joint, during a change: its stored values changed / its model transforms changed.
    dirty: Vec<bool>,
    moved: Vec<bool>,
}

impl<'a> Eval<'a> {
    /// The state of `work` quantized with `bits`. With `check`, also whether every joint is within
    /// its limit at every source time; the poses are then computed only up to the first time that
    /// is not (the state is for the check alone).
    fn build(
        ctx: &'a Ctx<'a>,
        layout: &'a Layout,
        work: &Work,
        bits: Vec<u8>,
        compensate: bool,
        check: bool,
    ) -> (Eval<'a>, bool) {
        let rig = ctx.rig;
        let nj = rig.skeleton.len();
        let parents = rig.skeleton.parents();
        let at: Vec<(usize, usize, f32)> = ctx
            .times
            .iter()
            .map(|&t| locate(ctx.like, &work.times, t))
            .collect();
        let key_src = work
            .times
            .iter()
            .map(|t| ctx.times.binary_search_by(|x| x.total_cmp(t)).ok())
            .collect();
        let joint: Vec<usize> = work
            .tracks
            .iter()
            .map(|t| rig.skeleton.find(&t.joint).map_or(0, usize::from))
            .collect();
        let mut track_of = vec![None; nj];
        for (tr, &j) in joint.iter().enumerate() {
            if let Some(slot) = track_of.get_mut(j) {
                *slot = Some(tr);
            }
        }
        let mut first = vec![[None; 3]; work.tracks.len()];
        for (c, comp) in layout.comps.iter().enumerate() {
            if comp.axis == 0 {
                first[comp.track][comp.kind as usize] = Some(c);
            }
        }
        let mut subtree: Vec<Vec<usize>> = (0..nj).map(|j| vec![j]).collect();
        for d in 0..nj {
            let mut p = parents.get(d).copied().flatten();
            while let Some(a) = p {
                let a = usize::from(a);
                subtree[a].push(d);
                p = parents.get(a).copied().flatten();
            }
        }
        let mut base: Vec<Transform> = if ctx.like.additive() {
            vec![Transform::IDENTITY; nj]
        } else {
            rig.skeleton.bind_local().to_vec()
        };
        for (tr, t) in work.tracks.iter().enumerate() {
            let Some(slot) = base.get_mut(joint[tr]) else {
                continue;
            };
            if let WChan::Constant(v) = t.t {
                slot.translation = v;
            }
            if let WChan::Constant(q) = t.r {
                slot.rotation = q;
            }
            if let WChan::Constant(v) = t.s {
                slot.scale = v;
            }
        }
        let mut seg_times = vec![Vec::new(); layout.seg_count];
        for (i, &(k0, k1, a)) in at.iter().enumerate() {
            let s0 = k0 / layout.seg_len;
            if let Some(list) = seg_times.get_mut(s0) {
                list.push(i);
            }
            let s1 = k1 / layout.seg_len;
            if a != 0.0 && s1 != s0 {
                if let Some(list) = seg_times.get_mut(s1) {
                    list.push(i);
                }
            }
        }
        let nc = layout.comps.len();
        let n = layout.keys;
        let mut e = Eval {
            ctx,
            layout,
            compensate,
            local: vec![base.clone(); at.len()],
            local_aff: vec![vec![Affine3A::IDENTITY; nj]; at.len()],
            model: vec![vec![Affine3A::IDENTITY; nj]; at.len()],
            dirty: vec![true; nj],
            moved: vec![true; nj],
            at,
            key_src,
            joint,
            track_of,
            first,
            subtree,
            base,
            params: (0..bits.len())
                .map(|i| layout.params(i / nc.max(1), i % nc.max(1), bits[i]))
                .collect(),
            bits,
            qi: vec![vec![0; n]; nc],
            dec: vec![vec![0.0; n]; nc],
            key_rot: vec![vec![Quat::IDENTITY; nj]; n],
            seg_times,
            undo: Undo::default(),
        };
        let all: Vec<usize> = (0..nj).collect();
        for s in 0..layout.seg_count {
            e.requantize(s, &all, None, false);
        }
        e.dirty.fill(true);
        e.moved.fill(true);
        for i in 0..e.at.len() {
            e.resample(i, &all, false);
            if check && (0..nj).any(|j| exceeds(e.joint_error(i, j), e.ctx.limits[j])) {
                return (e, false);
            }
        }
        (e, true)
    }

    /// [`Eval::build`] without the check.
    fn new(
        ctx: &'a Ctx<'a>,
        layout: &'a Layout,
        work: &Work,
        bits: Vec<u8>,
        compensate: bool,
    ) -> Eval<'a> {
        Eval::build(ctx, layout, work, bits, compensate, false).0
    }

    fn parent(&self, j: usize) -> Option<usize> {
        self.ctx
            .rig
            .skeleton
            .parents()
            .get(j)
            .copied()
            .flatten()
            .map(usize::from)
    }

    /// Quantizes the keys of segment `s` for `joints` (a joint's subtree, or all joints, in
    /// skeleton order). `changed`: the component (of the first joint) whose bit width changed, so
    /// that only what depends on it is redone; `None` redoes everything. Sets `dirty`, and records
    /// undo information when `record`.
    fn requantize(&mut self, s: usize, joints: &[usize], changed: Option<usize>, record: bool) {
        let nc = self.layout.comps.len();
        for &d in joints {
            self.dirty[d] = false;
        }
        if let Some(c) = changed.filter(|&c| self.layout.comps[c].kind != Kind::R) {
            // A translation or scale component: nothing else depends on it.
            if let Some(&j) = joints.first() {
                for k in self.layout.seg_keys(s) {
                    let v = self.layout.comps[c].vals[k];
                    self.dirty[j] |= self.store(s, c, k, v, record, nc);
                }
            }
            return;
        }
        for k in self.layout.seg_keys(s) {
            for (n, &d) in joints.iter().enumerate() {
                if changed.is_some() && n > 0 && !self.compensate {
                    break;
                }
                let pr = self
                    .parent(d)
                    .map_or(Quat::IDENTITY, |p| self.key_rot[k][p]);
                let mut rot = self.base[d].rotation;
                let mut rot_changed = false;
                if let Some(tr) = self.track_of[d] {
                    let [ft, fr, fs] = self.first[tr];
                    if changed.is_none() {
                        for c0 in [ft, fs].into_iter().flatten() {
                            for c in c0..c0 + 3 {
                                let v = self.layout.comps[c].vals[k];
                                self.dirty[d] |= self.store(s, c, k, v, record, nc);
                            }
                        }
                    }
                    if let Some(c0) = fr {
                        let comp = &self.layout.comps[c0];
                        let index = self.layout.index[comp.rot][k];
                        let vals = match self.key_src[k] {
                            Some(i) if self.compensate => {
                                let target = (pr.inverse() * self.ctx.src_rot[i][d]).normalize();
                                three_without(target, index)
                            }
                            _ => [0, 1, 2].map(|a| self.layout.comps[c0 + a].vals[k]),
                        };
                        for (a, v) in vals.into_iter().enumerate() {
                            rot_changed |= self.store(s, c0 + a, k, v, record, nc);
                        }
                        self.dirty[d] |= rot_changed;
                        let q = [0, 1, 2].map(|a| self.dec[c0 + a][k]);
                        rot = normalize_rotation(raw_rotation(index, q));
                    }
                }
                if changed.is_some() && n == 0 && !rot_changed {
                    // The joint's rotation at this key did not change: nothing below it does.
                    break;
                }
                if record {
                    self.undo.key_rot.push((k, d, self.key_rot[k][d]));
                }
                self.key_rot[k][d] = pr * rot;
            }
        }
    }

    /// Quantizes `v` as component `c` of key `k` (in segment `s`); returns whether the stored
    /// value changed.
    fn store(&mut self, s: usize, c: usize, k: usize, v: f32, record: bool, nc: usize) -> bool {
        let (q, x) = self.params[s * nc + c].quantize(v);
        let changed = q != self.qi[c][k] || x.to_bits() != self.dec[c][k].to_bits();
        if changed {
            if record {
                self.undo.comps.push((c, k, self.qi[c][k], self.dec[c][k]));
            }
            self.qi[c][k] = q;
            self.dec[c][k] = x;
        }
        changed
    }

    /// Recomputes the local poses (of dirty joints) and model transforms (of joints that moved:
    /// dirty, or below a dirty joint) of `joints` at source time `i`; sets `moved`.
    fn resample(&mut self, i: usize, joints: &[usize], record: bool) {
        for (n, &d) in joints.iter().enumerate() {
            let parent = self.parent(d);
            let below = n > 0 && parent.is_some_and(|p| self.moved[p]);
            self.moved[d] = self.dirty[d] || below;
            if !self.moved[d] {
                continue;
            }
            if record {
                self.undo.poses.push((
                    i,
                    d,
                    self.local[i][d],
                    self.local_aff[i][d],
                    self.model[i][d],
                ));
            }
            if self.dirty[d] {
                if let Some(tr) = self.track_of[d] {
                    self.local[i][d] = self.sampled(tr, i, self.local[i][d]);
                }
                self.local_aff[i][d] = self.local[i][d].to_affine();
            }
            let pm = parent.map_or(Affine3A::IDENTITY, |p| self.model[i][p]);
            self.model[i][d] = pm * self.local_aff[i][d];
        }
    }

    fn vec3(&self, c: usize, k: usize) -> Vec3 {
        Vec3::new(self.dec[c][k], self.dec[c + 1][k], self.dec[c + 2][k])
    }

    fn quat(&self, c: usize, k: usize) -> Quat {
        let rot = self.layout.comps[c].rot;
        let idx = self.layout.index[rot][k];
        raw_rotation(
            idx,
            [self.dec[c][k], self.dec[c + 1][k], self.dec[c + 2][k]],
        )
    }

    /// Track `tr`'s local transform at source time `i` (animated channels replaced in `base`), as
    /// the sampler computes it.
    fn sampled(&self, tr: usize, i: usize, mut base: Transform) -> Transform {
        let (k0, k1, a) = self.at[i];
        let [ft, fr, fs] = self.first[tr];
        if a == 0.0 {
            if let Some(c) = ft {
                base.translation = self.vec3(c, k0);
            }
            if let Some(c) = fs {
                base.scale = self.vec3(c, k0);
            }
            if let Some(c) = fr {
                base.rotation = normalize_rotation(self.quat(c, k0));
            }
        } else {
            if let Some(c) = ft {
                base.translation = self.vec3(c, k0).lerp(self.vec3(c, k1), a);
            }
            if let Some(c) = fs {
                base.scale = self.vec3(c, k0).lerp(self.vec3(c, k1), a);
            }
            if let Some(c) = fr {
                base.rotation = nlerp(self.quat(c, k0), self.quat(c, k1), a);
            }
        }
        base
    }

    fn joint_error(&self, i: usize, j: usize) -> f32 {
        let m = &self.model[i][j];
        let p = &self.ctx.rig.points[j];
        let s = &self.ctx.src[i][j];
        (0..3)
            .map(|x| m.transform_point3(p[x]).distance(s[x]))
            .fold(0.0f32, f32::max)
    }

    /// True when every joint is within its limit at every source time.
    #[cfg(test)]
    fn within(&self) -> bool {
        (0..self.at.len()).all(|i| {
            (0..self.ctx.limits.len()).all(|j| self.joint_error(i, j) <= self.ctx.limits[j])
        })
    }

    /// Sets component `c` of segment `s` to `bits` (tentatively: [`Eval::undo`] reverts it) and
    /// returns the largest ratio of error to limit over the joints and times that changed. As soon
    /// as one ratio exceeds `cap` it stops and returns infinity, leaving a state that only
    /// [`Eval::undo`] may follow.
    fn set(&mut self, s: usize, c: usize, bits: u8, cap: f32) -> f32 {
        let nc = self.layout.comps.len();
        self.undo.comps.clear();
        self.undo.key_rot.clear();
        self.undo.poses.clear();
        self.undo.bits = Some((s * nc + c, self.bits[s * nc + c]));
        self.bits[s * nc + c] = bits;
        self.params[s * nc + c] = self.layout.params(s, c, bits);
        let j = self.joint[self.layout.comps[c].track];
        let joints = std::mem::take(&mut self.subtree[j]);
        self.requantize(s, &joints, Some(c), true);
        let times = std::mem::take(&mut self.seg_times[s]);
        let mut worst = 0.0f32;
        'times: for &i in &times {
            self.resample(i, &joints, true);
            for &d in &joints {
                if !self.moved[d] {
                    continue;
                }
                let r = self.joint_error(i, d) / self.ctx.limits[d];
                if exceeds(r, cap) {
                    worst = f32::INFINITY;
                    break 'times;
                }
                worst = worst.max(r);
            }
        }
        self.seg_times[s] = times;
        self.subtree[j] = joints;
        worst
    }

    /// Reverts the last [`Eval::set`].
    fn undo(&mut self) {
        if let Some((i, b)) = self.undo.bits.take() {
            self.bits[i] = b;
            let nc = self.layout.comps.len().max(1);
            self.params[i] = self.layout.params(i / nc, i % nc, b);
        }
        for &(c, k, q, x) in self.undo.comps.iter().rev() {
            self.qi[c][k] = q;
            self.dec[c][k] = x;
        }
        for &(k, d, r) in self.undo.key_rot.iter().rev() {
            self.key_rot[k][d] = r;
        }
        for &(i, d, l, a, m) in self.undo.poses.iter().rev() {
            self.local[i][d] = l;
            self.local_aff[i][d] = a;
            self.model[i][d] = m;
        }
        self.undo.comps.clear();
        self.undo.key_rot.clear();
        self.undo.poses.clear();
    }

    /// The compressed clip of the current state.
    fn encode(&self, work: &Work) -> Option<Clip> {
        self.layout
            .encode(&self.bits, &self.qi, work, self.ctx.like)
    }
}

/// Step 3, first part, for one layout: the largest uniform budget, on a ladder of factors sqrt(2)
/// from `start`, whose a-priori bit widths ([`Layout::first_bits`]) measure within the limits;
/// returns the budget and the widths.
fn first_state(
    ctx: &Ctx,
    layout: &Layout,
    work: &Work,
    start: f32,
    compensate: bool,
) -> Option<(f32, Vec<u8>)> {
    let passes = |budget: f32| {
        let bits = layout.first_bits(budget);
        Eval::build(ctx, layout, work, bits.clone(), compensate, true)
            .1
            .then_some(bits)
    };
    let step = std::f32::consts::SQRT_2;
    let mut budget = start;
    let mut found = passes(budget);
    if found.is_some() {
        for _ in 0..16 {
            match passes(budget * step) {
                Some(f) => {
                    budget *= step;
                    found = Some(f);
                }
                None => break,
            }
        }
    } else {
        for _ in 0..40 {
            budget /= step;
            found = passes(budget);
            if found.is_some() {
                break;
            }
        }
    }
    found.map(|bits| (budget, bits))
}

/// Step 3, second part: rounds of one-bit reductions over every component of every segment. A
/// reduction is kept when the error it gives, as a fraction of the limit, is within the round's
/// threshold; thresholds rise over the first rounds ([`THRESHOLDS`]) so that the cheapest
/// reductions are taken first, then stay at 1 until no reduction is kept. A reduction that fails
/// at threshold 1 is not tried again (errors only grow as other widths shrink).
fn descend(eval: &mut Eval) {
    let nc = eval.layout.comps.len();
    let segs = eval.layout.seg_count;
    let mut blocked = vec![false; nc * segs];
    let mut round = 0;
    loop {
        let limit = THRESHOLDS.get(round).copied().unwrap_or(1.0);
        round += 1;
        let mut changed = false;
        for c in 0..nc {
            for s in 0..segs {
                let i = s * nc + c;
                let b = eval.bits[i];
                if b == 0 || blocked[i] {
                    continue;
                }
                if eval.set(s, c, b - 1, limit) <= limit {
                    changed = true;
                } else {
                    eval.undo();
                    blocked[i] = limit >= 1.0;
                }
            }
        }
        if !changed && round >= THRESHOLDS.len() {
            break;
        }
    }
}

/// The thresholds of the first rounds of [`descend`] (fractions of the joints' limits).
const THRESHOLDS: [f32; 4] = [0.5, 0.7, 0.85, 0.95];

/// Segment lengths tried for `n` keys: 16 and 32; up to [`SHORT_CLIP`] keys also 64 and the lengths
/// that split the keys into 1 to 4 segments of (nearly) equal size (segment headers weigh on short
/// clips; on long ones short segments follow the motion best).
fn segment_candidates(n: usize) -> Vec<usize> {
    let n = n.max(1);
    let short = n <= SHORT_CLIP;
    let mut out: Vec<usize> = [16, 32]
        .into_iter()
        .chain(short.then_some(64))
        .chain((1..=4).filter(|_| short).map(|k| n.div_ceil(k)))
        .map(|l| l.clamp(1, n))
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// Steps 1 to 5 of the module docs; `None` when nothing met the limits.
///
/// Every key-reduction budget of [`KEY_BUDGETS`] (giving distinct kept keys) and every segment length
/// of [`segment_candidates`] is quantized with its first bit widths; the [`DESCENDED`] smallest of
/// those (one for clips above [`LARGE_CLIP`]) are refined by [`descend`], and the smallest result
/// is kept (the first of equals). `compensate`: quantize rotations with chain compensation (only
/// when every scale of the source poses is positive and uniform).
fn compress_work(
    work: &mut Work,
    source: &Clip,
    rig: &Rig,
    tolerance: f32,
    bind_allowed: bool,
    options: &CompressOptions,
    compensate: bool,
) -> Option<Clip> {
    if work.times.is_empty() {
        return None;
    }
    let times = source.times();
    let ctx = Ctx::new(rig, source, times, tolerance);
    let compensate = compensate && ctx.uniform;
    let src = &ctx.src;
    simplify_channels(
        work,
        source,
        rig,
        src,
        times,
        tolerance * 0.25,
        bind_allowed,
    );
    let base = work.clone();
    let mut kept_sets: Vec<Vec<usize>> = Vec::new();
    let mut works: Vec<Work> = Vec::new();
    if options.key_reduction {
        for &frac in &KEY_BUDGETS {
            let kept = reduce_keys(&base, source, rig, src, tolerance * frac);
            if !kept_sets.contains(&kept) {
                let mut w = base.clone();
                w.keep(&kept);
                works.push(w);
                kept_sets.push(kept);
            }
        }
    } else {
        works.push(base);
    }
    let layouts: Vec<(usize, Layout)> = works
        .iter()
        .enumerate()
        .flat_map(|(wi, w)| {
            segment_candidates(w.times.len())
                .into_iter()
                .map(move |l| (wi, Layout::new(w, rig, l, compensate)))
        })
        .collect();
    // (size with the first bit widths, layout, bit widths)
    let mut firsts: Vec<(usize, usize, Vec<u8>)> = Vec::new();
    let mut start = tolerance;
    for (li, (wi, layout)) in layouts.iter().enumerate() {
        let w = &works[*wi];
        let Some((budget, bits)) = first_state(&ctx, layout, w, start, compensate) else {
            continue;
        };
        start = budget;
        let qi = Eval::new(&ctx, layout, w, bits.clone(), compensate).qi;
        let Some(c) = layout.encode(&bits, &qi, w, source) else {
            continue;
        };
        firsts.push((clip_record_size(&c), li, bits));
    }
    firsts.sort_by_key(|f| (f.0, f.1));
    let volume = times.len() * rig.skeleton.len();
    let descended = if volume <= LARGE_CLIP { DESCENDED } else { 1 };
    let mut best: Option<(usize, Clip)> = None;
    for (_, li, bits) in firsts.into_iter().take(descended) {
        let (wi, layout) = &layouts[li];
        let w = &works[*wi];
        let mut e = Eval::new(&ctx, layout, w, bits, compensate);
        let before = e.encode(w);
        descend(&mut e);
        for c in [e.encode(w), before].into_iter().flatten() {
            if !within(src, rig, &c, times, &ctx.limits) {
                continue;
            }
            let size = clip_record_size(&c);
            if best.as_ref().is_none_or(|b| size < b.0) {
                best = Some((size, c));
            }
            break;
        }
    }
    best.map(|b| b.1)
}

fn percentile(errors: &mut [f32], p: f32) -> f32 {
    if errors.is_empty() {
        return 0.0;
    }
    errors.sort_by(f32::total_cmp);
    let i = ((errors.len() as f32 * p).ceil() as usize).clamp(1, errors.len()) - 1;
    errors[i]
}

/// Compresses one clip within the tolerance (see the module docs) and reports what it reached.
///
/// `skeleton` gives the joint hierarchy for the error metric, the bind values for bind elision and the
/// extent for the default tolerance; without it every track is its own root and no channel is elided
/// to the bind value (except identity differences of an additive clip). When the compressed clip
/// would not be smaller than the plain one, the plain clip is returned (`report.compressed == false`).
pub fn compress_clip(
    clip: &Clip,
    skeleton: Option<&Skeleton>,
    options: &CompressOptions,
) -> (Clip, ClipCompressionReport) {
    let source = clip.to_plain();
    let extent = skeleton.map_or_else(|| clip_extent(&source), skeleton_extent);
    let tolerance = options
        .tolerance
        .filter(|t| t.is_finite() && *t > 0.0)
        .unwrap_or(DEFAULT_RELATIVE_TOLERANCE * extent);
    let distance = options
        .error_distance
        .filter(|t| t.is_finite() && *t >= 0.0)
        .unwrap_or(DEFAULT_RELATIVE_DISTANCE * extent);
    let rig = Rig::new(&source, skeleton, distance);
    let work = Work::from_plain(&source);
    let mut best: Option<Clip> = None;
    if let Some(rig) = rig {
        for compensate in [true, false] {
            best = compress_work(
                &mut work.clone(),
                &source,
                &rig,
                tolerance,
                skeleton.is_some(),
                options,
                compensate,
            );
            if best.is_some() {
                break;
            }
        }
    }
    let plain_bytes = clip_record_size(&source);
    let mut out = best.unwrap_or_else(|| source.clone());
    if clip_record_size(&out) >= plain_bytes {
        out = source.clone();
    }
    let compressed_bytes = clip_record_size(&out);
    let mut errors = measure(&source, &out, skeleton, distance);
    let max_error = errors.iter().copied().fold(0.0, f32::max);
    let p99_error = percentile(&mut errors, 0.99);
    let animated_joints = source
        .tracks()
        .iter()
        .filter(|t| {
            matches!(t.translation, Channel::Animated(_))
                || matches!(t.rotation, Channel::Animated(_))
                || matches!(t.scale, Channel::Animated(_))
        })
        .count();
    let samples = source.times().len();
    let raw_bytes = 40 * animated_joints * samples;
    let report = ClipCompressionReport {
        clip: clip.name().to_owned(),
        raw_bytes,
        plain_bytes,
        compressed_bytes,
        ratio: raw_bytes as f32 / compressed_bytes.max(1) as f32,
        max_error,
        p99_error,
        tolerance,
        error_distance: distance,
        animated_joints,
        samples,
        kept_keys: out.times().len(),
        bytes_per_joint_sample: compressed_bytes as f32 / (animated_joints * samples).max(1) as f32,
        compressed: out.is_compressed(),
    };
    (out, report)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use sinew_core::{Curve, JointDesc, TrackCurves};

    /// A chain of `n` joints, `bone` units apart along y.
    fn chain(n: usize, bone: f32) -> Skeleton {
        let joints = (0..n)
            .map(|i| JointDesc {
                name: format!("j{i}"),
                parent: i.checked_sub(1).map(|p| format!("j{p}")),
                bind_local: Transform::from_translation(Vec3::Y * if i == 0 { 0.0 } else { bone }),
                inverse_bind: None,
            })
            .collect();
        Skeleton::from_unordered(joints).unwrap().0
    }

    /// Every joint of `skeleton` swinging about a different axis, `keys` keys at 30 Hz.
    fn swing(skeleton: &Skeleton, keys: usize) -> Clip {
        let times: Vec<f32> = (0..keys).map(|k| k as f32 / 30.0).collect();
        let tracks = skeleton
            .names()
            .iter()
            .enumerate()
            .map(|(j, name)| {
                let axis = Vec3::new(1.0, j as f32 * 0.37, 0.5 - j as f32 * 0.11).normalize();
                let rotation = times
                    .iter()
                    .map(|t| Quat::from_axis_angle(axis, 0.6 * (t * (2.0 + j as f32 * 0.7)).sin()))
                    .collect();
                TrackCurves {
                    joint: name.clone(),
                    rotation: Curve::new(times.clone(), rotation),
                    ..Default::default()
                }
            })
            .collect();
        Clip::from_curves("swing", times[keys - 1], 30.0, false, false, tracks).unwrap()
    }

    fn compressed(clip: &Clip, skeleton: &Skeleton, tolerance: f32, compensate: bool) -> Clip {
        let source = clip.to_plain();
        let rig = Rig::new(&source, Some(skeleton), 0.1).unwrap();
        let mut work = Work::from_plain(&source);
        let options = CompressOptions {
            tolerance: Some(tolerance),
            error_distance: Some(0.1),
            key_reduction: true,
        };
        compress_work(
            &mut work, &source, &rig, tolerance, true, &options, compensate,
        )
        .unwrap()
    }

    #[test]
    fn chain_compensation_keeps_the_tolerance_and_saves_bits_on_a_long_chain() {
        let skeleton = chain(8, 0.3);
        let clip = swing(&skeleton, 61);
        let tolerance = 0.001;
        let with = compressed(&clip, &skeleton, tolerance, true);
        let without = compressed(&clip, &skeleton, tolerance, false);
        for c in [&with, &without] {
            assert!(c.is_compressed());
            let worst = measure(&clip, c, Some(&skeleton), 0.1)
                .into_iter()
                .fold(0.0f32, f32::max);
            assert!(worst <= tolerance, "error {worst} above {tolerance}");
        }
        let (a, b) = (clip_record_size(&with), clip_record_size(&without));
        assert!(a < b, "compensated {a} B, uncompensated {b} B");
    }

    #[test]
    fn mirrored_and_stretched_joints_stay_within_the_tolerance() {
        // Chain compensation assumes model rotations are products of local rotations; a mirrored
        // or non-uniformly scaled joint breaks that, and the clip must still compress correctly.
        for scale in [Vec3::new(-1.0, 1.0, 1.0), Vec3::new(1.0, 2.5, 0.7)] {
            let joints = (0..6)
                .map(|i: usize| JointDesc {
                    name: format!("j{i}"),
                    parent: i.checked_sub(1).map(|p| format!("j{p}")),
                    bind_local: Transform {
                        translation: Vec3::Y * if i == 0 { 0.0 } else { 0.3 },
                        rotation: Quat::IDENTITY,
                        scale: if i == 2 { scale } else { Vec3::ONE },
                    },
                    inverse_bind: None,
                })
                .collect();
            let skeleton = Skeleton::from_unordered(joints).unwrap().0;
            let clip = swing(&skeleton, 45);
            let (c, r) = compress_clip(&clip, Some(&skeleton), &CompressOptions::peers());
            assert!(c.is_compressed(), "{scale}: {r:?}");
            let worst = measure(&clip, &c, Some(&skeleton), 0.1)
                .into_iter()
                .fold(0.0f32, f32::max);
            assert!(worst <= 0.001, "{scale}: error {worst}");
            assert!(r.compressed_bytes < r.plain_bytes, "{scale}: {r:?}");
        }
    }

    #[test]
    fn incremental_state_matches_a_fresh_evaluation() {
        // After the descent (thousands of tentative changes and undos), the kept state must be what
        // quantizing from scratch with the final bit widths gives, bit for bit.
        let skeleton = chain(5, 0.4);
        let clip = swing(&skeleton, 40);
        let source = clip.to_plain();
        let rig = Rig::new(&source, Some(&skeleton), 0.1).unwrap();
        let work = Work::from_plain(&source);
        let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
        for compensate in [true, false] {
            let layout = Layout::new(&work, &rig, 16, compensate);
            let (_, bits) = first_state(&ctx, &layout, &work, 0.001, compensate).unwrap();
            let mut e = Eval::new(&ctx, &layout, &work, bits.clone(), compensate);
            descend(&mut e);
            assert!(
                e.bits.iter().zip(&bits).any(|(a, b)| a < b),
                "nothing descended"
            );
            let fresh = Eval::new(&ctx, &layout, &work, e.bits.clone(), compensate);
            assert_eq!(e.qi, fresh.qi);
            assert!(e.within() && fresh.within());
            for (m, f) in e.model.iter().zip(&fresh.model) {
                for (a, b) in m.iter().zip(f) {
                    assert!(a.abs_diff_eq(*b, 0.0), "{a:?} != {b:?}");
                }
            }
        }
    }

    #[test]
    fn rotations_keep_their_dropped_component_where_two_components_trade_places() {
        // About an axis near x, half angle from 36 to 56 degrees: x overtakes w as the largest
        // component near 46 degrees, which moves every stored component to another slot.
        let axis = Vec3::new(1.0, 0.0, 0.3).normalize();
        let v: Vec<Quat> = (0..=40)
            .map(|d| Quat::from_axis_angle(axis, (72.0 + d as f32).to_radians()))
            .collect();
        let split = split_rotations(&v);
        assert!(split.windows(2).all(|p| p[0].0 == p[1].0), "index changes");
        for (q, (i, c)) in v.iter().zip(&split) {
            assert!(q.to_array()[usize::from(*i)].abs() >= MIN_DROPPED);
            let back = raw_rotation(*i, *c).normalize();
            assert!(back.dot(*q).abs() > 0.999_999, "{q} {back}");
        }
        let range = |s: &[(u8, [f32; 3])]| {
            (0..3)
                .map(|a| {
                    let lo = s.iter().map(|x| x.1[a]).fold(f32::MAX, f32::min);
                    let hi = s.iter().map(|x| x.1[a]).fold(f32::MIN, f32::max);
                    hi - lo
                })
                .fold(0.0f32, f32::max)
        };
        let largest: Vec<(u8, [f32; 3])> = v.iter().map(|q| smallest_three(*q)).collect();
        // Largest-per-key: the first slot holds x (about 0.68) before the switch and y (0) after.
        assert!(largest.windows(2).any(|p| p[0].0 != p[1].0));
        assert!(range(&split) < 0.5 * range(&largest));
    }
}
