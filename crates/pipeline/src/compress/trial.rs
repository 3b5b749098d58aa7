//! Tentative bit-width changes, worked out beside the state they start from.
//!
//! A [`Trial`] lowers one component of one segment by a bit against an [`Eval`] it only reads: the
//! values it changes (stored integers and decoded values of the segment's keys, the subtree's
//! rotations and model rotations at those keys, the subtree's local and model transforms at the
//! source times that read the segment) go into its own buffers, with a flag per entry. A trial that
//! stays within the limits is then [`Trial::commit`]ted into the state; one that does not is simply
//! dropped. Two trials on segments two or more apart read and write disjoint parts of the state
//! (their keys differ, and so do the source times that read them), so the refinement runs them at
//! the same time and commits them in order, with the decisions of one trial at a time.
//!
//! The subtree's joints are worked on through [`Row`]s looked up once per trial (parent, track,
//! rotation components, quantization parameters), so the per-key and per-time loops index flat
//! buffers only.

use super::eval::{point_distance, Eval};
use super::metric::{exceeds, rebase_on};
use super::quantize::{raw_rotation, Kind, Quant};
use sinew_core::clip::{nlerp, normalize_rotation};
use sinew_core::glam::{Affine3A, Quat, Vec3};
use sinew_core::Transform;

/// The most times a trial measures first ([`Trial::run`]'s `probes`).
pub(super) const MAX_PROBES: usize = 4;

/// "None" for the `usize` fields of a [`Row`].
const NONE: usize = usize::MAX;

/// One joint of the trial's subtree, looked up once.
#[derive(Clone, Copy)]
struct Row {
    /// The joint.
    d: usize,
    /// Its parent's position in the subtree, or [`NONE`] (the first row, whose parent is outside).
    np: usize,
    /// Its parent joint, or [`NONE`] for a root.
    pj: usize,
    /// Its track, or [`NONE`].
    track: usize,
    /// Its rotation's first component and rotation number, or [`NONE`] when not quantized.
    fr: usize,
    ri: usize,
    /// Its scale where the clip does not quantize it (the local scale at every time), else `None`.
    fixed_scale: Option<Vec3>,
}

/// The buffers of one tentative change (reused from trial to trial; `Default`: empty).
#[derive(Default)]
pub(super) struct Trial {
    s: usize,
    c: usize,
    bits: u8,
    quant: Quant,
    /// The changed component's joint, and whether the component is a rotation's.
    j: usize,
    rot: bool,
    /// The segment's first key and key count; the joint's subtree size.
    key0: usize,
    nk: usize,
    nsub: usize,
    /// The subtree's joints, in subtree order.
    rows: Vec<Row>,
    /// The position in `rows` of the rig's anchor the subtree holds ([`NONE`] if none), and its
    /// position among the anchors ([`super::metric::Rig::rebase`]; 0 without one).
    anchor_row: usize,
    anchor_slot: usize,
    /// Per joint, its subtree's rows once looked up ([`Trial::set_rows`]), for the layout at this
    /// address.
    row_cache: Vec<Vec<Row>>,
    rows_of_layout: usize,
    /// Per slot (as `qi`): the quantization parameters of that component in the segment.
    slot_quant: Vec<Quant>,
    /// The changed component's kind, and for a translation its channel's first component.
    kind: Option<Kind>,
    first_t: usize,
    /// Per segment key: requantized (each key once; a time reads only requantized keys).
    key_done: Vec<bool>,
    /// Per segment key: how many subtree joints (the first ones, in order) were requantized at it
    /// (a rotation's change stops where a joint's rotation does not change: nothing below does).
    reached: Vec<usize>,
    /// Per slot (the changed component for a translation or scale; three per subtree joint for a
    /// rotation), per segment key: stored integer and decoded value, valid for requantized keys
    /// and joints.
    qi: Vec<u32>,
    dec: Vec<f32>,
    /// Per subtree joint, per segment key: the rotation as decoded (before normalisation) and the
    /// model rotation, valid likewise.
    raw: Vec<Quat>,
    key_rot: Vec<Quat>,
    /// Per subtree joint, per segment key: its stored integers (so its rotation) are the
    /// state's, valid likewise (the trial's `qi` and `dec` of its slots are then not written).
    same: Vec<bool>,
    /// Per subtree joint: its values changed.
    dirty: Vec<bool>,
    /// What the trial's measurements write ([`Timed`]).
    t: Timed,
    /// The largest ratio of error to limit over the joints and times that changed, or infinity
    /// when one exceeded the cap (the trial then stopped there).
    pub(super) worst: f32,
    /// Where a failed trial stopped: the position of that time among the segment's source times
    /// (`usize::MAX` when it was not one time's first measurement).
    pub(super) failed_at: usize,
}

