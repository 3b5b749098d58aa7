//! Key reduction: constant channels and keys that interpolation reproduces are dropped.

use super::metric::{point_error, rebase_on, Rig};
use rayon::prelude::*;
use sinew_core::clip::nlerp;
use sinew_core::glam::{Affine3A, Quat, Vec3};
use sinew_core::{Channel, Clip, Track, Transform};
use std::borrow::Cow;

/// A clip's channel values per key, ready to rebuild clips from.
#[derive(Clone)]
pub(super) struct Work {
    pub(super) times: Vec<f32>,
    pub(super) tracks: Vec<WTrack>,
}

#[derive(Clone)]
pub(super) struct WTrack {
    pub(super) joint: String,
    pub(super) t: WChan<Vec3>,
    pub(super) r: WChan<Quat>,
    pub(super) s: WChan<Vec3>,
}

impl WTrack {
    /// A track of no joint with every channel at its bind value: a candidate for one channel.
    fn unbound() -> WTrack {
        WTrack {
            joint: String::new(),
            t: WChan::Bind,
            r: WChan::Bind,
            s: WChan::Bind,
        }
    }

    /// Channel `ch` (0 translation, 1 rotation, 2 scale) replaced by `from`'s.
    fn take_channel(&mut self, ch: usize, from: WTrack) {
        match ch {
            0 => self.t = from.t,
            1 => self.r = from.r,
            _ => self.s = from.s,
        }
    }
}

#[derive(Clone)]
pub(super) enum WChan<T> {
    Bind,
    Constant(T),
    Keys(Vec<T>),
}

