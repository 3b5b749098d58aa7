//! Incremental error evaluation of a quantisation while its bit widths change.

use super::metric::{exceeds, joint_limits, subtrees, Rig};
use super::quantize::{locate, raw_rotation, Kind, Layout, Quant};
use super::reduce::{WChan, Work};
use sinew_core::clip::{nlerp, normalize_rotation};
use sinew_core::compressed::three_without;
use sinew_core::glam::{Affine3A, Quat, Vec3};
use sinew_core::{Clip, Transform};

/// What every quantization of one clip is measured against.
pub(super) struct Ctx<'a> {
    pub(super) rig: &'a Rig,
    pub(super) like: &'a Clip,
    /// Source key times.
    pub(super) times: &'a [f32],
    /// Per source time, per joint: the source's error points.
    pub(super) src: Vec<Vec<[Vec3; 3]>>,
    /// `src` flattened (time-major, `nj` joints per time): what [`Eval`] reads in its loops.
    pub(super) src_flat: Vec<[Vec3; 3]>,
    /// Per source time, per joint (time-major): the source's model-space rotation (the product of
    /// the local rotations down the chain).
    pub(super) src_rot: Vec<Quat>,
    /// Per joint: the largest error allowed.
    pub(super) limits: Vec<f32>,
    /// Every scale of the source poses is positive and uniform, so that model-space rotations are
    /// the products of the local rotations (what chain compensation relies on).
    pub(super) uniform: bool,
}

impl<'a> Ctx<'a> {
    pub(super) fn new(rig: &'a Rig, like: &'a Clip, times: &'a [f32], tolerance: f32) -> Ctx<'a> {
        let poses = rig.poses(like, times);
        let src = rig.all_points(&poses);
        let parents = rig.skeleton.parents();
        let src_rot = poses
            .iter()
            .flat_map(|pose| {
                let mut out: Vec<Quat> = Vec::with_capacity(pose.len());
                for (j, t) in pose.iter().enumerate() {
                    let p = parents.get(j).copied().flatten().map(usize::from);
                    let pr = p.and_then(|p| out.get(p).copied());
                    out.push(pr.map_or(t.rotation, |pr| pr * t.rotation));
                }
                out
            })
            .collect();
        let src_flat = src.iter().flatten().copied().collect();
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
            src_flat,
            src_rot,
            limits,
            uniform,
        }
    }
}

/// Undo records of one tentative change of [`Eval`].
#[derive(Default)]
pub(super) struct Undo {
    pub(super) bits: Option<(usize, u8)>,
    pub(super) comps: Vec<(usize, usize, u32, f32)>,
    pub(super) key_rot: Vec<(usize, usize, Quat)>,
    pub(super) raw: Vec<(usize, usize, Quat)>,
    pub(super) poses: Vec<(usize, usize, Affine3A, Affine3A)>,
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
pub(super) struct Eval<'a> {
    pub(super) ctx: &'a Ctx<'a>,
    pub(super) layout: &'a Layout,
    pub(super) compensate: bool,
    /// Per source time: the keys and blend factor the sampler uses.
    pub(super) at: Vec<(usize, usize, f32)>,
    /// Per key: its source time.
    pub(super) key_src: Vec<Option<usize>>,
    /// Per track: its joint. Per joint: its track.
    pub(super) joint: Vec<usize>,
    pub(super) track_of: Vec<Option<usize>>,
    /// Per track and channel kind (T, R, S): the first component, if quantized.
    pub(super) first: Vec<[Option<usize>; 3]>,
    /// Per joint: itself, then its descendants in skeleton order.
    pub(super) subtree: Vec<Vec<usize>>,
    /// Per joint: its local transform where the clip does not animate it.
    pub(super) base: Vec<Transform>,
    /// Per segment, per component: bit width, and the quantization parameters it gives.
    pub(super) bits: Vec<u8>,
    pub(super) params: Vec<Quant>,
    /// Per component, per key: the stored integer and the value it decodes to.
    pub(super) qi: Vec<Vec<u32>>,
    pub(super) dec: Vec<Vec<f32>>,
    /// Per rotation, per key: the rotation the decoder rebuilds from the stored components, before
    /// normalisation (what the sampler interpolates).
    pub(super) raw: Vec<Vec<Quat>>,
    /// Joint count (the stride of the per-time and per-key arrays below), and per joint its parent.
    pub(super) nj: usize,
    pub(super) parents: Vec<Option<usize>>,
    /// Per key, per joint (key-major): the quantized clip's model rotation at that key.
    pub(super) key_rot: Vec<Quat>,
    /// Per source time, per joint (time-major): the quantized clip's local pose as an affine
    /// transform (the pose itself is `base` with the sampled channels, recomputed when needed),
    /// and its model transform.
    pub(super) local_aff: Vec<Affine3A>,
    pub(super) model: Vec<Affine3A>,
    /// Per segment: the source times that read one of its keys.
    pub(super) seg_times: Vec<Vec<usize>>,
    pub(super) undo: Undo,
    /// Per joint, during a change: its stored values changed / its model transforms changed.
    pub(super) dirty: Vec<bool>,
    pub(super) moved: Vec<bool>,
    /// Scratch of [`Eval::set`]: per source time and joint of the change, measured already.
    pub(super) seen: Vec<bool>,
}