/// The buffers a trial's measurements write, apart from the rest of the [`Trial`] so that a
/// measurement can write them while reading the rest (each time's row of them a slice of its own).
#[derive(Default)]
struct Timed {
    /// Per source time of the segment, per subtree joint: local and model transforms, written.
    local_aff: Vec<Affine3A>,
    local_set: Vec<bool>,
    model: Vec<Affine3A>,
    model_set: Vec<bool>,
    /// Per subtree joint: its model transforms changed.
    moved: Vec<bool>,
    /// Per source time of the segment, per subtree joint: measured already, and the ratio of its
    /// error to its limit found then.
    seen: Vec<bool>,
    ratio: Vec<f32>,
}

impl Timed {
    /// The model transform of subtree joint `n` (joint `d`) at the segment's time `pos` (source
    /// time `i`): the trial's where it wrote one, else the state's.
    fn model_of(
        &self,
        e: &Eval,
        nsub: usize,
        pos: usize,
        i: usize,
        n: usize,
        d: usize,
    ) -> Affine3A {
        let at = pos * nsub + n;
        if self.model_set[at] {
            self.model[at]
        } else {
            e.model[(i - e.first_time) * e.nj + d]
        }
    }
}

impl Trial {
    /// Works out setting component `c` of segment `s` to `bits` on `e` (see the module docs) and
    /// sets [`Trial::worst`]. As soon as one ratio exceeds `cap` it stops: `worst` is infinity.
    /// `probes`: times (positions among the segment's source times) to measure first, in order
    /// (where an earlier trial of this component and segment failed, where the state's error is
    /// largest); the result does not depend on them.
    ///
    /// The result is that of requantizing the whole segment and then measuring every time, every
    /// joint that moved (a joint whose values changed anywhere in the segment, or below one):
    /// - a time is measured once the keys it reads are requantized (keys go in order); a joint that
    ///   moved by then is computed as the whole pass computes it (its values there are final);
    /// - a joint that moves only through later keys keeps its values at that time (the keys it reads
    ///   there did not change), so its error there is the one it had: measured after the segment.
    pub(super) fn run(
        &mut self,
        e: &Eval,
        s: usize,
        c: usize,
        bits: u8,
        cap: f32,
        probes: &[usize],
    ) {
        let keys = e.layout.seg_keys(s);
        let j = e.joint[e.layout.comps[c].track];
        let times = &e.seg_times[s];
        self.s = s;
        self.c = c;
        self.bits = bits;
        self.quant = e.layout.params(s, c, bits);
        self.j = j;
        self.rot = e.layout.comps[c].kind == Kind::R;
        self.kind = Some(e.layout.comps[c].kind);
        let track = e.layout.comps[c].track;
        self.first_t = e.first[track][Kind::T as usize].unwrap_or(NONE);
        self.key0 = keys.start;
        self.nk = keys.len();
        self.set_rows(e);
        let slots = if self.rot { 3 * self.nsub } else { 1 };
        grow(&mut self.qi, slots * self.nk, 0);
        grow(&mut self.dec, slots * self.nk, 0.0);
        for v in [&mut self.raw, &mut self.key_rot] {
            grow(v, self.nsub * self.nk, Quat::IDENTITY);
        }
        grow(&mut self.same, self.nsub * self.nk, false);
        reset(&mut self.key_done, self.nk, false);
        reset(&mut self.reached, self.nk, 0);
        let poses = times.len() * self.nsub;
        for v in [&mut self.t.local_aff, &mut self.t.model] {
            grow(v, poses, Affine3A::IDENTITY);
        }
        for f in [
            &mut self.t.local_set,
            &mut self.t.model_set,
            &mut self.t.seen,
        ] {
            reset(f, poses, false);
        }
        grow(&mut self.t.ratio, poses, 0.0);
        reset(&mut self.dirty, self.nsub, false);
        reset(&mut self.t.moved, self.nsub, false);
        // The measurements write `t` while they read the rest of the trial.
        let mut t = std::mem::take(&mut self.t);
        self.measure_all(&mut t, e, keys, times, cap, probes);
        self.t = t;
    }

