//! A state's copies for the refinement's segments side by side: what one segment's tries read
//! of an [`Eval`] ([`Eval::empty_copy`], [`Eval::load_segment`]) and what they write back
//! ([`Eval::segment_state`], [`Eval::store_segment`]).

use super::eval::{Eval, KeyRow};
use super::metric::exceeds;
use super::quantize::Quant;
use sinew_core::glam::{Affine3A, Quat};

/// What refining one segment writes in an [`Eval`] ([`Eval::segment_state`]): the segment's
/// widths and quantization parameters, its keys' stored integers, decoded values, rotations and
/// model rotations, and the local and model transforms at the source times that read its keys.
pub(super) struct SegmentState {
    s: usize,
    bits: Vec<u8>,
    params: Vec<Quant>,
    /// Per component, per key of the segment.
    qi: Vec<u32>,
    dec: Vec<f32>,
    /// Per rotation, per key of the segment.
    raw: Vec<Quat>,
    /// Per key of the segment, per joint.
    key_rot: Vec<Quat>,
    /// Per source time that reads the segment (in `seg_times` order), per joint.
    local_aff: Vec<Affine3A>,
    model: Vec<Affine3A>,
}

impl<'a> Eval<'a> {
    /// A copy of this state without its per-key and per-time values: what
    /// [`Eval::load_segment`] fills with one segment's neighbourhood.
    pub(super) fn empty_copy(&self) -> Eval<'a> {
        Eval {
            ctx: self.ctx,
            layout: self.layout,
            compensate: self.compensate,
            at: self.at.clone(),
            key_src: self.key_src.clone(),
            joint: self.joint.clone(),
            track_of: self.track_of.clone(),
            first: self.first.clone(),
            subtree: self.subtree,
            subtree_parent: self.subtree_parent,
            base: self.base.clone(),
            bits: self.bits.clone(),
            params: self.params.clone(),
            qi: vec![Vec::new(); self.qi.len()],
            dec: vec![Vec::new(); self.dec.len()],
            raw: vec![Vec::new(); self.raw.len()],
            nj: self.nj,
            parents: self.parents.clone(),
            key_rot: Vec::new(),
            local_aff: Vec::new(),
            model: Vec::new(),
            seg_times: self.seg_times.clone(),
            first_key: 0,
            first_time: 0,
        }
    }

    /// Makes this copy ([`Eval::empty_copy`]) of a state hold what a refinement of segment `s`
    /// reads in `from` (the state): the segment's widths and parameters, its keys and the keys
    /// next to it (a source time that reads the segment reads at most one key on either side),
    /// and every joint's transforms at the source times that read the segment (a run of
    /// consecutive times). Only that region is held (`first_key`, `first_time`).
    pub(super) fn load_segment(&mut self, from: &Eval, s: usize) {
        let nc = self.layout.comps.len();
        let nj = self.nj;
        let keys = self.layout.seg_keys(s);
        let near = keys.start.saturating_sub(1)..(keys.end + 1).min(self.layout.keys);
        let times = &self.seg_times[s];
        let span = match (times.first(), times.last()) {
            (Some(&a), Some(&b)) => a..b + 1,
            _ => 0..0,
        };
        let own = s * nc..(s + 1) * nc;
        self.bits[own.clone()].copy_from_slice(&from.bits[own.clone()]);
        self.params[own.clone()].copy_from_slice(&from.params[own]);
        let from_keys = near.start - from.first_key..near.end - from.first_key;
        load_keys(&mut self.qi, &from.qi, &from_keys);
        load_keys(&mut self.dec, &from.dec, &from_keys);
        load_keys(&mut self.raw, &from.raw, &from_keys);
        self.key_rot.clear();
        self.key_rot
            .extend_from_slice(&from.key_rot[from_keys.start * nj..from_keys.end * nj]);
        let rows = (span.start - from.first_time) * nj..(span.end - from.first_time) * nj;
        self.local_aff.clear();
        self.local_aff
            .extend_from_slice(&from.local_aff[rows.clone()]);
        self.model.clear();
        self.model.extend_from_slice(&from.model[rows]);
        (self.first_key, self.first_time) = (near.start, span.start);
    }

    /// What a refinement of segment `s` may have written ([`SegmentState`]).
    pub(super) fn segment_state(&self, s: usize) -> SegmentState {
        let nc = self.layout.comps.len();
        let nj = self.nj;
        let keys = self.layout.seg_keys(s);
        let here = keys.start - self.first_key..keys.end - self.first_key;
        let own = s * nc..(s + 1) * nc;
        let times = &self.seg_times[s];
        let rows = |i: usize| (i - self.first_time) * nj..(i - self.first_time + 1) * nj;
        let mut local_aff = Vec::with_capacity(times.len() * nj);
        let mut model = Vec::with_capacity(times.len() * nj);
        for &i in times {
            local_aff.extend_from_slice(&self.local_aff[rows(i)]);
            model.extend_from_slice(&self.model[rows(i)]);
        }
        SegmentState {
            s,
            bits: self.bits[own.clone()].to_vec(),
            params: self.params[own].to_vec(),
            qi: gather_keys(&self.qi, &here),
            dec: gather_keys(&self.dec, &here),
            raw: gather_keys(&self.raw, &here),
            key_rot: self.key_rot[here.start * nj..here.end * nj].to_vec(),
            local_aff,
            model,
        }
    }

    /// Sets segment `s`'s bit widths to `bits` (each at most the state's) at once, when that keeps
    /// every joint within `limit` of its limit (a ratio) at every source time that reads the
    /// segment: then returns, per joint, the largest ratio over those times and its position among
    /// them (`known`'s entry for a joint nothing moves); else leaves the state as it was and
    /// returns the joint and the time's position where it found that it does not. The state holds
    /// the segment's neighbourhood (a whole state, or a copy with [`Eval::load_segment`] done).
    /// Only the joints that move (the changed components' joints and their subtrees) are
    /// requantized and measured, the `probes` (positions among the segment's times) first: the
    /// times where the segment's errors were largest, or where an earlier change failed.
    pub(super) fn lower_segment(
        &mut self,
        s: usize,
        bits: &[u8],
        limit: f32,
        (probes, known): (&[usize], &[(f32, usize)]),
    ) -> Result<Vec<(f32, usize)>, (usize, usize)> {
        let nc = self.layout.comps.len();
        let nj = self.nj;
        let saved = self.segment_state(s);
        // The joints that move: each changed component's joint with its subtree.
        let mut moved = vec![false; nj];
        for (c, &b) in bits.iter().enumerate().take(nc) {
            let i = s * nc + c;
            if b != self.bits[i] {
                self.bits[i] = b;
                self.params[i] = self.layout.params(s, c, b);
                for &d in &self.subtree[self.joint[self.layout.comps[c].track]] {
                    moved[d] = true;
                }
            }
        }
        let keys = self.layout.seg_keys(s);
        let mut key_done = vec![false; keys.len()];
        let mut row = KeyRow::default();
        let times = std::mem::take(&mut self.seg_times[s]);
        // The joints that do not move keep their errors (`known`).
        let mut worst: Vec<(f32, usize)> = (0..nj)
            .map(|j| match known.get(j) {
                Some(&w) if !moved[j] => w,
                _ => (0.0, 0),
            })
            .collect();
        let mut seen = vec![false; times.len()];
        // Where it does not hold: the joint and the time's position.
        let mut over = None;
        // The probes first (where the segment's errors were largest), each with only the keys it
        // reads requantized (a key's quantization reads no other key), then the rest in order.
        let order = probes
            .iter()
            .copied()
            .filter(|&p| p < times.len())
            .chain(0..times.len());
        for pos in order {
            if seen[pos] {
                continue;
            }
            seen[pos] = true;
            let i = times[pos];
            let (k0, k1, a) = self.at[i];
            for k in [Some(k0), (a != 0.0).then_some(k1)].into_iter().flatten() {
                if let Some(kk) = k.checked_sub(keys.start).filter(|&kk| kk < keys.len()) {
                    if !key_done[kk] {
                        key_done[kk] = true;
                        self.requantize_moved(k, &mut row, &moved);
                    }
                }
            }
            let rows = (i - self.first_time) * nj..(i - self.first_time + 1) * nj;
            let mut local = std::mem::take(&mut self.local_aff);
            let mut model = std::mem::take(&mut self.model);
            self.pose_moved_into(
                i,
                &mut local[rows.clone()],
                &mut model[rows.clone()],
                &moved,
            );
            for (j, m) in model[rows].iter().enumerate() {
                if !moved[j] {
                    continue;
                }
                let r = self.error_at(i, j, m) / self.ctx.limits[j];
                if exceeds(r, limit) {
                    over = Some((j, pos));
                    break;
                }
                if r > worst[j].0 {
                    worst[j] = (r, pos);
                }
            }
            self.local_aff = local;
            self.model = model;
            if over.is_some() {
                break;
            }
        }
        if over.is_none() {
            for (kk, done) in key_done.iter().enumerate() {
                if !done {
                    self.requantize_moved(keys.start + kk, &mut row, &moved);
                }
            }
        }
        self.seg_times[s] = times;
        match over {
            None => Ok(worst),
            Some(at) => {
                self.store_segment(&saved);
                Err(at)
            }
        }
    }

    /// Writes back what [`Eval::segment_state`] took (from a copy of this state).
    pub(super) fn store_segment(&mut self, st: &SegmentState) {
        let nc = self.layout.comps.len();
        let nj = self.nj;
        let keys = self.layout.seg_keys(st.s);
        let here = keys.start - self.first_key..keys.end - self.first_key;
        let own = st.s * nc..(st.s + 1) * nc;
        self.bits[own.clone()].copy_from_slice(&st.bits);
        self.params[own].copy_from_slice(&st.params);
        scatter_keys(&mut self.qi, &st.qi, &here);
        scatter_keys(&mut self.dec, &st.dec, &here);
        scatter_keys(&mut self.raw, &st.raw, &here);
        self.key_rot[here.start * nj..here.end * nj].copy_from_slice(&st.key_rot);
        let times = std::mem::take(&mut self.seg_times[st.s]);
        for (n, &i) in times.iter().enumerate() {
            let rows = (i - self.first_time) * nj..(i - self.first_time + 1) * nj;
            self.local_aff[rows.clone()].copy_from_slice(&st.local_aff[n * nj..(n + 1) * nj]);
            self.model[rows].copy_from_slice(&st.model[n * nj..(n + 1) * nj]);
        }
        self.seg_times[st.s] = times;
    }
}

/// Per-component (or per-rotation) key arrays: `to` made to hold `from`'s keys `range` (indices
/// into `from`).
fn load_keys<T: Copy>(to: &mut [Vec<T>], from: &[Vec<T>], range: &std::ops::Range<usize>) {
    for (to, from) in to.iter_mut().zip(from) {
        to.clear();
        to.extend_from_slice(&from[range.clone()]);
    }
}

/// Per-component key arrays: the keys `range` of each, one array after the other.
fn gather_keys<T: Copy>(arrays: &[Vec<T>], range: &std::ops::Range<usize>) -> Vec<T> {
    let mut out = Vec::with_capacity(arrays.len() * range.len());
    for v in arrays {
        out.extend_from_slice(&v[range.clone()]);
    }
    out
}

/// The inverse of [`gather_keys`]: `gathered`'s runs written back into keys `range` of each array.
fn scatter_keys<T: Copy>(arrays: &mut [Vec<T>], gathered: &[T], range: &std::ops::Range<usize>) {
    for (to, from) in arrays
        .iter_mut()
        .zip(gathered.chunks_exact(range.len().max(1)))
    {
        to[range.clone()].copy_from_slice(from);
    }
}