impl<'a> Eval<'a> {
    /// The state of `work` quantized with `bits`. With `check`, also whether every joint is within
    /// its limit at every source time; the poses are then computed only up to the first time that
    /// is not (the state is for the check alone).
    pub(super) fn build(
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
        let subtree = subtrees(parents);
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
            local_aff: vec![Affine3A::IDENTITY; nj * at.len()],
            model: vec![Affine3A::IDENTITY; nj * at.len()],
            nj,
            parents: (0..nj)
                .map(|j| parents.get(j).copied().flatten().map(usize::from))
                .collect(),
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
            raw: vec![vec![Quat::IDENTITY; n]; layout.index.len()],
            key_rot: vec![Quat::IDENTITY; nj * n],
            seg_times,
            undo: Undo::default(),
            seen: Vec::new(),
        };
        let all: Vec<usize> = (0..nj).collect();
        e.dirty.fill(true);
        e.moved.fill(true);
        // Keys are quantized as the source times reach them (a check that fails early leaves the
        // rest undone); every key is quantized in key order, as a whole pass would.
        let seg_len = layout.seg_len.max(1);
        let mut next = 0;
        for i in 0..e.at.len() {
            let (k0, k1, a) = e.at[i];
            let need = if a != 0.0 { k0.max(k1) } else { k0 } + 1;
            while next < need.min(n) {
                e.requantize_key(next / seg_len, next, &all, None, false);
                next += 1;
            }
            e.resample(i, &all, false);
            if check && (0..nj).any(|j| exceeds(e.joint_error(i, j), e.ctx.limits[j])) {
                return (e, false);
            }
        }
        while next < n {
            e.requantize_key(next / seg_len, next, &all, None, false);
            next += 1;
        }
        (e, true)
    }

    /// [`Eval::build`] without the check.
    pub(super) fn new(
        ctx: &'a Ctx<'a>,
        layout: &'a Layout,
        work: &Work,
        bits: Vec<u8>,
        compensate: bool,
    ) -> Eval<'a> {
        Eval::build(ctx, layout, work, bits, compensate, false).0
    }

    pub(super) fn parent(&self, j: usize) -> Option<usize> {
        self.parents.get(j).copied().flatten()
    }

    /// Quantizes key `k` of segment `s` for `joints` (a joint's subtree, or all joints, in
    /// skeleton order). `changed`: the component (of the first joint) whose bit width changed, so
    /// that only what depends on it is redone; `None` redoes everything. Sets `dirty`, and records
    /// undo information when `record`.
    /// Keys of a segment are done in order; `dirty` is only ever set here, the caller clears it.
    pub(super) fn requantize_key(
        &mut self,
        s: usize,
        k: usize,
        joints: &[usize],
        changed: Option<usize>,
        record: bool,
    ) {
        let nc = self.layout.comps.len();
        if let Some(c) = changed.filter(|&c| self.layout.comps[c].kind != Kind::R) {
            // A translation or scale component: nothing else depends on it.
            if let Some(&j) = joints.first() {
                let v = self.layout.comps[c].vals[k];
                self.dirty[j] |= self.store(s, c, k, v, record, nc);
            }
            return;
        }
        for (n, &d) in joints.iter().enumerate() {
            if changed.is_some() && n > 0 && !self.compensate {
                break;
            }
            let pr = self
                .parent(d)
                .map_or(Quat::IDENTITY, |p| self.key_rot[k * self.nj + p]);
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
                    let ri = comp.rot;
                    let index = self.layout.index[ri][k];
                    let vals = match self.key_src[k] {
                        Some(i) if self.compensate => {
                            let target =
                                (pr.inverse() * self.ctx.src_rot[i * self.nj + d]).normalize();
                            three_without(target, index)
                        }
                        _ => [0, 1, 2].map(|a| self.layout.comps[c0 + a].vals[k]),
                    };
                    for (a, v) in vals.into_iter().enumerate() {
                        rot_changed |= self.store(s, c0 + a, k, v, record, nc);
                    }
                    self.dirty[d] |= rot_changed;
                    let q = [0, 1, 2].map(|a| self.dec[c0 + a][k]);
                    let raw = raw_rotation(index, q);
                    if record {
                        self.undo.raw.push((ri, k, self.raw[ri][k]));
                    }
                    self.raw[ri][k] = raw;
                    rot = normalize_rotation(raw);
                }
            }
            if changed.is_some() && n == 0 && !rot_changed {
                // The joint's rotation at this key did not change: nothing below it does.
                break;
            }
            if record {
                self.undo
                    .key_rot
                    .push((k, d, self.key_rot[k * self.nj + d]));
            }
            self.key_rot[k * self.nj + d] = pr * rot;
        }
    }

    /// Quantizes `v` as component `c` of key `k` (in segment `s`); returns whether the stored
    /// value changed.
    pub(super) fn store(
        &mut self,
        s: usize,
        c: usize,
        k: usize,
        v: f32,
        record: bool,
        nc: usize,
    ) -> bool {
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
    pub(super) fn resample(&mut self, i: usize, joints: &[usize], record: bool) {
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
                    self.local_aff[i * self.nj + d],
                    self.model[i * self.nj + d],
                ));
            }
            if self.dirty[d] {
                let local = match self.track_of[d] {
                    Some(tr) => self.sampled(tr, i, self.base[d]),
                    None => self.base[d],
                };
                self.local_aff[i * self.nj + d] = local.to_affine();
            }
            let pm = parent.map_or(Affine3A::IDENTITY, |p| self.model[i * self.nj + p]);
            self.model[i * self.nj + d] = pm * self.local_aff[i * self.nj + d];
        }
    }

    pub(super) fn vec3(&self, c: usize, k: usize) -> Vec3 {
        Vec3::new(self.dec[c][k], self.dec[c + 1][k], self.dec[c + 2][k])
    }

    pub(super) fn quat(&self, c: usize, k: usize) -> Quat {
        self.raw[self.layout.comps[c].rot][k]
    }

    /// Track `tr`'s local transform at source time `i` (animated channels replaced in `base`), as
    /// the sampler computes it.
    pub(super) fn sampled(&self, tr: usize, i: usize, mut base: Transform) -> Transform {
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

    pub(super) fn joint_error(&self, i: usize, j: usize) -> f32 {
        let m = &self.model[i * self.nj + j];
        let p = &self.ctx.rig.points[j];
        let s = &self.ctx.src_flat[i * self.nj + j];
        (0..3)
            .map(|x| m.transform_point3(p[x]).distance(s[x]))
            .fold(0.0f32, f32::max)
    }

    /// True when every joint is within its limit at every source time.
    #[cfg(test)]
    pub(super) fn within(&self) -> bool {
        (0..self.at.len()).all(|i| {
            (0..self.ctx.limits.len()).all(|j| self.joint_error(i, j) <= self.ctx.limits[j])
        })
    }

    /// Sets component `c` of segment `s` to `bits` (tentatively: [`Eval::undo`] reverts it) and
    /// returns the largest ratio of error to limit over the joints and times that changed. As soon
    /// as one ratio exceeds `cap` it stops and returns infinity, leaving a state that only
    /// [`Eval::undo`] may follow.
    pub(super) fn set(&mut self, s: usize, c: usize, bits: u8, cap: f32) -> f32 {
        let nc = self.layout.comps.len();
        self.undo.comps.clear();
        self.undo.key_rot.clear();
        self.undo.raw.clear();
        self.undo.poses.clear();
        self.undo.bits = Some((s * nc + c, self.bits[s * nc + c]));
        self.bits[s * nc + c] = bits;
        self.params[s * nc + c] = self.layout.params(s, c, bits);
        let j = self.joint[self.layout.comps[c].track];
        let joints = std::mem::take(&mut self.subtree[j]);
        let times = std::mem::take(&mut self.seg_times[s]);
        let worst = self.measure_change(s, c, &joints, &times, cap);
        self.seg_times[s] = times;
        self.subtree[j] = joints;
        worst
    }

    /// The body of [`Eval::set`]: requantizes segment `s` for `joints` (component `c` changed) and
    /// measures the joints that moved at `times`, interleaved so that a failing change stops early.
    ///
    /// The result is that of requantizing the whole segment and then measuring every time, every
    /// joint that moved (a joint whose values changed anywhere in the segment, or below one):
    /// - a time is measured once the keys it reads are requantized (keys go in order); a joint that
    ///   moved by then is computed as the whole pass computes it (its values there are final);
    /// - a joint that moves only through later keys keeps its values at that time (the keys it reads
    ///   there did not change), so its error there is the one it had: measured after the segment.
    fn measure_change(
        &mut self,
        s: usize,
        c: usize,
        joints: &[usize],
        times: &[usize],
        cap: f32,
    ) -> f32 {
        for &d in joints {
            self.dirty[d] = false;
        }
        let keys = self.layout.seg_keys(s);
        let mut next = keys.start;
        let nj = joints.len();
        let mut seen = std::mem::take(&mut self.seen);
        seen.clear();
        seen.resize(times.len() * nj, false);
        let mut worst = 0.0f32;
        let mut failed = false;
        'times: for (pos, &i) in times.iter().enumerate() {
            let (k0, k1, a) = self.at[i];
            let mut need = next;
            if keys.contains(&k0) {
                need = need.max(k0 + 1);
            }
            if a != 0.0 && keys.contains(&k1) {
                need = need.max(k1 + 1);
            }
            while next < need {
                self.requantize_key(s, next, joints, Some(c), true);
                next += 1;
            }
            self.resample(i, joints, true);
            for (n, &d) in joints.iter().enumerate() {
                if !self.moved[d] {
                    continue;
                }
                seen[pos * nj + n] = true;
                let r = self.joint_error(i, d) / self.ctx.limits[d];
                if exceeds(r, cap) {
                    failed = true;
                    break 'times;
                }
                worst = worst.max(r);
            }
        }
        if !failed {
            while next < keys.end {
                self.requantize_key(s, next, joints, Some(c), true);
                next += 1;
            }
            'late: for (pos, &i) in times.iter().enumerate() {
                for (n, &d) in joints.iter().enumerate() {
                    let below = n > 0 && self.parent(d).is_some_and(|p| self.moved[p]);
                    self.moved[d] = self.dirty[d] || below;
                    if !self.moved[d] || seen[pos * nj + n] {
                        continue;
                    }
                    let r = self.joint_error(i, d) / self.ctx.limits[d];
                    if exceeds(r, cap) {
                        failed = true;
                        break 'late;
                    }
                    worst = worst.max(r);
                }
            }
        }
        self.seen = seen;
        if failed {
            f32::INFINITY
        } else {
            worst
        }
    }

    /// Reverts the last [`Eval::set`].
    pub(super) fn undo(&mut self) {
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
            self.key_rot[k * self.nj + d] = r;
        }
        for &(r, k, q) in self.undo.raw.iter().rev() {
            self.raw[r][k] = q;
        }
        for &(i, d, a, m) in self.undo.poses.iter().rev() {
            self.local_aff[i * self.nj + d] = a;
            self.model[i * self.nj + d] = m;
        }
        self.undo.comps.clear();
        self.undo.key_rot.clear();
        self.undo.raw.clear();
        self.undo.poses.clear();
    }

    /// The compressed clip of the current state.
    pub(super) fn encode(&self, work: &Work) -> Option<Clip> {
        self.layout
            .encode(&self.bits, &self.qi, work, self.ctx.like)
    }
}
