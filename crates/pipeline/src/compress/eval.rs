//! Incremental error evaluation of a quantisation while its bit widths change.

use super::metric::{exceeds, joint_limits, rebase_on, Rig};
use super::quantize::{locate, raw_rotation, Kind, Layout, Quant};
use super::reduce::{WChan, Work};
use rayon::prelude::*;
use sinew_core::clip::{nlerp, normalize_rotation};
use sinew_core::compressed::three_without;
use sinew_core::glam::{Affine3A, Quat, Vec3};
use sinew_core::{Clip, Transform};
use std::sync::Arc;

/// What every quantization of one clip is measured against.
pub(super) struct Ctx<'a> {
    pub(super) rig: &'a Rig,
    pub(super) like: &'a Clip,
    /// Source key times.
    pub(super) times: &'a [f32],
    /// Per source time, per joint: the source's error points (shared with the search that made
    /// them: computed once per clip).
    pub(super) src: Arc<Vec<Vec<[Vec3; 3]>>>,
    /// Per source time, per anchor: the origin the error points are about ([`Rig::source_points`]).
    pub(super) origins: Arc<Vec<Vec3>>,
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

/// A clip sampled at its times: poses and error points, computed once per clip and shared by the
/// searches on it and the final measurement.
pub(super) struct Sampled {
    /// Per time: the local pose.
    pub(super) poses: Vec<Vec<Transform>>,
    /// Per time, per joint: the error points, about the time's origins.
    pub(super) points: Arc<Vec<Vec<[Vec3; 3]>>>,
    /// Per time, per anchor: the origin ([`Rig::source_points`]).
    pub(super) origins: Arc<Vec<Vec3>>,
}

impl Sampled {
    pub(super) fn new(rig: &Rig, clip: &Clip, times: &[f32]) -> Sampled {
        let poses = rig.poses(clip, times);
        let (points, origins) = rig.source_points(&poses);
        Sampled {
            poses,
            points: Arc::new(points),
            origins: Arc::new(origins),
        }
    }
}

impl<'a> Ctx<'a> {
    pub(super) fn new(rig: &'a Rig, like: &'a Clip, times: &'a [f32], tolerance: f32) -> Ctx<'a> {
        Ctx::of_sampled(rig, like, times, tolerance, &Sampled::new(rig, like, times))
    }

    /// [`Ctx::new`] from `like` already sampled at `times`.
    pub(super) fn of_sampled(
        rig: &'a Rig,
        like: &'a Clip,
        times: &'a [f32],
        tolerance: f32,
        sampled: &Sampled,
    ) -> Ctx<'a> {
        let poses = &sampled.poses;
        let src = Arc::clone(&sampled.points);
        let parents = rig.skeleton.parents();
        let nj = rig.skeleton.len();
        // Each time's model rotations, and its error points, into its own rows of the flat
        // tables: the same values whether the times go side by side or not.
        let rotations_into = |(pose, out): (&Vec<Transform>, &mut [Quat])| {
            for (j, t) in pose.iter().enumerate().take(out.len()) {
                let p = parents.get(j).copied().flatten().map(usize::from);
                let pr = p.filter(|&p| p < j).map(|p| out[p]);
                out[j] = pr.map_or(t.rotation, |pr| pr * t.rotation);
            }
        };
        let points_into = |(points, out): (&Vec<[Vec3; 3]>, &mut [[Vec3; 3]])| {
            for (o, p) in out.iter_mut().zip(points) {
                *o = *p;
            }
        };
        let mut src_rot = vec![Quat::IDENTITY; poses.len() * nj];
        let mut src_flat = vec![[Vec3::ZERO; 3]; src.len() * nj];
        let par = rig.side_by_side(poses.len());
        fill_rows(poses, &mut src_rot, nj, par, rotations_into);
        fill_rows(src.as_slice(), &mut src_flat, nj, par, points_into);
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
            origins: Arc::clone(&sampled.origins),
            src_flat,
            src_rot,
            limits,
            uniform,
        }
    }
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
/// and re-measures only the source times that read those keys ([`super::trial::Trial`]).
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
    pub(super) subtree: &'a [Vec<usize>],
    /// Per joint `j`, per position `n > 0` in `subtree[j]`: the position of that joint's parent
    /// (`usize::MAX` at `n == 0`, whose parent is outside the subtree).
    pub(super) subtree_parent: &'a [Vec<usize>],
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
    /// and its model transform. A long clip's checked build ([`Eval::build`], from
    /// [`KEEP_LOCAL_BELOW`] joint-times) computes the model transforms alone: most checks are of
    /// widths that are then dropped, and its local poses are megabytes the process would touch for
    /// nothing (a page fault per page, and the stores); a refinement fills them in first
    /// ([`Eval::fill_local`]).
    pub(super) local_aff: Vec<Affine3A>,
    pub(super) model: Vec<Affine3A>,
    /// Per segment: the source times that read one of its keys.
    pub(super) seg_times: Vec<Vec<usize>>,
    /// The first key and the first source time the per-key and per-time arrays above hold (`qi`,
    /// `dec`, `raw`, `key_rot`; `local_aff`, `model`): 0 in a whole state, the start of the
    /// region in a copy that holds one segment's neighbourhood ([`Eval::load_segment`]).
    pub(super) first_key: usize,
    pub(super) first_time: usize,
}