    /// The measuring part of [`Trial::run`], writing `t`.
    fn measure_all(
        &mut self,
        t: &mut Timed,
        e: &Eval,
        keys: std::ops::Range<usize>,
        times: &[usize],
        cap: f32,
        probes: &[usize],
    ) {
        let nsub = self.nsub;
        let mut worst = 0.0f32;
        let mut failed = false;
        self.failed_at = usize::MAX;
        // The keys time `i` reads inside the segment.
        let reads = |i: usize| {
            let (k0, k1, a) = e.at[i];
            [Some(k0), (a != 0.0).then_some(k1)]
                .into_iter()
                .flatten()
                .filter(|k| keys.contains(k))
        };
        // The probes: times where this try is likely to fail (where this component of this
        // segment failed last, where the state's error is largest), measured first with only the
        // keys they read. Their joints' values there are final (a key's quantization does not
        // depend on other keys), so if one fails the trial fails; if they pass, the times are
        // measured in order as usual, the probes' counting as measured.
        let mut first = [usize::MAX; MAX_PROBES];
        let mut nprobes = 0;
        for &p in probes {
            if p < times.len() && nprobes < MAX_PROBES && !first[..nprobes].contains(&p) {
                first[nprobes] = p;
                nprobes += 1;
            }
        }
        let probes = &first[..nprobes];
        for &p in probes {
            let i = times[p];
            for k in reads(i) {
                self.requantize_once(e, k);
            }
            match self.measure_time(t, e, p, i, cap) {
                Some(r) => worst = worst.max(r),
                None => {
                    self.failed_at = p;
                    self.worst = f32::INFINITY;
                    return;
                }
            }
        }
        // Keys go in order: a time is measured once every key up to the last it reads is done
        // (the joints that moved by then are the ones a whole pass would compute there).
        let mut next = keys.start;
        for (pos, &i) in times.iter().enumerate() {
            let need = reads(i).map(|k| k + 1).max().unwrap_or(next).max(next);
            while next < need {
                self.requantize_once(e, next);
                next += 1;
            }
            if probes.contains(&pos) {
                continue;
            }
            match self.measure_time(t, e, pos, i, cap) {
                Some(r) => worst = worst.max(r),
                None => {
                    failed = true;
                    self.failed_at = pos;
                    break;
                }
            }
        }
        if !failed {
            while next < keys.end {
                self.requantize_once(e, next);
                next += 1;
            }
            'late: for (pos, &i) in times.iter().enumerate() {
                for n in 0..nsub {
                    let row = self.rows[n];
                    let below = row.np != NONE && t.moved[row.np];
                    t.moved[n] = self.dirty[n] || below;
                    if !t.moved[n] || t.seen[pos * nsub + n] {
                        continue;
                    }
                    let m = t.model_of(e, nsub, pos, i, n, row.d);
                    let r = e.error_at(i, row.d, &m) / e.ctx.limits[row.d];
                    t.seen[pos * nsub + n] = true;
                    t.ratio[pos * nsub + n] = r;
                    if exceeds(r, cap) {
                        failed = true;
                        break 'late;
                    }
                    worst = worst.max(r);
                }
            }
        }
        self.worst = if failed { f32::INFINITY } else { worst };
    }

    /// Looks up the subtree's rows (once per joint: they depend on the state's layout alone) and
    /// the quantization parameters of the slots the trial requantizes.
    fn set_rows(&mut self, e: &Eval) {
        let layout = std::ptr::from_ref(e.layout) as usize;
        if self.rows_of_layout != layout {
            self.row_cache.clear();
            self.rows_of_layout = layout;
        }
        if self.row_cache.len() < e.nj {
            self.row_cache.resize_with(e.nj, Vec::new);
        }
        if self.row_cache[self.j].is_empty() {
            self.row_cache[self.j] = subtree_rows(e, self.j);
        }
        self.rows.clear();
        self.rows.extend_from_slice(&self.row_cache[self.j]);
        self.nsub = self.rows.len();
        // A subtree holds at most one anchor (one per root).
        let rig = e.ctx.rig;
        (self.anchor_row, self.anchor_slot) = self
            .rows
            .iter()
            .enumerate()
            .find_map(|(n, row)| rig.anchor_of(row.d).map(|slot| (n, slot)))
            .unwrap_or((NONE, 0));
        self.slot_quant.clear();
        if self.rot {
            let nc = e.layout.comps.len();
            for row in &self.rows {
                for a in 0..3 {
                    let x = row.fr.wrapping_add(a);
                    self.slot_quant.push(if row.fr == NONE {
                        Quant::default()
                    } else if x == self.c {
                        self.quant
                    } else {
                        e.params[self.s * nc + x]
                    });
                }
            }
        }
    }

    /// Resamples the subtree at the segment's time `pos` (source time `i`) and measures the joints
    /// that moved: the largest ratio of error to limit, or `None` at the first over `cap`.
    fn measure_time(&self, t: &mut Timed, e: &Eval, pos: usize, i: usize, cap: f32) -> Option<f32> {
        let nsub = self.nsub;
        let nj = e.nj;
        // This time's row of each buffer, and the state's transforms at this time.
        let row_of = pos * nsub..(pos + 1) * nsub;
        let (rows, dirty) = (&self.rows[..nsub], &self.dirty[..nsub]);
        let moved = &mut t.moved[..nsub];
        let local_aff = &mut t.local_aff[row_of.clone()];
        let local_set = &mut t.local_set[row_of.clone()];
        let model = &mut t.model[row_of.clone()];
        let model_set = &mut t.model_set[row_of.clone()];
        let seen = &mut t.seen[row_of.clone()];
        let ratio = &mut t.ratio[row_of];
        let state_row = (i - e.first_time) * nj..(i - e.first_time + 1) * nj;
        let (state_local, state_model) = (&e.local_aff[state_row.clone()], &e.model[state_row]);
        let src = &e.ctx.src_flat[i * nj..(i + 1) * nj];
        let (scales, limits) = (&e.ctx.rig.point_scale[..nj], &e.ctx.limits[..nj]);
        let mut worst = 0.0f32;
        for n in 0..nsub {
            let row = rows[n];
            let below = row.np != NONE && moved[row.np];
            let is_moved = dirty[n] || below;
            moved[n] = is_moved;
            if !is_moved {
                continue;
            }
            let d = row.d;
            let local = if dirty[n] {
                // Only the changed translation or scale component, or the subtree's rotations,
                // differ from the state: the rest of the local transform is the state's (the
                // values `Transform::to_affine` of the sampled pose gives, bit for bit).
                let state = state_local[d];
                let a = match (self.kind, row.fixed_scale) {
                    (Some(Kind::R), Some(scale)) if row.fr != NONE => {
                        let (k0, k1, alpha) = e.at[i];
                        let rot = if alpha == 0.0 {
                            normalize_rotation(self.raw_of(e, n, row.ri, k0))
                        } else {
                            nlerp(
                                self.raw_of(e, n, row.ri, k0),
                                self.raw_of(e, n, row.ri, k1),
                                alpha,
                            )
                        };
                        Affine3A::from_scale_rotation_translation(
                            scale,
                            rot,
                            state.translation.into(),
                        )
                    }
                    (Some(Kind::T), _) if self.first_t != NONE => {
                        let (k0, k1, alpha) = e.at[i];
                        let f = self.first_t;
                        let v = |k: usize| {
                            let at = |x: usize| match self.in_segment(k).filter(|_| x == self.c) {
                                Some(kk) if self.key_done[kk] => self.dec[kk],
                                _ => e.dec[x][k - e.first_key],
                            };
                            Vec3::new(at(f), at(f + 1), at(f + 2))
                        };
                        let t = if alpha == 0.0 {
                            v(k0)
                        } else {
                            v(k0).lerp(v(k1), alpha)
                        };
                        Affine3A {
                            matrix3: state.matrix3,
                            translation: t.into(),
                        }
                    }
                    _ => self.sampled_local(e, n, i).to_affine(),
                };
                local_aff[n] = a;
                local_set[n] = true;
                a
            } else if local_set[n] {
                local_aff[n]
            } else {
                state_local[d]
            };
            let pm = if row.pj == NONE {
                Affine3A::IDENTITY
            } else if row.np != NONE && model_set[row.np] {
                model[row.np]
            } else {
                state_model[row.pj]
            };
            let mut m = pm * local;
            if n == self.anchor_row {
                rebase_on(&mut m, e.origins_at(i), self.anchor_slot);
            }
            model[n] = m;
            model_set[n] = true;
            seen[n] = true;
            let r = point_distance(&src[d], scales[d], &m) / limits[d];
            ratio[n] = r;
            if exceeds(r, cap) {
                return None;
            }
            worst = worst.max(r);
        }
        Some(worst)
    }

    /// Subtree joint `n`'s local pose at source time `i` as the sampler computes it, with the
    /// trial's values.
    fn sampled_local(&self, e: &Eval, n: usize, i: usize) -> Transform {
        let row = self.rows[n];
        let d = row.d;
        if row.track == NONE {
            e.base[d]
        } else if self.rot {
            e.sampled_with(
                row.track,
                i,
                e.base[d],
                |x, k| e.dec[x][k - e.first_key],
                |ri, k| self.raw_of(e, n, ri, k),
            )
        } else {
            e.sampled_with(
                row.track,
                i,
                e.base[d],
                |x, k| match self.in_segment(k).filter(|_| x == self.c) {
                    Some(kk) if self.key_done[kk] => self.dec[kk],
                    _ => e.dec[x][k - e.first_key],
                },
                |ri, k| e.raw[ri][k - e.first_key],
            )
        }
    }

    /// Writes the trial's changes into `e` (the state it was run on, unchanged since).
    pub(super) fn commit(&self, e: &mut Eval) {
        let nc = e.layout.comps.len();
        let nj = e.nj;
        e.bits[self.s * nc + self.c] = self.bits;
        e.params[self.s * nc + self.c] = self.quant;
        if !self.rot {
            for kk in (0..self.nk).filter(|&kk| self.key_done[kk]) {
                e.qi[self.c][self.key0 + kk - e.first_key] = self.qi[kk];
                e.dec[self.c][self.key0 + kk - e.first_key] = self.dec[kk];
            }
        }
        for kk in (0..self.nk).filter(|&kk| self.key_done[kk]) {
            let k = self.key0 + kk - e.first_key;
            for (n, row) in self.rows.iter().enumerate().take(self.reached[kk]) {
                let at = n * self.nk + kk;
                if row.fr != NONE && !self.same[at] {
                    for a in 0..3 {
                        let slot = (3 * n + a) * self.nk + kk;
                        e.qi[row.fr + a][k] = self.qi[slot];
                        e.dec[row.fr + a][k] = self.dec[slot];
                    }
                    e.raw[row.ri][k] = self.raw[at];
                }
                e.key_rot[k * nj + row.d] = self.key_rot[at];
            }
        }
        let times = std::mem::take(&mut e.seg_times[self.s]);
        let nsub = self.nsub;
        for (pos, &i) in times.iter().enumerate() {
            // This time's rows of the trial's buffers and of the state's.
            let ours = pos * nsub..(pos + 1) * nsub;
            let (local_set, local_aff) = (
                &self.t.local_set[ours.clone()],
                &self.t.local_aff[ours.clone()],
            );
            let (model_set, model) = (&self.t.model_set[ours.clone()], &self.t.model[ours]);
            let theirs = (i - e.first_time) * nj..(i - e.first_time + 1) * nj;
            let state_local = &mut e.local_aff[theirs.clone()];
            let state_model = &mut e.model[theirs];
            for (n, row) in self.rows[..nsub].iter().enumerate() {
                if local_set[n] {
                    state_local[row.d] = local_aff[n];
                }
                if model_set[n] {
                    state_model[row.d] = model[n];
                }
            }
        }
        e.seg_times[self.s] = times;
    }

    /// After a kept trial: per joint of the subtree whose errors it measured at every time of the
    /// segment (the joints that moved), the largest ratio of error to limit and its time's
    /// position. (A kept trial measures every time of a joint that moved.)
    pub(super) fn moved_worst(&self) -> impl Iterator<Item = (usize, f32, usize)> + '_ {
        let nsub = self.nsub;
        let times = self.t.seen.len() / nsub.max(1);
        self.rows
            .iter()
            .enumerate()
            .filter(move |&(n, _)| self.t.moved[n])
            .map(move |(n, row)| {
                let mut best = (0.0f32, 0usize);
                for pos in 0..times {
                    let r = self.t.ratio[pos * nsub + n];
                    if self.t.seen[pos * nsub + n] && r > best.0 {
                        best = (r, pos);
                    }
                }
                (row.d, best.0, best.1)
            })
    }

    fn in_segment(&self, k: usize) -> Option<usize> {
        k.checked_sub(self.key0).filter(|&kk| kk < self.nk)
    }

    /// Subtree joint `n`'s rotation as decoded at key `k` (rotation number `ri`), as the trial has
    /// it.
    #[inline]
    fn raw_of(&self, e: &Eval, n: usize, ri: usize, k: usize) -> Quat {
        match self.in_segment(k) {
            Some(kk) if self.key_done[kk] && n < self.reached[kk] => self.raw[n * self.nk + kk],
            _ => e.raw[ri][k - e.first_key],
        }
    }

    /// [`Trial::requantize`] unless key `k` was requantized already.
    fn requantize_once(&mut self, e: &Eval, k: usize) {
        let kk = k - self.key0;
        if !self.key_done[kk] {
            self.requantize(e, k);
            self.key_done[kk] = true;
        }
    }

    /// [`Eval::requantize_key`] for the changed component at key `k` of the segment.
    fn requantize(&mut self, e: &Eval, k: usize) {
        let kk = k - self.key0;
        let nk = self.nk;
        if !self.rot {
            // A translation or scale component: nothing else depends on it.
            let v = e.layout.comps[self.c].vals[k];
            let (q, y) = self.quant.quantize(v);
            self.dirty[0] |= q != e.qi[self.c][k - e.first_key]
                || y.to_bits() != e.dec[self.c][k - e.first_key].to_bits();
            self.qi[kk] = q;
            self.dec[kk] = y;
            return;
        }
        for n in 0..self.nsub {
            if n > 0 && !e.compensate {
                break;
            }
            let row = self.rows[n];
            // A parent inside the subtree was requantized just before (parents come first).
            let pr = if row.pj == NONE {
                Quat::IDENTITY
            } else if row.np != NONE {
                self.key_rot[row.np * nk + kk]
            } else {
                e.key_rot[(k - e.first_key) * e.nj + row.pj]
            };
            let mut rot = e.base[row.d].rotation;
            let mut rot_changed = false;
            if row.fr != NONE {
                let at = k - e.first_key;
                let index = e.layout.index[row.ri][k];
                let compensated = e.compensated(row.d, k, pr);
                // Below the changed joint (n > 0) only the parent's model rotation changed: where
                // the new target certainly quantizes to the state's integers, the rotation is the
                // state's (and without compensation it does not depend on the parent at all).
                let kept = n > 0
                    && compensated.is_none_or(|u| {
                        let stored: [u32; 3] = std::array::from_fn(|a| e.qi[row.fr + a][at]);
                        let slots = 3 * n..3 * n + 3;
                        stays(u, index, &self.slot_quant[slots], stored)
                    });
                let raw = if kept {
                    e.raw[row.ri][at]
                } else {
                    let vals = e.values_of(row.fr, k, compensated);
                    let mut q = [0.0; 3];
                    for (a, &v) in vals.iter().enumerate() {
                        let x = row.fr + a;
                        let slot = 3 * n + a;
                        let (qq, y) = self.slot_quant[slot].quantize(v);
                        rot_changed |= qq != e.qi[x][at] || y.to_bits() != e.dec[x][at].to_bits();
                        self.qi[slot * nk + kk] = qq;
                        self.dec[slot * nk + kk] = y;
                        q[a] = y;
                    }
                    self.dirty[n] |= rot_changed;
                    raw_rotation(index, q)
                };
                self.same[n * nk + kk] = !rot_changed;
                self.raw[n * nk + kk] = raw;
                rot = normalize_rotation(raw);
            }
            if n == 0 && !rot_changed {
                // The joint's rotation at this key did not change: nothing below it does.
                break;
            }
            self.key_rot[n * nk + kk] = pr * rot;
            self.reached[kk] = n + 1;
        }
    }
}

