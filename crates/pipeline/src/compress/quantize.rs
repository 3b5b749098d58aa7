//! Quantisation: per-component ranges, segments, bit widths and the smallest-three rotation split.

use super::metric::Rig;
use super::reduce::{WChan, WTrack, Work};
use rayon::prelude::*;
use sinew_core::compressed::{
    compact_range_units, compact_rotation_range, dequant_params, pack, shared_indices,
    smallest_three, three_without, QuantizedParts, SegmentComponent, MAX_BITS,
};
use sinew_core::format::clip_record_size;
use sinew_core::glam::Quat;
use sinew_core::Clip;
use std::sync::{Arc, OnceLock};

/// Which channel of a track a component belongs to.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Kind {
    T,
    R,
    S,
}

/// One quantized component: its values at the kept keys and where it comes from.
pub(super) struct Comp {
    pub(super) vals: Vec<f32>,
    /// A-priori error per unit of value, model units (used for the first bit widths only).
    pub(super) gain: f32,
    pub(super) track: usize,
    pub(super) kind: Kind,
    pub(super) axis: usize,
    /// For rotation components: the rotation's number (component order).
    pub(super) rot: usize,
}

/// Smallest magnitude a dropped quaternion component may have: the largest of four unit components
/// is at least 0.5, so dropping any component of at least this size rebuilds it no less precisely
/// than dropping the largest could in the worst case.
pub(super) const MIN_DROPPED: f32 = 0.5;