/// One key's quantized values, as [`Eval::key_into`] works them out: per component its stored
/// integer and decoded value, per rotation its decoded value, per joint its model rotation.
#[derive(Default)]
pub(super) struct KeyRow {
    q: Vec<(u32, f32)>,
    raw: Vec<Quat>,
    rot: Vec<Quat>,
}

/// Joint-times from which [`Eval::build`] quantizes keys and computes times in chunks side by side
/// (a long clip's passing check is a few milliseconds of work).
const SIDE_BY_SIDE_BUILD: usize = 16 * 1024;

/// Whether a pass over `volume` joint-keys or joint-times goes side by side ([`SIDE_BY_SIDE_BUILD`],
/// and more than one thread to share it).
fn goes_side_by_side(volume: usize) -> bool {
    volume >= SIDE_BY_SIDE_BUILD && rayon::current_num_threads() > 1
}

/// Joint-times below which a checked build keeps its local poses as it computes them (4 MiB of
/// them): a shorter clip's are little memory, soon reused, and computing them again for the state
/// a refinement starts from ([`Eval::fill_local`]) costs most of a pass (with 16 Ki here the
/// Half-Life batch was 1.2-1.7% slower); a long clip's are megabytes touched for nothing in most
/// checks (docs/performance.md, session 26).
const KEEP_LOCAL_BELOW: usize = 64 * 1024;

/// Whether a checked build of `times` source times of `nj` joints keeps its local poses
/// ([`KEEP_LOCAL_BELOW`]).
fn keeps_local(nj: usize, times: usize) -> bool {
    nj * times < KEEP_LOCAL_BELOW
}
/// Source times of the first block of [`Eval::build`]'s side-by-side passes (each block after a
/// passing one twice as long, at most `MAX_TIMES_PER_BLOCK`), and the fewest keys and source
/// times per chunk of a block (a chunk much shorter costs more in waiting than it saves).
const TIMES_PER_BLOCK: usize = 256;
const MAX_TIMES_PER_BLOCK: usize = 4096;
const MIN_KEYS_PER_CHUNK: usize = 16;
const MIN_TIMES_PER_CHUNK: usize = 16;

/// `fill` on each of `items` with its row of `rows` (`width` entries per item), the items side by
/// side when `par` (each row written by its item alone: the same values either way).
fn fill_rows<I: Sync, O: Send>(
    items: &[I],
    rows: &mut [O],
    width: usize,
    par: bool,
    fill: impl Fn((&I, &mut [O])) + Sync + Send,
) {
    if width == 0 {
        return;
    }
    if par {
        items
            .par_iter()
            .zip(rows.par_chunks_mut(width))
            .for_each(fill);
    } else {
        items.iter().zip(rows.chunks_mut(width)).for_each(fill);
    }
}

/// Per chunk of `per` keys of `keys`, its range of each of `buffers` (per-key buffers, in order).
fn key_chunks<T>(
    buffers: &mut [Vec<T>],
    keys: std::ops::Range<usize>,
    per: usize,
) -> Vec<Vec<&mut [T]>> {
    let mut chunks: Vec<Vec<&mut [T]>> = (0..keys.len().div_ceil(per))
        .map(|_| Vec::with_capacity(buffers.len()))
        .collect();
    for v in buffers {
        for (c, s) in chunks.iter_mut().zip(v[keys.clone()].chunks_mut(per)) {
            c.push(s);
        }
    }
    chunks
}

/// One chunk of [`Eval::quantize_keys_side_by_side`]: its first key and its range of every
/// per-key buffer (per component, per rotation, and the model rotations).
struct KeyChunk<'s> {
    k0: usize,
    qi: Vec<&'s mut [u32]>,
    dec: Vec<&'s mut [f32]>,
    raw: Vec<&'s mut [Quat]>,
    rot: &'s mut [Quat],
}