impl<T: Copy> WChan<T> {
    pub(super) fn channel(&self, o: &mut u32, n: u32) -> Channel<T> {
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
    pub(super) fn from_plain(p: &Clip) -> Work {
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
    pub(super) fn clip_tracks(&self, rotation_components: u32) -> (Vec<Track>, u32) {
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
    pub(super) fn plain(&self, like: &Clip) -> Option<Clip> {
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

    pub(super) fn keep(&mut self, keys: &[usize]) {
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

pub(super) fn mid3(v: &[Vec3]) -> Vec3 {
    let (lo, hi) = v.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(a, b), x| (a.min(*x), b.max(*x)),
    );
    (lo + hi) * 0.5
}

pub(super) fn mean_quat(v: &[Quat]) -> Quat {
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
///
/// Channels are tried one at a time, in track order, each against the work as it stands (with the
/// channels accepted so far); a candidate is accepted when no joint's error exceeds `budget`.
/// Only the tried joint and its descendants move, and every other joint's error is that of the
/// work, which is within the budget (accepted before, or the source itself): so a candidate is
/// measured on that subtree alone, with the work's poses and model transforms at every source time
/// kept up to date instead of re-sampling whole clips. The tried joint's local pose is the one the
/// runtime sampler gives for its track alone (lanes are independent), so the decisions are those of
/// measuring whole clips.
///
/// `poses`: the work's poses at `src_times` when they are known already (the work as
/// [`Work::from_plain`] gives it for the clip they were sampled from: the same values at the same
/// times, so the same poses); else they are sampled here. Returns the simplified work's poses at
/// `src_times` (`None` when the work makes no clip).
#[allow(clippy::too_many_arguments)]
pub(super) fn simplify_channels<'p>(
    work: &mut Work,
    like: &Clip,
    rig: &Rig,
    src: &[Vec<[Vec3; 3]>],
    origins: &[Vec3],
    src_times: &[f32],
    poses: Option<&'p [Vec<Transform>]>,
    budget: f32,
    bind_allowed: bool,
) -> Option<Cow<'p, [Vec<Transform>]>> {
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
    let local = match poses {
        Some(poses) => Cow::Borrowed(poses),
        None => match work.plain(like) {
            Some(plain) => Cow::Owned(rig.poses(&plain, src_times)),
            None => return None,
        },
    };
    let mut state = SubtreeState::new(rig, local, origins, like.additive());
    #[allow(clippy::needless_range_loop)] // `work` is replaced inside the loop
    for i in 0..work.tracks.len() {
        let Some(joint) = rig.skeleton.find(&work.tracks[i].joint).map(usize::from) else {
            continue;
        };
        for ch in 0..3 {
            // Each candidate holds channel `ch` alone (the others Bind, never read): the track's
            // keys are not copied for each try (a long clip's are tens of kilobytes per channel).
            let mut candidates: Vec<WTrack> = Vec::new();
            let tr = &work.tracks[i];
            let mut with = |f: &dyn Fn(&mut WTrack)| {
                let mut t = WTrack::unbound();
                f(&mut t);
                candidates.push(t);
            };
            let d = defaults[i];
            // A channel the source already holds constant becomes the bind value when that
            // reproduces it (sources often key every joint, most at its rest value): a bind
            // channel costs nothing beyond its track's kind byte, a constant 12 or 16 bytes.
            // The bind value itself (or the same rotation, negated) changes nothing and needs
            // no measurement, nor any update of the state, which on files that key every channel
            // is most of them.
            let mut exact: Option<WTrack> = None;
            match ch {
                0 if matches!(tr.t, WChan::Constant(_)) && d.is_some() => {
                    if let (WChan::Constant(v), Some(d)) = (&tr.t, d) {
                        if *v == d.translation {
                            let mut t = WTrack::unbound();
                            t.t = WChan::Bind;
                            exact = Some(t);
                        }
                    }
                    with(&|t: &mut WTrack| t.t = WChan::Bind);
                }
                1 if matches!(tr.r, WChan::Constant(_)) && d.is_some() => {
                    if let (WChan::Constant(q), Some(d)) = (&tr.r, d) {
                        if *q == d.rotation || -*q == d.rotation {
                            let mut t = WTrack::unbound();
                            t.r = WChan::Bind;
                            exact = Some(t);
                        }
                    }
                    with(&|t: &mut WTrack| t.r = WChan::Bind);
                }
                2 if matches!(tr.s, WChan::Constant(_)) && d.is_some() => {
                    if let (WChan::Constant(v), Some(d)) = (&tr.s, d) {
                        if *v == d.scale {
                            let mut t = WTrack::unbound();
                            t.s = WChan::Bind;
                            exact = Some(t);
                        }
                    }
                    with(&|t: &mut WTrack| t.s = WChan::Bind);
                }
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
            if let Some(t) = exact {
                // The same value (a rotation possibly negated, which gives the same matrix, bit
                // for bit: its entries are products of two components): every local and model
                // transform of the state stays as it is.
                work.tracks[i].take_channel(ch, t);
                continue;
            }
            for t in candidates {
                let Some(value) = Replacement::of(ch, &t, state.defaults[joint]) else {
                    continue;
                };
                if state.try_channel(rig, src, joint, value, budget) {
                    work.tracks[i].take_channel(ch, t);
                    break;
                }
            }
        }
    }
    Some(state.local)
}

/// The work's local poses and model transforms at every source time (time-major, one per rig
/// joint), as the runtime sampler and [`super::metric`]'s forward kinematics give them, kept up to
/// date as [`simplify_channels`] replaces tracks.
struct SubtreeState<'a, 'p> {
    /// Borrowed until a channel is replaced (most clips' channels are kept as they are).
    local: Cow<'p, [Vec<Transform>]>,
    /// Worked out at the first try (the channels the source holds at their bind values need
    /// none), the anchors rebased on `origins` ([`Rig::rebase`]).
    model: Option<Vec<Vec<Affine3A>>>,
    /// Per source time, per anchor: the origin the error points are about.
    origins: &'a [Vec3],
    /// Per joint: itself, then its descendants in skeleton order (the rig's).
    subtree: &'a [Vec<usize>],
    defaults: Vec<Transform>,
}

impl<'a, 'p> SubtreeState<'a, 'p> {
    /// The state of the work whose poses at the source times are `local` (`additive`: the
    /// clip's kind).
    fn new(
        rig: &'a Rig,
        local: Cow<'p, [Vec<Transform>]>,
        origins: &'a [Vec3],
        additive: bool,
    ) -> Self {
        let nj = rig.skeleton.len();
        let defaults = if additive {
            vec![Transform::IDENTITY; nj]
        } else {
            rig.skeleton.bind_local().to_vec()
        };
        SubtreeState {
            local,
            model: None,
            origins,
            subtree: &rig.subtree,
            defaults,
        }
    }

    /// Whether the work's track for `joint` with one channel replaced by a value held at every time
    /// (`value`: a constant, or the bind value) keeps every error of the joint's subtree within
    /// `budget`; if so the state takes it. The joint's local pose at each time is the state's with
    /// that channel replaced: what the runtime sampler gives for the track so changed, bit for bit
    /// (it copies a channel that is not animated, and computes each channel on its own).
    fn try_channel(
        &mut self,
        rig: &Rig,
        src: &[Vec<[Vec3; 3]>],
        joint: usize,
        value: Replacement,
        budget: f32,
    ) -> bool {
        if !value.is_finite() {
            return false;
        }
        let models = self
            .model
            .get_or_insert_with(|| models_of(rig, &self.local, self.origins));
        let parents = rig.skeleton.parents();
        let sub = &self.subtree[joint];
        let mut at = vec![0usize; rig.skeleton.len()];
        for (n, &d) in sub.iter().enumerate() {
            at[d] = n;
        }
        // Per time, the subtree's new model transforms (in `sub` order).
        let mut new_model: Vec<Affine3A> = Vec::with_capacity(self.local.len() * sub.len());
        for (k, ((local, model), src_k)) in
            self.local.iter().zip(models.iter()).zip(src).enumerate()
        {
            let base = new_model.len();
            let origins = rig.origins_at(self.origins, k);
            for (n, &d) in sub.iter().enumerate() {
                let a = if n == 0 {
                    value.applied(local[d]).to_affine()
                } else {
                    local[d].to_affine()
                };
                let mut m = match parents.get(d).copied().flatten().map(usize::from) {
                    Some(p) if n > 0 => new_model[base + at[p]] * a,
                    Some(p) => model[p] * a,
                    None => a,
                };
                rig.rebase(d, origins, &mut m);
                new_model.push(m);
                let pts = rig.points[d].map(|x| m.transform_point3(x));
                let e =
                    point_error(&src_k[d..=d], std::slice::from_ref(&pts)).fold(0.0f32, f32::max);
                if e > budget {
                    return false;
                }
            }
        }
        for ((local, model), new) in self
            .local
            .to_mut()
            .iter_mut()
            .zip(models)
            .zip(new_model.chunks_exact(sub.len()))
        {
            local[joint] = value.applied(local[joint]);
            for (&d, &m) in sub.iter().zip(new) {
                model[d] = m;
            }
        }
        true
    }
}

/// The model transforms of `local`'s poses, the anchors rebased on `origins` (forward kinematics at
/// every time, [`Rig::rebased_fk`]; a long clip's times side by side, each computed alone: the
/// same values either way).
fn models_of(rig: &Rig, local: &[Vec<Transform>], origins: &[Vec3]) -> Vec<Vec<Affine3A>> {
    let model_of = |m: &mut Vec<Affine3A>, (k, p): (usize, &Vec<Transform>)| {
        rig.rebased_fk(p, rig.origins_at(origins, k), m);
        m.clone()
    };
    if rig.side_by_side(local.len()) {
        local
            .par_iter()
            .enumerate()
            .map_init(Vec::new, model_of)
            .collect()
    } else {
        let mut m = Vec::new();
        local
            .iter()
            .enumerate()
            .map(|p| model_of(&mut m, p))
            .collect()
    }
}

/// One channel's value at every time, for [`SubtreeState::try_channel`].
#[derive(Clone, Copy)]
pub(super) enum Replacement {
    T(Vec3),
    R(Quat),
    S(Vec3),
}

impl Replacement {
    /// Channel `ch` (0 translation, 1 rotation, 2 scale) of `track`, replaced by a constant or
    /// the bind value (`bind`: the joint's bind pose, as the runtime sampler has it); `None` for
    /// keys.
    pub(super) fn of(ch: usize, track: &WTrack, bind: Transform) -> Option<Replacement> {
        let v3 = |c: &WChan<Vec3>, b: Vec3| match c {
            WChan::Bind => Some(b),
            WChan::Constant(v) => Some(*v),
            WChan::Keys(_) => None,
        };
        match ch {
            0 => v3(&track.t, bind.translation).map(Replacement::T),
            1 => match &track.r {
                WChan::Bind => Some(Replacement::R(bind.rotation)),
                WChan::Constant(q) => Some(Replacement::R(*q)),
                WChan::Keys(_) => None,
            },
            _ => v3(&track.s, bind.scale).map(Replacement::S),
        }
    }

    /// Whether the value is finite (a clip holds only finite constants).
    fn is_finite(self) -> bool {
        match self {
            Replacement::T(v) | Replacement::S(v) => v.is_finite(),
            Replacement::R(q) => q.is_finite(),
        }
    }

    /// `local` with this channel replaced.
    pub(super) fn applied(self, mut local: Transform) -> Transform {
        match self {
            Replacement::T(v) => local.translation = v,
            Replacement::R(q) => local.rotation = q,
            Replacement::S(v) => local.scale = v,
        }
        local
    }
}

/// Step 2: greedy key reduction. Returns the kept key indices. `known`: the work's poses at its
/// key times when they are known already (sampled once for several budgets); else they are
/// sampled here.
pub(super) fn reduce_keys(
    work: &Work,
    like: &Clip,
    rig: &Rig,
    src: &[Vec<[Vec3; 3]>],
    origins: &[Vec3],
    known: Option<&[Vec<Transform>]>,
    budget: f32,
) -> Vec<usize> {
    let n = work.times.len();
    if let Some(poses) = known.filter(|p| p.len() == n) {
        return reduce_posed(&work.times, poses, rig, src, origins, budget);
    }
    if n <= 2 {
        return (0..n).collect();
    }
    let Some(plain) = work.plain(like) else {
        return (0..n).collect();
    };
    reduce_posed(
        &work.times,
        &rig.poses(&plain, &work.times),
        rig,
        src,
        origins,
        budget,
    )
}

/// [`reduce_keys`] of a work whose poses at its key times (`times`) are `poses`.
fn reduce_posed(
    times: &[f32],
    poses: &[Vec<Transform>],
    rig: &Rig,
    src: &[Vec<[Vec3; 3]>],
    origins: &[Vec3],
    budget: f32,
) -> Vec<usize> {
    let n = times.len();
    if n <= 2 || poses.len() != n {
        return (0..n).collect();
    }
    let parents = rig.skeleton.parents();
    let mut m: Vec<Affine3A> = Vec::new();
    // Whether interpolating between keys `a` and `b` keeps every time between them within the
    // budget. Joint by joint, parents first (the forward kinematics and points of
    // [`Rig::points_of`], the errors of [`point_error`]), stopping at the first joint over it.
    let ok = |a: usize, b: usize| -> bool {
        let (ta, tb) = (times[a], times[b]);
        for (k, src_k) in src.iter().enumerate().take(b).skip(a + 1) {
            let x = (times[k] - ta) / (tb - ta);
            m.clear();
            for (j, ((p, q), (src_j, at))) in poses[a]
                .iter()
                .zip(&poses[b])
                .zip(src_k.iter().zip(&rig.points))
                .enumerate()
            {
                let local = Transform {
                    translation: p.translation.lerp(q.translation, x),
                    rotation: nlerp(p.rotation, q.rotation, x),
                    scale: p.scale.lerp(q.scale, x),
                }
                .to_affine();
                let mut model = match parents.get(j).copied().flatten() {
                    Some(p) => m.get(p as usize).copied().unwrap_or(Affine3A::IDENTITY) * local,
                    None => local,
                };
                if let Some(slot) = rig.anchor_of(j) {
                    rebase_on(&mut model, rig.origins_at(origins, k), slot);
                }
                m.push(model);
                let pts = at.map(|x| model.transform_point3(x));
                if point_error(std::slice::from_ref(src_j), std::slice::from_ref(&pts))
                    .any(|e| e > budget)
                {
                    return false;
                }
            }
        }
        true
    };
    greedy_keys(n, ok)
}

/// The keys kept by extending each span from the last kept key while `ok(first, last)` holds
/// (at most 128 keys a span): the greedy part of [`reduce_keys`].
pub(super) fn greedy_keys(n: usize, mut ok: impl FnMut(usize, usize) -> bool) -> Vec<usize> {
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