/// The rows of joint `j`'s subtree, in subtree order.
fn subtree_rows(e: &Eval, j: usize) -> Vec<Row> {
    let parents = &e.subtree_parent[j];
    e.subtree[j]
        .iter()
        .enumerate()
        .map(|(n, &d)| {
            let fr = e.track_of[d]
                .and_then(|tr| e.first[tr][Kind::R as usize])
                .unwrap_or(NONE);
            let scaled = e.track_of[d].is_some_and(|tr| e.first[tr][Kind::S as usize].is_some());
            Row {
                d,
                np: if n > 0 { parents[n] } else { NONE },
                pj: e.parent(d).unwrap_or(NONE),
                track: e.track_of[d].unwrap_or(NONE),
                fr,
                ri: if fr == NONE {
                    0
                } else {
                    e.layout.comps[fr].rot
                },
                fixed_scale: (!scaled).then_some(e.base[d].scale),
            }
        })
        .collect()
}

/// Whether the compensated rotation `u` (before normalisation) certainly gives the stored
/// integers `stored` with `quants` (the component `index` left out, [`Eval::values_of`]): its
/// left-out component far enough from 0 that its sign (which sets the others') is the
/// normalised one's, and each other component `v` within a margin that holds what the
/// normalisation moves it by (at most `|v| (||u|^2 - 1| / 2 + 2.4e-7)`: the length's and the
/// reciprocal's rounding) plus the rounding of `v` itself and of the margin's ends, doubled.
fn stays(u: Quat, index: u8, quants: &[Quant], stored: [u32; 3]) -> bool {
    let a = u.to_array();
    let big = usize::from(index & 3);
    if a[big].is_nan() || a[big].abs() <= 1e-6 {
        return false;
    }
    let stretch = (u.length_squared() - 1.0).abs() + 5e-7;
    let sign = if a[big] < 0.0 { -1.0 } else { 1.0 };
    let mut k = 0;
    for (i, &x) in a.iter().enumerate() {
        if i == big {
            continue;
        }
        let v = x * sign;
        if !quants[k].keeps(v, v.abs() * stretch + 2e-7, stored[k]) {
            return false;
        }
        k += 1;
    }
    true
}

/// `v` holding `len` entries equal to `fill` (reusing its allocation): for flags.
fn reset<T: Copy>(v: &mut Vec<T>, len: usize, fill: T) {
    v.clear();
    v.resize(len, fill);
}

/// `v` holding at least `len` entries: for values, which are read only where a flag says they
/// were written.
fn grow<T: Copy>(v: &mut Vec<T>, len: usize, fill: T) {
    if v.len() < len {
        v.resize(len, fill);
    }
}