/// Source times a first-width check measures first, most recent first: where the last checks
/// failed, and where the last passing ones had their largest errors ([`add_probe`]).
pub(super) type Probes = [Option<usize>; PROBES];

/// How many times [`Probes`] holds: a probe costs one time's poses, a check that fails late
/// nearly a whole pass.
pub(super) const PROBES: usize = 8;

/// Puts time `i` first in `probes` (moving it up if it is there, else dropping the oldest).
pub(super) fn add_probe(probes: &mut Probes, i: usize) {
    let at = probes
        .iter()
        .position(|&p| p == Some(i))
        .unwrap_or(PROBES - 1);
    probes.copy_within(0..at, 1);
    probes[0] = Some(i);
}

impl<'a> Eval<'a> {
    /// The state of `work` at `bits` before any key is quantized or any time computed.
    fn unquantized(
        ctx: &'a Ctx<'a>,
        layout: &'a Layout,
        work: &Work,
        bits: Vec<u8>,
        compensate: bool,
    ) -> Eval<'a> {
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
        Eval {
            ctx,
            layout,
            compensate,
            // Filled time by time ([`Eval::resample`]): a check that fails early touches little
            // of this memory (a fresh process pays a page fault for every page it touches). A
            // long clip's check leaves the local poses out ([`KEEP_LOCAL_BELOW`]).
            local_aff: if keeps_local(nj, at.len()) {
                Vec::with_capacity(nj * at.len())
            } else {
                Vec::new()
            },
            model: Vec::with_capacity(nj * at.len()),
            nj,
            parents: (0..nj)
                .map(|j| parents.get(j).copied().flatten().map(usize::from))
                .collect(),
            at,
            key_src,
            joint,
            track_of,
            first,
            subtree: &rig.subtree,
            subtree_parent: &rig.subtree_parent,
            base,
            params: (0..bits.len())
                .map(|i| layout.params(i / nc.max(1), i % nc.max(1), bits[i]))
                .collect(),
            bits,
            // Each row made on its own: `vec![row; count]` would copy the first row into every
            // other (a memcpy of megabytes on a long clip) where a zeroed allocation writes nothing.
            qi: (0..nc).map(|_| vec![0; n]).collect(),
            dec: (0..nc).map(|_| vec![0.0; n]).collect(),
            raw: (0..layout.index.len())
                .map(|_| vec![Quat::IDENTITY; n])
                .collect(),
            key_rot: vec![Quat::IDENTITY; nj * n],
            seg_times,
            first_key: 0,
            first_time: 0,
        }
    }

    /// The state of `work` quantized with `bits`, every key, and no source time computed: its
    /// stored integers (the same as [`Eval::build`]'s, key for key) for an encoding whose check
    /// is the runtime's ([`super::metric::errors_against`]) rather than this state's.
    pub(super) fn quantized(
        ctx: &'a Ctx<'a>,
        layout: &'a Layout,
        work: &Work,
        bits: Vec<u8>,
        compensate: bool,
    ) -> Eval<'a> {
        let mut e = Eval::unquantized(ctx, layout, work, bits, compensate);
        let n = layout.keys;
        if goes_side_by_side(n * e.nj) {
            e.quantize_keys_side_by_side(0..n, 2 * rayon::current_num_threads());
        } else {
            e.requantize_keys(0..n, &mut KeyRow::default());
        }
        e
    }

    /// The state of `work` quantized with `bits`. With `check`, also whether every joint is within
    /// its limit at every source time: `Err(i)` names a source time `i` where one is not, and the
    /// poses are then computed only up to there (the state is for the check alone); `Ok(i)` names
    /// the source time where the largest ratio of a joint's error to its limit is (0 without the
    /// check). `probes`: source times to check first (where a previous check failed, where a
    /// previous passing one had its largest error): their keys are quantized out of order, which
    /// changes nothing, as a key's quantization reads no other key.
    pub(super) fn build(
        ctx: &'a Ctx<'a>,
        layout: &'a Layout,
        work: &Work,
        bits: Vec<u8>,
        compensate: bool,
        check: bool,
        probes: Probes,
    ) -> (Eval<'a>, Result<usize, usize>) {
        let mut e = Eval::unquantized(ctx, layout, work, bits, compensate);
        let nj = e.nj;
        let n = layout.keys;
        let mut row = KeyRow::default();
        for &i in probes.iter().flatten() {
            if !check || i >= e.at.len() {
                continue;
            }
            let (k0, k1, a) = e.at[i];
            for k in [k0, k1]
                .into_iter()
                .filter(|&k| k < n && (k == k0 || a != 0.0))
            {
                e.requantize_key(k, &mut row);
            }
            if e.probe_fails(i) {
                return (e, Err(i));
            }
        }
        if goes_side_by_side(e.at.len() * nj) {
            let verdict = e.build_side_by_side(check);
            return (e, verdict);
        }
        let mut worst = (0.0f32, 0usize);
        // Keys are quantized as the source times reach them (a check that fails early leaves the
        // rest undone); every key is quantized in key order, as a whole pass would.
        let mut next = 0;
        let keep_local = keeps_local(nj, e.at.len());
        let mut local = vec![Affine3A::IDENTITY; if keep_local { 0 } else { nj }];
        for i in 0..e.at.len() {
            let need = e.keys_read_before(i);
            e.requantize_keys(next..need, &mut row);
            next = next.max(need);
            e.resample(i, (!keep_local).then_some(&mut local[..]));
            if check {
                let at = (i - e.first_time) * nj;
                match e.time_ratio(i, &e.model[at..at + nj]) {
                    None => return (e, Err(i)),
                    Some(r) if r > worst.0 => worst = (r, i),
                    Some(_) => {}
                }
            }
        }
        e.requantize_keys(next..n, &mut row);
        (e, Ok(worst.1))
    }

    /// The rest of [`Eval::build`] for a long clip, a block of source times at a time (each block
    /// after a passing one twice as long, up to [`MAX_TIMES_PER_BLOCK`]): the keys the block reads
    /// that are not quantized yet, in chunks side by side, each writing its own range of the
    /// state, then the block's transforms (and with `check`, its errors), in chunks side by side;
    /// a check stops after the first block where a joint is over its limit. The state is the one the sequential build
    /// gives, value for value, and so is the verdict (its failing time may be another failing
    /// one: it only serves as the next check's probe).
    fn build_side_by_side(&mut self, check: bool) -> Result<usize, usize> {
        let n = self.layout.keys;
        let nj = self.nj.max(1);
        let times = self.at.len();
        // Chunks per block: a few per thread, so that a thread that finishes early takes another.
        let chunks = 2 * rayon::current_num_threads().max(1);
        let mut next = 0;
        let mut worst = (0.0f32, 0usize);
        let mut t0 = 0;
        let mut block = TIMES_PER_BLOCK;
        while t0 < times {
            let t1 = (t0 + block).min(times);
            let need = self.keys_read_before(t1 - 1);
            self.quantize_keys_side_by_side(next..need.max(next), chunks);
            next = next.max(need);
            let keep = keeps_local(self.nj, times);
            let mut local = std::mem::take(&mut self.local_aff);
            let mut model = std::mem::take(&mut self.model);
            if keep {
                local.resize(t1 * nj, Affine3A::IDENTITY);
            }
            model.resize(t1 * nj, Affine3A::IDENTITY);
            let per = (t1 - t0).div_ceil(chunks).max(MIN_TIMES_PER_CHUNK);
            let state: &Eval = self;
            // One chunk: its first failing time, or its first time of the largest ratio. Its
            // local poses go into `kept` (the state's, when it keeps them) or a row of scratch.
            let chunk = |ci: usize, model: &mut [Affine3A], mut kept: Option<&mut [Affine3A]>| {
                let mut worst = (0.0f32, 0usize);
                let mut scratch = vec![Affine3A::IDENTITY; if kept.is_some() { 0 } else { nj }];
                for (t, model) in model.chunks_mut(nj).enumerate() {
                    let i = t0 + ci * per + t;
                    let local = match kept.as_deref_mut() {
                        Some(k) => &mut k[t * nj..(t + 1) * nj],
                        None => &mut scratch[..],
                    };
                    state.pose_into(i, local, model);
                    if check {
                        match state.time_ratio(i, model) {
                            None => return Err(i),
                            Some(r) if r > worst.0 => worst = (r, i),
                            Some(_) => {}
                        }
                    }
                }
                Ok(worst)
            };
            let found: Vec<Result<(f32, usize), usize>> = if keep {
                local[t0 * nj..]
                    .par_chunks_mut(per * nj)
                    .zip(model[t0 * nj..].par_chunks_mut(per * nj))
                    .enumerate()
                    .map(|(ci, (local, model))| chunk(ci, model, Some(local)))
                    .collect()
            } else {
                model[t0 * nj..]
                    .par_chunks_mut(per * nj)
                    .enumerate()
                    .map(|(ci, model)| chunk(ci, model, None))
                    .collect()
            };
            self.local_aff = local;
            self.model = model;
            for f in found {
                match f {
                    Err(i) => return Err(i),
                    Ok(w) if w.0 > worst.0 => worst = w,
                    Ok(_) => {}
                }
            }
            t0 = t1;
            // A check that passed this block likely passes: larger blocks, fewer waits.
            block = (2 * block).min(MAX_TIMES_PER_BLOCK);
        }
        self.quantize_keys_side_by_side(next..n.max(next), chunks);
        Ok(worst.1)
    }

    /// Quantizes `keys` ([`Eval::key_into`]; the state holds every key, from key 0) in about
    /// `chunks` runs side by side, each writing its own range of every per-key buffer.
    fn quantize_keys_side_by_side(&mut self, keys: std::ops::Range<usize>, chunks: usize) {
        let (len, nj) = (keys.len(), self.nj);
        if len == 0 || nj == 0 {
            self.requantize_keys(keys, &mut KeyRow::default());
            return;
        }
        let per = len.div_ceil(chunks.max(1)).max(MIN_KEYS_PER_CHUNK);
        let (mut qi, mut dec) = (std::mem::take(&mut self.qi), std::mem::take(&mut self.dec));
        let (mut raw, mut rot) = (
            std::mem::take(&mut self.raw),
            std::mem::take(&mut self.key_rot),
        );
        let parts: Vec<KeyChunk> = keys
            .clone()
            .step_by(per)
            .zip(key_chunks(&mut qi, keys.clone(), per))
            .zip(key_chunks(&mut dec, keys.clone(), per))
            .zip(key_chunks(&mut raw, keys.clone(), per))
            .zip(rot[keys.start * nj..keys.end * nj].chunks_mut(per * nj))
            .map(|((((k0, qi), dec), raw), rot)| KeyChunk {
                k0,
                qi,
                dec,
                raw,
                rot,
            })
            .collect();
        let state: &Eval = self;
        parts.into_par_iter().for_each(|mut p| {
            let mut row = KeyRow::default();
            for (at, k) in (p.k0..).take(p.rot.len() / nj).enumerate() {
                state.key_into(k, &mut row, &[]);
                for (c, &(q, x)) in row.q.iter().enumerate() {
                    p.qi[c][at] = q;
                    p.dec[c][at] = x;
                }
                for (ri, &r) in row.raw.iter().enumerate() {
                    p.raw[ri][at] = r;
                }
                p.rot[at * nj..(at + 1) * nj].copy_from_slice(&row.rot);
            }
        });
        (self.qi, self.dec, self.raw, self.key_rot) = (qi, dec, raw, rot);
    }

    /// [`Eval::build`] without the check, with its local poses ([`Eval::fill_local`]).
    pub(super) fn new(
        ctx: &'a Ctx<'a>,
        layout: &'a Layout,
        work: &Work,
        bits: Vec<u8>,
        compensate: bool,
    ) -> Eval<'a> {
        let mut e = Eval::build(ctx, layout, work, bits, compensate, false, [None; PROBES]).0;
        e.fill_local();
        e
    }

    pub(super) fn parent(&self, j: usize) -> Option<usize> {
        self.parents.get(j).copied().flatten()
    }

    /// Quantizes key `k`: every component of every joint, parents first (`row`: scratch space).
    /// (A change of one component is worked out by [`super::trial::Trial`].)
    fn requantize_key(&mut self, k: usize, row: &mut KeyRow) {
        self.key_into(k, row, &[]);
        self.store_key(k, row);
    }

    /// [`Eval::requantize_key`] for the joints `moved` marks alone (the others' values, which
    /// read nothing that changed, are the state's; a joint is marked with its subtree).
    pub(super) fn requantize_moved(&mut self, k: usize, row: &mut KeyRow, moved: &[bool]) {
        self.key_into(k, row, moved);
        self.store_key(k, row);
    }

    /// [`Eval::requantize_key`] for each of `keys`, in order.
    fn requantize_keys(&mut self, keys: std::ops::Range<usize>, row: &mut KeyRow) {
        for k in keys {
            self.requantize_key(k, row);
        }
    }

    /// One past the last key source time `i` reads (at most the key count): the keys that must
    /// be quantized before it is computed.
    fn keys_read_before(&self, i: usize) -> usize {
        let (k0, k1, a) = self.at[i];
        (if a != 0.0 { k0.max(k1) } else { k0 } + 1).min(self.layout.keys)
    }

    /// Key `k` quantized into `row`: every component's stored integer and decoded value, every
    /// rotation as decoded, every joint's model rotation (parents first). With `moved` (one flag
    /// per joint; empty: every joint), the joints not marked take the state's values.
    fn key_into(&self, k: usize, row: &mut KeyRow, moved: &[bool]) {
        let s = k / self.layout.seg_len.max(1);
        let nc = self.layout.comps.len();
        let at = k - self.first_key;
        row.q.resize(nc, (0, 0.0));
        row.raw.resize(self.layout.index.len(), Quat::IDENTITY);
        row.rot.resize(self.nj, Quat::IDENTITY);
        for d in 0..self.nj {
            if moved.get(d).is_some_and(|m| !m) {
                if let Some(tr) = self.track_of[d] {
                    for c0 in self.first[tr].into_iter().flatten() {
                        for c in c0..c0 + 3 {
                            row.q[c] = (self.qi[c][at], self.dec[c][at]);
                        }
                    }
                    if let Some(c0) = self.first[tr][Kind::R as usize] {
                        let ri = self.layout.comps[c0].rot;
                        row.raw[ri] = self.raw[ri][at];
                    }
                }
                row.rot[d] = self.key_rot[at * self.nj + d];
                continue;
            }
            let pr = self.parent(d).map_or(Quat::IDENTITY, |p| row.rot[p]);
            let mut rot = self.base[d].rotation;
            if let Some(tr) = self.track_of[d] {
                let [ft, fr, fs] = self.first[tr];
                for c0 in [ft, fs].into_iter().flatten() {
                    for c in c0..c0 + 3 {
                        let v = self.layout.comps[c].vals[k];
                        row.q[c] = self.params[s * nc + c].quantize(v);
                    }
                }
                if let Some(c0) = fr {
                    let ri = self.layout.comps[c0].rot;
                    let index = self.layout.index[ri][k];
                    let vals = self.values_of(c0, k, self.compensated(d, k, pr));
                    for (a, v) in vals.into_iter().enumerate() {
                        row.q[c0 + a] = self.params[s * nc + c0 + a].quantize(v);
                    }
                    let raw = raw_rotation(index, [0, 1, 2].map(|a| row.q[c0 + a].1));
                    row.raw[ri] = raw;
                    rot = normalize_rotation(raw);
                }
            }
            row.rot[d] = pr * rot;
        }
    }

    /// Writes key `k`'s quantized values ([`Eval::key_into`]) into the state.
    fn store_key(&mut self, k: usize, row: &KeyRow) {
        let at = k - self.first_key;
        for (c, &(q, x)) in row.q.iter().enumerate() {
            self.qi[c][at] = q;
            self.dec[c][at] = x;
        }
        for (ri, &raw) in row.raw.iter().enumerate() {
            self.raw[ri][at] = raw;
        }
        self.key_rot[at * self.nj..(at + 1) * self.nj].copy_from_slice(&row.rot);
    }

    /// With chain compensation at a source key: the rotation that gives joint `d` its source
    /// model rotation under its parent's model rotation `pr`, before normalisation
    /// ([`Eval::values_of`] gives its stored components). `None` where the stored components are
    /// the source values.
    #[inline]
    pub(super) fn compensated(&self, d: usize, k: usize, pr: Quat) -> Option<Quat> {
        match self.key_src[k] {
            Some(i) if self.compensate => Some(pr.inverse() * self.ctx.src_rot[i * self.nj + d]),
            _ => None,
        }
    }

    /// The three stored components of the rotation with first component `c0` at key `k`: those
    /// of its compensated rotation ([`Eval::compensated`]), or the source values without one.
    #[inline]
    pub(super) fn values_of(&self, c0: usize, k: usize, compensated: Option<Quat>) -> [f32; 3] {
        match compensated {
            Some(u) => {
                let index = self.layout.index[self.layout.comps[c0].rot][k];
                three_without(u.normalize(), index)
            }
            None => [0, 1, 2].map(|a| self.layout.comps[c0 + a].vals[k]),
        }
    }

    /// Computes every joint's local pose and model transform at source time `i` (parents first),
    /// the local poses into `scratch` (one row) where the state leaves them out
    /// ([`KEEP_LOCAL_BELOW`]). While the state is being built, the times are computed in order and
    /// each one's transforms are appended; after that, they are replaced.
    fn resample(&mut self, i: usize, scratch: Option<&mut [Affine3A]>) {
        let nj = self.nj;
        let row = (i - self.first_time) * nj;
        if row == self.model.len() {
            self.model.resize(row + nj, Affine3A::IDENTITY);
            if scratch.is_none() {
                self.local_aff.resize(row + nj, Affine3A::IDENTITY);
            }
        }
        let mut local = std::mem::take(&mut self.local_aff);
        let mut model = std::mem::take(&mut self.model);
        let local_row = match scratch {
            Some(s) => s,
            None => &mut local[row..row + nj],
        };
        self.pose_into(i, local_row, &mut model[row..row + nj]);
        self.local_aff = local;
        self.model = model;
    }

    /// Fills in the local poses of a whole state whose model transforms are computed (a checked
    /// build leaves them out): the values [`Eval::pose_into`] computes, time by time (side by
    /// side for a long clip). A state that has them is left as it is.
    pub(super) fn fill_local(&mut self) {
        let nj = self.nj;
        if nj == 0 || self.local_aff.len() == self.model.len() {
            return;
        }
        let times = self.model.len() / nj;
        let mut local = std::mem::take(&mut self.local_aff);
        local.clear();
        local.resize(times * nj, Affine3A::IDENTITY);
        let state: &Eval = self;
        // Through `pose_into` (its model transforms into one row of scratch space), so that the
        // local poses are the ones a build computes and `local_pose` keeps the one caller it is
        // inlined into (called from here too, it was not, and the Half-Life batch took 2% more
        // CPU). `rows` starts at time `t0`.
        let fill = |t0: usize, rows: &mut [Affine3A]| {
            let mut models = vec![Affine3A::IDENTITY; nj];
            for (t, row) in rows.chunks_mut(nj).enumerate() {
                state.pose_into(state.first_time + t0 + t, row, &mut models);
            }
        };
        if goes_side_by_side(times * nj) {
            local
                .par_chunks_mut(MIN_TIMES_PER_CHUNK * nj)
                .enumerate()
                .for_each(|(c, rows)| fill(c * MIN_TIMES_PER_CHUNK, rows));
        } else {
            fill(0, &mut local);
        }
        self.local_aff = local;
    }

    /// Every joint's local and model transform at source time `i` into `local` and `model` (one
    /// per joint, parents first), the anchors' model transforms rebased on the source's origins at
    /// `i` ([`Rig::rebase`]).
    fn pose_into(&self, i: usize, local: &mut [Affine3A], model: &mut [Affine3A]) {
        self.pose_moved_into(i, local, model, &[]);
    }

    /// [`Eval::pose_into`] for the joints `moved` marks (one flag per joint, a joint marked with
    /// its subtree; empty: every joint); the others' entries of `local` and `model` are left as
    /// they are (the state's, which read nothing that changed).
    pub(super) fn pose_moved_into(
        &self,
        i: usize,
        local: &mut [Affine3A],
        model: &mut [Affine3A],
        moved: &[bool],
    ) {
        let origins = self.origins_at(i);
        // The anchors are in joint order: each compared with in turn (most rigs have one).
        let mut anchors = self.ctx.rig.anchors.iter().enumerate();
        let mut next = anchors.next();
        for d in 0..self.nj {
            let anchor = next.filter(|&(_, &a)| a == d);
            if anchor.is_some() {
                next = anchors.next();
            }
            if moved.get(d).is_some_and(|m| !m) {
                continue;
            }
            local[d] = self.local_pose(d, i).to_affine();
            let pm = self.parent(d).map_or(Affine3A::IDENTITY, |p| model[p]);
            model[d] = pm * local[d];
            if let Some((slot, _)) = anchor {
                rebase_on(&mut model[d], origins, slot);
            }
        }
    }

    /// The origins of source time `i` (one per anchor).
    #[inline]
    pub(super) fn origins_at(&self, i: usize) -> &[Vec3] {
        self.ctx.rig.origins_at(&self.ctx.origins, i)
    }

    /// The largest ratio of a joint's error to its limit at source time `i` with the model
    /// transforms `model` (one per joint), or `None` when one exceeds its limit.
    fn time_ratio(&self, i: usize, model: &[Affine3A]) -> Option<f32> {
        let mut worst = 0.0f32;
        let nj = self.nj.min(model.len());
        let src = &self.ctx.src_flat[i * self.nj..i * self.nj + nj];
        let (scales, limits) = (&self.ctx.rig.point_scale[..nj], &self.ctx.limits[..nj]);
        for j in 0..nj {
            let error = point_distance(&src[j], scales[j], &model[j]);
            let limit = limits[j];
            if exceeds(error, limit) {
                return None;
            }
            worst = worst.max(error / limit);
        }
        Some(worst)
    }

    /// Whether some joint exceeds its limit at source time `i`, computed apart from the state
    /// (the probe of [`Eval::build`], before the times ahead of it are computed): the same
    /// transforms [`Eval::resample`] computes.
    fn probe_fails(&self, i: usize) -> bool {
        let mut local = vec![Affine3A::IDENTITY; self.nj];
        let mut model = vec![Affine3A::IDENTITY; self.nj];
        self.pose_into(i, &mut local, &mut model);
        self.time_ratio(i, &model).is_none()
    }

    /// Joint `d`'s local pose at source time `i`: its track's, or its base pose without one.
    fn local_pose(&self, d: usize, i: usize) -> Transform {
        match self.track_of[d] {
            Some(tr) => self.sampled(tr, i, self.base[d]),
            None => self.base[d],
        }
    }

    /// Track `tr`'s local transform at source time `i` (animated channels replaced in `base`), as
    /// the sampler computes it.
    pub(super) fn sampled(&self, tr: usize, i: usize, base: Transform) -> Transform {
        self.sampled_with(
            tr,
            i,
            base,
            |c, k| self.dec[c][k - self.first_key],
            |ri, k| self.raw[ri][k - self.first_key],
        )
    }

    /// [`Eval::sampled`] with the decoded values (component, key) and decoded rotations (rotation
    /// number, key) read through `dec` and `raw`.
    #[inline(always)]
    pub(super) fn sampled_with(
        &self,
        tr: usize,
        i: usize,
        mut base: Transform,
        dec: impl Fn(usize, usize) -> f32,
        raw: impl Fn(usize, usize) -> Quat,
    ) -> Transform {
        let (k0, k1, a) = self.at[i];
        let [ft, fr, fs] = self.first[tr];
        let vec3 = |c: usize, k: usize| Vec3::new(dec(c, k), dec(c + 1, k), dec(c + 2, k));
        let quat = |c: usize, k: usize| raw(self.layout.comps[c].rot, k);
        if a == 0.0 {
            if let Some(c) = ft {
                base.translation = vec3(c, k0);
            }
            if let Some(c) = fs {
                base.scale = vec3(c, k0);
            }
            if let Some(c) = fr {
                base.rotation = normalize_rotation(quat(c, k0));
            }
        } else {
            if let Some(c) = ft {
                base.translation = vec3(c, k0).lerp(vec3(c, k1), a);
            }
            if let Some(c) = fs {
                base.scale = vec3(c, k0).lerp(vec3(c, k1), a);
            }
            if let Some(c) = fr {
                base.rotation = nlerp(quat(c, k0), quat(c, k1), a);
            }
        }
        base
    }

    pub(super) fn joint_error(&self, i: usize, j: usize) -> f32 {
        self.error_at(i, j, &self.model[(i - self.first_time) * self.nj + j])
    }

    /// Joint `j`'s error at source time `i` with model transform `m`: the largest distance of its
    /// three error points from the source's. The points are `m`'s axes scaled by the rig's
    /// `point_scale` plus its translation (what `m.transform_point3` gives for an axis point: the
    /// other axes' terms are zeros), and the largest squared distance is rooted once (the square
    /// root is monotonic and correctly rounded): the same value as measuring each distance.
    #[inline]
    pub(super) fn error_at(&self, i: usize, j: usize, m: &Affine3A) -> f32 {
        point_distance(
            &self.ctx.src_flat[i * self.nj + j],
            self.ctx.rig.point_scale[j],
            m,
        )
    }

    /// True when every joint is within its limit at every source time.
    #[cfg(test)]
    pub(super) fn within(&self) -> bool {
        (0..self.at.len()).all(|i| {
            (0..self.ctx.limits.len()).all(|j| self.joint_error(i, j) <= self.ctx.limits[j])
        })
    }

    /// The compressed clip of the current state.
    pub(super) fn encode(&self, work: &Work) -> Option<Clip> {
        self.layout
            .encode(&self.bits, &self.qi, work, self.ctx.like)
    }
}

/// The largest distance of the error points of model transform `m` (its axes scaled by `scale`,
/// the rig's `point_scale`, plus its translation) from the source's points `src`
/// ([`Eval::error_at`]).
#[inline]
pub(super) fn point_distance(src: &[Vec3; 3], scale: f32, m: &Affine3A) -> f32 {
    let axes = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
    let mut worst = 0.0f32;
    for (axis, src) in axes.iter().zip(src) {
        let d = Vec3::from(*axis * scale + m.translation) - *src;
        worst = worst.max(d.x * d.x + d.y * d.y + d.z * d.z);
    }
    worst.sqrt()
}