/// Splits a rotation track into per-key (index, three components). The dropped component stays the
/// same from key to key while its magnitude is at least [`MIN_DROPPED`] (switching to the largest
/// otherwise), so the stored components do not jump where two components trade places as the
/// largest; of the four possible first indices (and the plain largest-per-key split) the one whose
/// component ranges are narrowest (sum of log2 of the ranges) is kept.
pub(super) fn split_rotations(v: &[Quat]) -> Vec<(u8, [f32; 3])> {
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
/// The parts that do not depend on the segment length ([`Components`]) are shared by the layouts
/// of one set of kept keys.
pub(super) struct Layout {
    pub(super) keys: usize,
    pub(super) seg_len: usize,
    pub(super) seg_count: usize,
    pub(super) comps: Arc<Vec<Comp>>,
    pub(super) starts: Arc<Vec<bool>>,
    /// Per rotation, per key: the index of the dropped quaternion component.
    pub(super) index: Arc<Vec<Vec<u8>>>,
    pub(super) ranges: Arc<Vec<[f32; 2]>>,
    /// Per segment, per component (segment-major): the sub-range (`bits` is set later).
    pub(super) sub: Vec<SegmentComponent>,
    /// Per segment: how many rotations store their index per key (2 bits per key each).
    pub(super) per_key_index: Vec<usize>,
    /// Every rotation range has its 16-bit form, so the record is compact.
    compact: bool,
    /// The size of the record's parts before its segment entries (see [`Layout::record_size`]),
    /// the same for every layout of one [`Components`], once worked out.
    prefix: Arc<OnceLock<Option<usize>>>,
}

/// The components of one set of kept keys (values, gains, smallest-three splits, clip ranges):
/// what every segment length's [`Layout`] of it shares.
pub(super) struct Components {
    keys: usize,
    comps: Arc<Vec<Comp>>,
    starts: Arc<Vec<bool>>,
    index: Arc<Vec<Vec<u8>>>,
    ranges: Arc<Vec<[f32; 2]>>,
    prefix: Arc<OnceLock<Option<usize>>>,
}

/// How one component of one segment is quantized: `value = bias + scale * q`, `q <= top`; `inv`
/// is `1 / scale` as f32 rounds it (0 without a scale), for [`Quant::keeps`].
#[derive(Clone, Copy, Default)]
pub(super) struct Quant {
    pub(super) scale: f32,
    pub(super) bias: f32,
    pub(super) top: u32,
    inv: f32,
}

impl Quant {
    /// The parameters `value = bias + scale * q`, `q <= top`, with their reciprocal scale.
    pub(super) fn new(scale: f32, bias: f32, top: u32) -> Quant {
        Quant {
            scale,
            bias,
            top,
            inv: if scale > 0.0 { 1.0 / scale } else { 0.0 },
        }
    }

    /// The stored integer nearest to `v` and the value it decodes to (as the decoder computes it).
    pub(super) fn quantize(self, v: f32) -> (u32, f32) {
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

    /// Whether every value within `margin` of `v` quantizes to `q` ([`Quant::quantize`]): `v`'s
    /// place among the integers' rounding intervals, worked out with a multiplication, must be
    /// inside `q`'s by more than the margin plus what the rounding of this arithmetic and of
    /// `quantize`'s own may move it by (a few parts in 1e7 of it). False for a NaN, and near the
    /// interval's ends, where it may be true.
    pub(super) fn keeps(self, v: f32, margin: f32, q: u32) -> bool {
        if self.scale <= 0.0 || self.top == 0 {
            // Every value quantizes to 0.
            return !v.is_nan();
        }
        let y = (v - self.bias) * self.inv;
        let slack = margin * self.inv * 1.0001 + (y.abs() + 1.0) * 4e-7;
        let f = y + 0.5 - q as f32;
        (q == 0 || f >= slack) && (q >= self.top || f <= 1.0 - slack) && !v.is_nan()
    }
}

/// The segment sub-range of values `keys` inside the clip range `lo .. lo + ext`: the 8-bit
/// fractions `min` and `extent` whose decoded range covers every value.
pub(super) fn sub_range(range: [f32; 2], keys: &[f32]) -> SegmentComponent {
    let [lo, ext] = range;
    let mut e = SegmentComponent::default();
    if ext <= 0.0 || keys.is_empty() {
        // Nothing to narrow: the whole (empty) range, which a record of whole ranges leaves out
        // (it decodes to the same value as any other sub-range of an empty range).
        e.extent = 255;
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

/// One key of a split rotation track ([`split_rotations`]): the dropped component's index and the
/// three stored components.
type SplitKey = (u8, [f32; 3]);

/// Joint-keys from which [`Components::new`] splits the rotation tracks side by side.
const SPLIT_SIDE_BY_SIDE: usize = 16 * 1024;

impl Components {
    pub(super) fn new(work: &Work, rig: &Rig, compensate: bool) -> Components {
        let n = work.times.len();
        let mut comps: Vec<Comp> = Vec::new();
        let mut starts: Vec<bool> = Vec::new();
        let mut index: Vec<Vec<u8>> = Vec::new();
        let mut compensating = vec![false; rig.skeleton.len()];
        for t in &work.tracks {
            if let (Some(j), WChan::Keys(_)) = (rig.skeleton.find(&t.joint), &t.r) {
                compensating[usize::from(j)] = compensate;
            }
        }
        let levers = rig.levers(&compensating);
        // Each rotation track's split (most of the work here), one track per job on a long clip.
        let split_of = |t: &WTrack| match &t.r {
            WChan::Keys(v) => Some(split_rotations(v)),
            _ => None,
        };
        let mut splits: Vec<Option<Vec<SplitKey>>> = if n * work.tracks.len() >= SPLIT_SIDE_BY_SIDE
        {
            work.tracks.par_iter().map(split_of).collect()
        } else {
            work.tracks.iter().map(split_of).collect()
        };
        for (track, t) in work.tracks.iter().enumerate() {
            let j = rig.skeleton.find(&t.joint).map_or(0, usize::from);
            let reach = rig.reach.get(j).copied().unwrap_or(1.0);
            let lever = if compensate {
                levers.get(j).copied().unwrap_or(1.0)
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
            if let Some(split) = splits[track].take() {
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
        let ranges: Vec<[f32; 2]> = comps
            .iter()
            .map(|c| {
                let lo = c.vals.iter().copied().fold(f32::MAX, f32::min);
                let hi = c.vals.iter().copied().fold(f32::MIN, f32::max);
                if n == 0 {
                    [0.0, 0.0]
                } else if c.kind == Kind::R {
                    // The 16-bit range a compact record stores (it covers the values; a step of
                    // 2^-15 wider at most).
                    compact_rotation_range(lo, hi).unwrap_or([lo, (hi - lo).max(0.0)])
                } else {
                    [lo, (hi - lo).max(0.0)]
                }
            })
            .collect();
        Components {
            keys: n,
            comps: Arc::new(comps),
            starts: Arc::new(starts),
            index: Arc::new(index),
            ranges: Arc::new(ranges),
            prefix: Arc::new(OnceLock::new()),
        }
    }
}

impl Layout {
    /// The layout of `work` in segments of `seg_len` keys.
    #[cfg(test)]
    pub(super) fn new(work: &Work, rig: &Rig, seg_len: usize, compensate: bool) -> Layout {
        Layout::with_segments(&Components::new(work, rig, compensate), seg_len)
    }

    /// The layout of `base`'s components in segments of `seg_len` keys.
    pub(super) fn with_segments(base: &Components, seg_len: usize) -> Layout {
        let n = base.keys;
        let seg_len = seg_len.clamp(1, n.max(1));
        let comps = &base.comps;
        let ranges = &base.ranges;
        let index = &base.index;
        let nc = comps.len();
        let seg_count = n.div_ceil(seg_len);
        let mut sub = vec![SegmentComponent::default(); seg_count * nc];
        for s in 0..seg_count {
            let keys = s * seg_len..((s + 1) * seg_len).min(n);
            for (c, comp) in comps.iter().enumerate() {
                sub[s * nc + c] = sub_range(ranges[c], &comp.vals[keys.clone()]);
            }
        }
        let rotations = index.len();
        let compact = comps
            .iter()
            .zip(ranges.iter())
            .all(|(c, r)| c.kind != Kind::R || compact_range_units(*r).is_some());
        let per_key_index = (0..seg_count)
            .map(|s| {
                let keys = s * seg_len..((s + 1) * seg_len).min(n);
                if !compact {
                    return rotations;
                }
                index
                    .iter()
                    .filter(|list| {
                        let i0 = list[keys.start];
                        list[keys.clone()].iter().any(|&i| i != i0)
                    })
                    .count()
            })
            .collect();
        Layout {
            keys: n,
            seg_len,
            seg_count,
            comps: Arc::clone(comps),
            starts: Arc::clone(&base.starts),
            index: Arc::clone(index),
            ranges: Arc::clone(ranges),
            sub,
            per_key_index,
            compact,
            prefix: Arc::clone(&base.prefix),
        }
    }

    pub(super) fn seg_keys(&self, s: usize) -> std::ops::Range<usize> {
        s * self.seg_len..((s + 1) * self.seg_len).min(self.keys)
    }

    /// The quantization parameters of component `c` in segment `s` at `bits`.
    pub(super) fn params(&self, s: usize, c: usize, bits: u8) -> Quant {
        let e = SegmentComponent {
            bits,
            ..self.sub[s * self.comps.len() + c]
        };
        let (scale, bias) = dequant_params(self.ranges[c], e);
        Quant::new(scale, bias, ((1u64 << bits) - 1) as u32)
    }

    /// First bit widths (per segment, per component): the fewest whose a-priori error bound
    /// (`gain` x half a quantization step) stays within `budget` model units.
    pub(super) fn first_bits(&self, budget: f32) -> Vec<u8> {
        let nc = self.comps.len();
        let mut bits = vec![0u8; self.sub.len()];
        for (i, e) in self.sub.iter().enumerate() {
            let c = i % nc.max(1);
            let allowed = budget / self.comps[c].gain.max(1e-12);
            let seg_ext = self.ranges[c][1] * (f32::from(e.extent) / 255.0);
            let mut b = 0u8;
            while b < MAX_BITS {
                if half_step(seg_ext, b) <= allowed {
                    break;
                }
                b += 1;
            }
            bits[i] = b;
        }
        bits
    }

    /// The a-priori error bound of [`Layout::first_bits`] for component `c` of segment `s` at
    /// `bits`, in model units: its gain times half a quantization step.
    pub(super) fn first_bound(&self, s: usize, c: usize, bits: u8) -> f32 {
        let e = self.sub[s * self.comps.len() + c];
        let seg_ext = self.ranges[c][1] * (f32::from(e.extent) / 255.0);
        half_step(seg_ext, bits) * self.comps[c].gain.max(1e-12)
    }

    /// The size of the clip record [`Layout::encode`] gives with these bit widths (whatever the
    /// stored integers): the parts before the segment entries (the same for every segment length,
    /// worked out once by encoding), the segment entries and the shared rotation indices (each
    /// padded to 16 bytes, as the writer pads them), then each segment's keys of `R_s` bits.
    pub(super) fn record_size(&self, bits: &[u8], work: &Work, like: &Clip) -> Option<usize> {
        let prefix = *self.prefix.get_or_init(|| {
            let zero = vec![0u8; bits.len()];
            let qi: Vec<Vec<u32>> = (0..self.comps.len()).map(|_| vec![0; self.keys]).collect();
            let size = clip_record_size(&self.encode(&zero, &qi, work, like)?);
            size.checked_sub(self.entries_size() + self.data_size(&zero))
        });
        prefix.map(|p| p + self.entries_size() + self.data_size(bits))
    }

    /// The record's segment entries and shared rotation indices, padded as the writer pads them.
    fn entries_size(&self) -> usize {
        let pad = |n: usize| n.div_ceil(16) * 16;
        let entries = self.sub.len();
        let whole = self.sub.iter().all(|e| e.min == 0 && e.extent == 255);
        let ranges = if whole { 0 } else { 2 * entries };
        let rotations = self.index.len();
        let shared = if self.compact && rotations > 0 {
            pad(self.seg_count * rotations)
        } else {
            0
        };
        pad((5 * entries).div_ceil(8) + ranges) + shared
    }

    /// The record's data: per segment, its keys of `R_s` bits, in whole bytes.
    fn data_size(&self, bits: &[u8]) -> usize {
        let nc = self.comps.len();
        (0..self.seg_count)
            .map(|s| {
                let seg = &bits[s * nc..(s + 1) * nc];
                let record: usize =
                    seg.iter().map(|&b| usize::from(b)).sum::<usize>() + 2 * self.per_key_index[s];
                (record * self.seg_keys(s).len()).div_ceil(8)
            })
            .sum()
    }

    /// The compressed clip with these bit widths and stored integers (per component, per key).
    pub(super) fn encode(
        &self,
        bits: &[u8],
        qi: &[Vec<u32>],
        work: &Work,
        like: &Clip,
    ) -> Option<Clip> {
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
        // Rotation indices shared by a whole segment are stored once (a compact record), when every
        // rotation range has its 16-bit form.
        let rotation_index = if self.compact && rotations > 0 {
            shared_indices(n, self.seg_len, rotations, &idx)
        } else {
            Vec::new()
        };
        let data = pack(
            n,
            self.seg_len,
            &segments,
            &rotation_index,
            self.starts.as_slice(),
            &q,
            &idx,
        );
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
                ranges: self.ranges.to_vec(),
                segments,
                rotation_index,
                data,
            },
        )
        .ok()
    }
}

/// The rotation the decoder rebuilds from a smallest-three split, before normalisation (the same
/// arithmetic as `sinew_core::compressed`).
pub(super) fn raw_rotation(index: u8, v: [f32; 3]) -> Quat {
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
pub(super) fn locate(like: &Clip, times: &[f32], t: f32) -> (usize, usize, f32) {
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

/// Half a quantization step of a range `extent` wide at `bits` (half the range at 0 bits, where
/// its middle is stored).
fn half_step(extent: f32, bits: u8) -> f32 {
    if bits == 0 {
        extent * 0.5
    } else {
        extent / ((1u32 << bits) - 1) as f32 * 0.5
    }
}

#[cfg(test)]
mod keeps_tests {
    use super::Quant;

    /// `keeps` is a sufficient condition: wherever it holds, every value within the margin (its
    /// ends, the floats next to them and points between) quantizes to the same integer; and it
    /// holds for most values away from an interval's ends (else the trials it saves would all
    /// be made in full).
    #[test]
    fn a_kept_integer_is_the_integer_of_every_value_within_the_margin() {
        let mut s = 0x9e37_79b9u32;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s as f32 / u32::MAX as f32
        };
        let (mut kept, mut centred) = (0, 0);
        for case in 0..20_000 {
            let bits = 1 + case % 16;
            let top = (1u32 << bits) - 1;
            // Ranges from a few float steps per integer to wide ones, around 0 and off it.
            let extent = [1e-4f32, 1e-3, 0.05, 1.4][case % 4] * (0.5 + rnd());
            let bias = (rnd() - 0.5) * 1.5;
            let quant = Quant::new(extent / top as f32, bias, top);
            let (v, margin) = if case % 3 == 0 {
                // A few float steps from an interval's end, with a margin of a few steps.
                let k = (rnd() * top as f32) as u32;
                let end = bias + quant.scale * (k as f32 + 0.5);
                let ulp = end.abs() * f32::EPSILON + 1e-30;
                (end + (rnd() - 0.5) * 16.0 * ulp, rnd() * 4.0 * ulp)
            } else {
                let v = bias + extent * (rnd() * 1.2 - 0.1);
                (
                    v,
                    [0.0f32, 1e-7, 1e-6, quant.scale * 0.3][case % 4 / 2 + case % 2],
                )
            };
            let q = quant.quantize(v).0;
            if !quant.keeps(v, margin, q) {
                continue;
            }
            kept += 1;
            for x in [
                v - margin,
                v + margin,
                f32::from_bits((v - margin).to_bits().wrapping_sub(1)),
                v,
                v - margin * 0.5,
                v + margin * 0.5,
            ] {
                if (x - v).abs() <= margin {
                    assert_eq!(
                        quant.quantize(x).0,
                        q,
                        "case {case}: {x} near {v} ± {margin}"
                    );
                }
            }
            let y = (v - bias) / quant.scale;
            if (y - y.round()).abs() < 0.25 && margin < quant.scale * 0.1 && q > 0 && q < top {
                centred += 1;
            }
        }
        assert!(kept > 8_000, "{kept}");
        assert!(centred > 1_000, "{centred}");
        // NaN is never kept.
        let quant = Quant::new(0.01, 0.0, 255);
        assert!(!quant.keeps(f32::NAN, 0.0, 0));
    }
}
