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
//! 2. Keys that linear interpolation between their neighbours reproduces within half the tolerance are
//!    dropped (whole keys, so the runtime still reads one record per key: time-major).
//! 3. Every remaining animated channel is quantized: rotations as the three smallest components plus a
//!    2-bit index, translations and scales as three components; each component is range-reduced over
//!    the clip and over segments of 16 keys, with a bit width per segment chosen from an error budget
//!    that accounts for how far the joint's descendants and its error points reach. The whole result
//!    is then measured; while the measured maximum exceeds the tolerance the budget shrinks and
//!    quantization is redone.
//!
//! Key times are kept as the source has them (no resampling), so every source key is honoured in time.

use sinew_core::clip::nlerp;
use sinew_core::compressed::{
    dequant_params, pack, smallest_three, QuantizedParts, SegmentComponent, MAX_BITS,
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
/// Keys per segment.
pub const SEGMENT_KEYS: u32 = 16;

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
        // Children come after parents: walk backwards, pushing reach up the chain.
        for j in (0..n).rev() {
            if let Some(p) = parents[j] {
                let p = p as usize;
                let d = (Vec3::from(m[j].translation) - Vec3::from(m[p].translation)).length();
                reach[p] = reach[p].max(reach[j] + d);
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
    let binding = ClipBinding::new(clip, &rig.skeleton);
    let mut sampler = Sampler::new();
    let defaults: Vec<Transform> = if clip.additive() {
        vec![Transform::IDENTITY; rig.skeleton.len()]
    } else {
        rig.skeleton.bind_local().to_vec()
    };
    let mut pose = defaults.clone();
    let (mut m, mut pts) = (Vec::new(), Vec::new());
    let mut worst = 0.0f32;
    for (k, &t) in times.iter().enumerate() {
        pose.copy_from_slice(&defaults);
        let _ = sampler.sample(clip, &binding, &rig.skeleton, t, &mut pose);
        rig.points_of(&pose, &mut m, &mut pts);
        for e in point_error(&src[k], &pts) {
            worst = worst.max(e);
        }
        if worst > limit {
            return worst;
        }
    }
    worst
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

    /// A plain clip with these values.
    fn plain(&self, like: &Clip) -> Option<Clip> {
        let mut o = 0;
        let tracks: Vec<Track> = self
            .tracks
            .iter()
            .map(|t| Track {
                joint: t.joint.clone(),
                translation: t.t.channel(&mut o, 3),
                rotation: t.r.channel(&mut o, 4),
                scale: t.s.channel(&mut o, 3),
            })
            .collect();
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

/// Step 3: quantization with a per-joint error budget `budget` (model units).
fn quantize(work: &Work, like: &Clip, rig: &Rig, budget: f32) -> Option<Clip> {
    let n = work.times.len();
    let seg_len = SEGMENT_KEYS as usize;
    // Components: (values per key, error per unit of value in model units, is rotation start).
    let mut comps: Vec<(Vec<f32>, f32)> = Vec::new();
    let mut starts: Vec<bool> = Vec::new();
    let mut index: Vec<Vec<u8>> = Vec::new(); // per rotation, per key
    for t in &work.tracks {
        let j = rig.skeleton.find(&t.joint).map_or(0, usize::from);
        let reach = rig.reach.get(j).copied().unwrap_or(1.0);
        let ps = rig.parent_scale.get(j).copied().unwrap_or(1.0);
        if let WChan::Keys(v) = &t.t {
            for i in 0..3 {
                comps.push((v.iter().map(|x| x[i]).collect(), ps * 1.8));
                starts.push(false);
            }
        }
        if let WChan::Keys(v) = &t.r {
            let split: Vec<(u8, [f32; 3])> = v.iter().map(|q| smallest_three(*q)).collect();
            index.push(split.iter().map(|s| s.0).collect());
            for i in 0..3 {
                comps.push((split.iter().map(|s| s.1[i]).collect(), 4.0 * reach));
                starts.push(i == 0);
            }
        }
        if let WChan::Keys(v) = &t.s {
            for i in 0..3 {
                comps.push((v.iter().map(|x| x[i]).collect(), ps * reach * 1.8));
                starts.push(false);
            }
        }
    }
    let nc = comps.len();
    let seg_count = n.div_ceil(seg_len);
    let mut ranges = Vec::with_capacity(nc);
    let mut segments = vec![SegmentComponent::default(); seg_count * nc];
    let mut q = vec![0u32; n * nc];
    for (c, (vals, gain)) in comps.iter().enumerate() {
        let lo = vals.iter().copied().fold(f32::MAX, f32::min);
        let hi = vals.iter().copied().fold(f32::MIN, f32::max);
        let (lo, ext) = if n == 0 {
            (0.0, 0.0)
        } else {
            (lo, (hi - lo).max(0.0))
        };
        let range = [lo, ext];
        ranges.push(range);
        let allowed = budget / gain.max(1e-12);
        for s in 0..seg_count {
            let keys = &vals[s * seg_len..((s + 1) * seg_len).min(n)];
            let smin = keys.iter().copied().fold(f32::MAX, f32::min);
            let smax = keys.iter().copied().fold(f32::MIN, f32::max);
            let mut e = SegmentComponent::default();
            if ext > 0.0 {
                let a = (((smin - lo) / ext) * 255.0).floor().clamp(0.0, 255.0) as u8;
                e.min = a;
                let mut b =
                    ((((smax - lo) / ext) * 255.0).ceil() as i32 - i32::from(a)).clamp(0, 255);
                loop {
                    e.extent = b as u8;
                    let (_, seg_lo) = dequant_params(range, SegmentComponent { bits: 1, ..e });
                    let seg_ext = ext * (f32::from(e.extent) / 255.0);
                    if seg_lo + seg_ext >= smax || b >= 255 - i32::from(a) {
                        break;
                    }
                    b += 1;
                }
                let seg_ext = ext * (f32::from(e.extent) / 255.0);
                // Max error of `bits` bits: seg_ext / (2^bits - 1) / 2; zero bits: seg_ext / 2.
                let mut bits = 0u8;
                while bits < MAX_BITS {
                    let err = if bits == 0 {
                        seg_ext * 0.5
                    } else {
                        seg_ext / ((1u32 << bits) - 1) as f32 * 0.5
                    };
                    if err <= allowed {
                        break;
                    }
                    bits += 1;
                }
                e.bits = bits;
            }
            segments[s * nc + c] = e;
            let (scale, bias) = dequant_params(range, e);
            let top = ((1u64 << e.bits) - 1) as f32;
            for (k, v) in keys.iter().enumerate() {
                let x = if scale > 0.0 {
                    ((v - bias) / scale).round().clamp(0.0, top)
                } else {
                    0.0
                };
                q[(s * seg_len + k) * nc + c] = x as u32;
            }
        }
    }
    let rotations = index.len();
    let mut idx = vec![0u8; n * rotations];
    for (r, list) in index.iter().enumerate() {
        for (k, &i) in list.iter().enumerate() {
            idx[k * rotations + r] = i;
        }
    }
    let data = pack(n, seg_len, &segments, &starts, &q, &idx);
    let mut o = 0;
    let tracks: Vec<Track> = work
        .tracks
        .iter()
        .map(|t| Track {
            joint: t.joint.clone(),
            translation: t.t.channel(&mut o, 3),
            rotation: t.r.channel(&mut o, 3),
            scale: t.s.channel(&mut o, 3),
        })
        .collect();
    Clip::from_quantized(
        like.name().to_owned(),
        like.duration(),
        like.sample_rate(),
        like.looping(),
        like.additive(),
        work.times.clone(),
        tracks,
        QuantizedParts {
            segment_len: SEGMENT_KEYS,
            ranges,
            segments,
            data,
        },
    )
    .ok()
}

/// Steps 1 to 3 of the module docs; `None` when no budget met the tolerance.
fn compress_work(
    work: &mut Work,
    source: &Clip,
    rig: &Rig,
    times: &[f32],
    tolerance: f32,
    bind_allowed: bool,
    options: &CompressOptions,
) -> Option<Clip> {
    let src = rig.all_points(&rig.poses(source, times));
    simplify_channels(
        work,
        source,
        rig,
        &src,
        times,
        tolerance * 0.25,
        bind_allowed,
    );
    if options.key_reduction {
        let kept = reduce_keys(work, source, rig, &src, tolerance * 0.5);
        work.keep(&kept);
    }
    let mut budget = tolerance;
    for _ in 0..24 {
        if let Some(c) = quantize(work, source, rig, budget) {
            if max_error_of(&src, rig, &c, times, tolerance) <= tolerance {
                return Some(c);
            }
        }
        budget *= 0.75;
    }
    None
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
    let times = source.times().to_vec();
    let rig = Rig::new(&source, skeleton, distance);
    let mut work = Work::from_plain(&source);
    let mut best: Option<Clip> = None;
    if let Some(rig) = rig {
        best = compress_work(
            &mut work,
            &source,
            &rig,
            &times,
            tolerance,
            skeleton.is_some(),
            options,
        );
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
