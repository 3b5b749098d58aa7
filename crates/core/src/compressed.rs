//! Quantized clip storage: the decoder side of error-bounded keyframe compression.
//!
//! A compressed [`crate::Clip`] keeps the plain clip's key times and track list, but its animated
//! channels are not `f32` frames: every animated channel is split into scalar *components* (translation
//! x y z, rotation as the three smallest quaternion components plus a 2-bit index of the largest, scale
//! x y z), numbered in track order (translation, rotation, scale of track 0, then track 1, ...). A
//! channel's [`crate::Channel::Animated`] value is the number of its first component.
//!
//! Keys are grouped into *segments* of `segment_len` consecutive keys. Every component has a clip range
//! (`min`, `extent`, f32) and, per segment, a sub-range given as two 8-bit fractions of the clip range
//! and a bit width `0..=24`. Each key of a segment is one fixed-size bit record (time-major: all
//! components of one key together), so any key is found by arithmetic. A value decodes as
//! `bias + scale * q` where, with `lo = min + extent * smin / 255` and `ext = extent * sext / 255`,
//! `scale = ext / (2^bits - 1)` and `bias = lo` (for `bits == 0`: `scale = 0`, `bias = lo + ext / 2`).
//! See docs/format.md for the byte layout.
//!
//! A rotation's 2-bit index is stored per key, or once per segment when every key of the segment
//! drops the same component ([`QuantizedParts::rotation_index`]); with the usual smallest-three
//! hysteresis that is most segments, and it saves two bits per rotation and key. Rotation
//! component ranges of such *compact* clips are multiples of 2^-15 ([`compact_rotation_range`]), so
//! that a file stores them in 16 bits each.

use glam::{Quat, Vec4};

/// Largest bit width a component may use.
pub const MAX_BITS: u8 = 24;
/// Bits of the index of the largest quaternion component stored before each rotation.
pub const ROTATION_INDEX_BITS: u32 = 2;
/// [`QuantizedParts::rotation_index`] entry of a rotation whose index is stored in every key.
pub const INDEX_PER_KEY: u8 = 255;
/// Rotation ranges of compact clips are multiples of `1 / RANGE_UNITS`.
pub const RANGE_UNITS: f32 = 32768.0;

/// The smallest range `[min, extent]` that covers `lo ..= hi` and whose `min + 1` and `extent` are
/// multiples of 2^-15 below 2 (so a file stores each in 16 bits: `min = q / 2^15 - 1`,
/// `extent = q / 2^15`); `None` when `lo ..= hi` is not inside that span (not a smallest-three
/// rotation component).
pub fn compact_rotation_range(lo: f32, hi: f32) -> Option<[f32; 2]> {
    if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
        return None;
    }
    let qmin = ((lo + 1.0) * RANGE_UNITS).floor();
    if !(0.0..=65535.0).contains(&qmin) {
        return None;
    }
    let min = qmin / RANGE_UNITS - 1.0;
    let mut qext = ((hi - min) * RANGE_UNITS).ceil().max(0.0);
    // Rounding in `hi - min` may leave the top a step short.
    while qext <= 65535.0 && min + qext / RANGE_UNITS < hi {
        qext += 1.0;
    }
    if qext > 65535.0 {
        return None;
    }
    Some([min, qext / RANGE_UNITS])
}

/// The 16-bit form of a range [`compact_rotation_range`] gives, if it is one.
pub fn compact_range_units(range: [f32; 2]) -> Option<[u16; 2]> {
    let qmin = (range[0] + 1.0) * RANGE_UNITS;
    let qext = range[1] * RANGE_UNITS;
    let ok = |q: f32| (0.0..=65535.0).contains(&q) && q.fract() == 0.0;
    let back = [qmin / RANGE_UNITS - 1.0, qext / RANGE_UNITS];
    (ok(qmin) && ok(qext) && back[0].to_bits() == range[0].to_bits() && back[1] == range[1])
        .then_some([qmin as u16, qext as u16])
}

/// The range a 16-bit pair of a compact clip stands for.
pub fn range_from_units(units: [u16; 2]) -> [f32; 2] {
    [
        f32::from(units[0]) / RANGE_UNITS - 1.0,
        f32::from(units[1]) / RANGE_UNITS,
    ]
}

/// One component's parameters inside one segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SegmentComponent {
    /// Bits per key, `0..=MAX_BITS`.
    pub bits: u8,
    /// Start of the segment range as a fraction `min / 255` of the clip range.
    pub min: u8,
    /// Length of the segment range as a fraction `extent / 255` of the clip range.
    pub extent: u8,
}

/// What a compressed clip stores besides its times and tracks (the encoder's output, the reader's input).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct QuantizedParts {
    /// Keys per segment (the last segment may be shorter); at least 1.
    pub segment_len: u32,
    /// Per component: clip range `[min, extent]`, finite, `extent >= 0`.
    pub ranges: Vec<[f32; 2]>,
    /// Per segment, per component (segment-major): `segments[s * components + c]`.
    pub segments: Vec<SegmentComponent>,
    /// Per segment, per rotation (segment-major, rotations in component order): the index of the
    /// dropped component for every key of the segment (`0..=3`), or [`INDEX_PER_KEY`] when each key
    /// stores its own. Empty: every key stores every index (files before 1.4).
    pub rotation_index: Vec<u8>,
    /// The bit records of all segments; each segment starts at a byte boundary and holds exactly
    /// `ceil(record_bits * keys / 8)` bytes.
    pub data: Vec<u8>,
}

/// The decode parameters of one component in one segment.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Dec {
    /// Bit offset inside the key record.
    pub(crate) off: u32,
    /// Mask of `bits` ones.
    pub(crate) mask: u32,
    pub(crate) scale: f32,
    pub(crate) bias: f32,
    /// For the first component of a rotation: the segment's shared index (`0..=3`), or
    /// [`INDEX_PER_KEY`] when the key record holds it (right before the component).
    pub(crate) index: u8,
}

/// A validated compressed payload with precomputed decode tables.
#[derive(Debug, Clone)]
pub(crate) struct Quantized {
    pub(crate) parts: QuantizedParts,
    pub(crate) components: usize,
    /// Floats per decoded key: 3 per translation or scale, 4 per rotation (raw x y z w), in component
    /// order (the layout [`crate::Clip::to_plain`] gives its frames).
    pub(crate) decoded_stride: usize,
    /// Per group of three components (one channel): where its values start in a decoded key.
    pub(crate) group_dest: Vec<u32>,
    /// Per group: true when the channel is a rotation.
    group_rot: Vec<bool>,
    /// Per segment: first bit of its data, bits per key record.
    seg: Vec<(usize, usize)>,
    /// Per segment, per component.
    dec: Vec<Dec>,
    /// Per segment, per channel (group of three components): everything decoding it needs (what
    /// [`Quantized::lane_table`] gathers).
    channels: Vec<ChannelDec>,
    /// `parts.data` followed by 8 zero bytes, so that every read is one unaligned 8-byte load.
    padded: Vec<u8>,
}

/// How one channel (three components) decodes in one segment.
#[derive(Debug, Clone, Copy, Default)]
struct ChannelDec {
    /// Bit offsets of the three components inside a key record.
    off: [u32; 3],
    /// Masks of their bit widths.
    mask: [u32; 3],
    scale: [f32; 3],
    bias: [f32; 3],
    /// For a rotation: the bits of its index right before its first component (2, or 0 when the
    /// segment shares one index, `fixed_index`).
    index_bits: u32,
    fixed_index: u32,
    /// The channel's bits (index and components, which are contiguous) fit one 8-byte load from
    /// any bit position (at most 57 bits).
    one_load: bool,
}

/// How four channels of one kind decode in one segment, lane by lane ([`Quantized::lane_table`]): a
/// sampler builds these when it enters a segment and decodes each key of it four joints at a time.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct LaneTable {
    scale: [Vec4; 3],
    bias: [Vec4; 3],
    /// Per lane: bit offset inside a key record of the channel's first field (a rotation's index,
    /// when the record holds it).
    at: [u32; 4],
    /// Per lane: mask of the stored index (3, or 0 when the segment shares one) and the shared
    /// index (0 when stored): a lane's index is `(word & index_mask) | index_fixed`.
    index_mask: [u32; 4],
    index_fixed: [u32; 4],
    /// Per component, per lane: its bit offset from `at`, and the mask of its bit width.
    shift: [[u32; 4]; 3],
    mask: [[u32; 4]; 3],
    /// Every lane's fields fit one 8-byte load from `at`.
    pub(crate) one_load: bool,
}

impl PartialEq for Quantized {
    fn eq(&self, other: &Self) -> bool {
        // Everything else is derived from the parts and the layout.
        self.parts == other.parts && self.group_rot == other.group_rot
    }
}

/// The scale and bias a component decodes with: `value = bias + scale * q`.
pub fn dequant_params(range: [f32; 2], seg: SegmentComponent) -> (f32, f32) {
    let lo = range[0] + range[1] * (f32::from(seg.min) / 255.0);
    let ext = range[1] * (f32::from(seg.extent) / 255.0);
    if seg.bits == 0 {
        (0.0, lo + ext * 0.5)
    } else {
        let steps = ((1u64 << seg.bits) - 1) as f32;
        (ext / steps, lo)
    }
}

/// Splits a rotation into the index of its largest component (by magnitude) and the other three in
/// order, sign-flipped so that the largest is positive. Decodes with [`from_smallest_three`].
pub fn smallest_three(q: Quat) -> (u8, [f32; 3]) {
    let a = q.to_array();
    let mut big = 0;
    for i in 1..4 {
        if a[i].abs() > a[big].abs() {
            big = i;
        }
    }
    (big as u8, three_without(q, big as u8))
}

/// The three components of `q` other than component `index` (0-3), in order, sign-flipped so that
/// component `index` is positive: what [`from_smallest_three`] rebuilds `q` from with that index,
/// whether or not that component is the largest.
#[inline]
pub fn three_without(q: Quat, index: u8) -> [f32; 3] {
    let a = q.to_array();
    let big = usize::from(index & 3);
    let sign = if a[big] < 0.0 { -1.0 } else { 1.0 };
    let mut out = [0.0; 3];
    let mut k = 0;
    for (i, v) in a.iter().enumerate() {
        if i != big {
            out[k] = v * sign;
            k += 1;
        }
    }
    out
}

/// Rebuilds a unit quaternion from [`smallest_three`]'s output.
#[inline]
pub fn from_smallest_three(index: u32, v: [f32; 3]) -> Quat {
    raw_from_smallest_three(index, v).normalize()
}

/// [`from_smallest_three`] without the final normalisation (unit up to quantization error).
#[inline]
pub(crate) fn raw_from_smallest_three(index: u32, v: [f32; 3]) -> Quat {
    let w = (1.0 - v[0] * v[0] - v[1] * v[1] - v[2] * v[2])
        .max(0.0)
        .sqrt();
    // `index` names the component that was dropped; the other three follow in order.
    match index & 3 {
        0 => Quat::from_xyzw(w, v[0], v[1], v[2]),
        1 => Quat::from_xyzw(v[0], w, v[1], v[2]),
        2 => Quat::from_xyzw(v[0], v[1], w, v[2]),
        _ => Quat::from_xyzw(v[0], v[1], v[2], w),
    }
}

/// Bit offsets of every component inside a key record, and the record size. `rotation_starts[c]` is
/// true when component `c` is the first of a rotation; its 2-bit index comes right before it unless
/// `fixed` (that segment's [`QuantizedParts::rotation_index`] entries, one per rotation; empty:
/// none fixed) gives it for the whole segment.
pub fn record_layout(bits: &[u8], rotation_starts: &[bool], fixed: &[u8]) -> (Vec<u32>, u32) {
    let mut off = Vec::with_capacity(bits.len());
    let mut at = 0u32;
    let mut r = 0;
    for (c, &b) in bits.iter().enumerate() {
        if rotation_starts.get(c).copied().unwrap_or(false) {
            if fixed.get(r).is_none_or(|&i| i > 3) {
                at += ROTATION_INDEX_BITS;
            }
            r += 1;
        }
        off.push(at);
        at += u32::from(b);
    }
    (off, at)
}

/// Per segment, per rotation: the index every key of the segment shares, or [`INDEX_PER_KEY`]
/// (what an encoder stores as [`QuantizedParts::rotation_index`]). `index[k * rotations + r]` as
/// in [`pack`].
pub fn shared_indices(keys: usize, segment_len: usize, rotations: usize, index: &[u8]) -> Vec<u8> {
    let seg_len = segment_len.max(1);
    let mut out = Vec::with_capacity(keys.div_ceil(seg_len) * rotations);
    for first in (0..keys).step_by(seg_len) {
        let last = (first + seg_len).min(keys);
        for r in 0..rotations {
            let at = |k: usize| index.get(k * rotations + r).copied().unwrap_or(0);
            let i0 = at(first);
            let same = (first..last).all(|k| at(k) == i0);
            out.push(if same { i0 } else { INDEX_PER_KEY });
        }
    }
    out
}

/// Packs quantized integers into the segment bitstreams [`QuantizedParts::data`] expects.
///
/// `q[k * components + c]` is key `k`'s integer for component `c` (below `2^bits` of its segment);
/// `index[k * rotations + r]` is key `k`'s largest-component index of rotation `r` (rotations in
/// component order). `segments`, `rotation_index` and `rotation_starts` as in [`QuantizedParts`]
/// and [`record_layout`].
pub fn pack(
    keys: usize,
    segment_len: usize,
    segments: &[SegmentComponent],
    rotation_index: &[u8],
    rotation_starts: &[bool],
    q: &[u32],
    index: &[u8],
) -> Vec<u8> {
    let comps = rotation_starts.len();
    let rotations = rotation_starts.iter().filter(|&&r| r).count();
    let mut out = Vec::new();
    let seg_len = segment_len.max(1);
    for (s, first) in (0..keys).step_by(seg_len).enumerate() {
        let n = seg_len.min(keys - first);
        let seg = &segments[s * comps..(s + 1) * comps];
        let bits: Vec<u8> = seg.iter().map(|x| x.bits).collect();
        let fixed = rotation_index
            .get(s * rotations..(s + 1) * rotations)
            .unwrap_or_default();
        let (off, record) = record_layout(&bits, rotation_starts, fixed);
        let mut buf = vec![0u8; (record as usize * n).div_ceil(8) + 8];
        // The low `nbits` of `v` at bit `bit` (least significant first): at most 32 bits after up
        // to 7 of the first byte, so five bytes, which the buffer's 8 bytes of padding cover.
        let mut put = |bit: usize, v: u32, nbits: u32| {
            if nbits == 0 {
                return;
            }
            let v = u64::from(v) & (u64::MAX >> (64 - nbits.min(32)));
            let bytes = (v << (bit % 8)).to_le_bytes();
            for (to, from) in buf[bit / 8..].iter_mut().zip(&bytes[..5]) {
                *to |= from;
            }
        };
        // What each key writes, in the order it is written: per rotation whose index is not
        // shared (its component, the index's bit offset, its number among the rotations), then
        // the component's integer when it has bits (a component of 0 bits writes nothing).
        let mut writes: Vec<(usize, u32, Option<usize>)> = Vec::with_capacity(comps);
        let mut r = 0;
        for c in 0..comps {
            if rotation_starts[c] {
                if fixed.get(r).is_none_or(|&i| i > 3) {
                    writes.push((c, off[c] - ROTATION_INDEX_BITS, Some(r)));
                }
                r += 1;
            }
            if seg[c].bits > 0 {
                writes.push((c, off[c], None));
            }
        }
        for k in 0..n {
            let base = k * record as usize;
            for &(c, at, rotation) in &writes {
                match rotation {
                    Some(r) => put(
                        base + at as usize,
                        u32::from(index[(first + k) * rotations + r]),
                        ROTATION_INDEX_BITS,
                    ),
                    None => put(
                        base + at as usize,
                        q[(first + k) * comps + c],
                        u32::from(seg[c].bits),
                    ),
                }
            }
        }
        buf.truncate((record as usize * n).div_ceil(8));
        out.extend_from_slice(&buf);
    }
    out
}

impl Quantized {
    /// Validates `parts` for `keys` keys and the given component layout, and builds decode tables. The
    /// error is the reason, which the clip reports as `ClipError::BadCompressed`.
    pub(crate) fn new(
        parts: QuantizedParts,
        keys: usize,
        rotation_starts: &[bool],
    ) -> Result<Quantized, String> {
        let bad = |m: String| Err(m);
        let comps = rotation_starts.len();
        if parts.segment_len == 0 {
            return bad("segment length 0".into());
        }
        if parts.ranges.len() != comps {
            return bad(format!(
                "{} component ranges for {comps} components",
                parts.ranges.len()
            ));
        }
        for (c, r) in parts.ranges.iter().enumerate() {
            if !r[0].is_finite() || !r[1].is_finite() || r[1] < 0.0 {
                return bad(format!("component {c}: range is not finite or negative"));
            }
        }
        let seg_len = parts.segment_len as usize;
        let seg_count = keys.div_ceil(seg_len);
        if Some(parts.segments.len()) != seg_count.checked_mul(comps) {
            return bad(format!(
                "{} segment entries for {seg_count} segments of {comps} components",
                parts.segments.len()
            ));
        }
        let rotations = rotation_starts.iter().filter(|&&r| r).count();
        if !parts.rotation_index.is_empty()
            && Some(parts.rotation_index.len()) != seg_count.checked_mul(rotations)
        {
            return bad(format!(
                "{} rotation index entries for {seg_count} segments of {rotations} rotations",
                parts.rotation_index.len()
            ));
        }
        if let Some(i) = parts
            .rotation_index
            .iter()
            .find(|&&i| i > 3 && i != INDEX_PER_KEY)
        {
            return bad(format!(
                "rotation index entry {i} is neither 0-3 nor {INDEX_PER_KEY}"
            ));
        }
        if !parts.rotation_index.is_empty() {
            // A compact record stores rotation ranges in 16 bits.
            for (first, _) in rotation_starts.iter().enumerate().filter(|s| *s.1) {
                for c in first..first + 3 {
                    let r = parts.ranges.get(c).copied().unwrap_or_default();
                    if compact_range_units(r).is_none() {
                        return bad(format!(
                            "component {c}: rotation range {r:?} has no 16-bit form"
                        ));
                    }
                }
            }
        }
        let mut seg = Vec::with_capacity(seg_count);
        let mut dec = Vec::with_capacity(parts.segments.len());
        let mut bit = 0usize;
        for s in 0..seg_count {
            let entries = parts
                .segments
                .get(s * comps..(s + 1) * comps)
                .unwrap_or_default();
            let bits: Vec<u8> = entries.iter().map(|e| e.bits).collect();
            if let Some(b) = bits.iter().find(|&&b| b > MAX_BITS) {
                return bad(format!("segment {s}: bit width {b} is above {MAX_BITS}"));
            }
            let fixed = parts
                .rotation_index
                .get(s * rotations..(s + 1) * rotations)
                .unwrap_or_default();
            let (off, record) = record_layout(&bits, rotation_starts, fixed);
            let mut r = 0;
            for (c, e) in entries.iter().enumerate() {
                let mut index = INDEX_PER_KEY;
                if rotation_starts.get(c).copied().unwrap_or(false) {
                    index = fixed.get(r).copied().unwrap_or(INDEX_PER_KEY);
                    r += 1;
                }
                let range = parts.ranges.get(c).copied().unwrap_or_default();
                let (scale, bias) = dequant_params(range, *e);
                let top = bias + scale * ((1u64 << e.bits) - 1) as f32;
                if !scale.is_finite() || !bias.is_finite() || !top.is_finite() {
                    return bad(format!("segment {s} component {c}: range overflows"));
                }
                dec.push(Dec {
                    off: off.get(c).copied().unwrap_or(0),
                    mask: ((1u64 << e.bits) - 1) as u32,
                    scale,
                    bias,
                    index,
                });
            }
            let n = seg_len.min(keys - s * seg_len);
            seg.push((bit, record as usize));
            bit += (record as usize * n).div_ceil(8) * 8;
        }
        if bit / 8 != parts.data.len() {
            return bad(format!(
                "the segments need {} data bytes; {} present",
                bit / 8,
                parts.data.len()
            ));
        }
        let mut padded = parts.data.clone();
        padded.extend_from_slice(&[0; 8]);
        let mut group_dest = Vec::with_capacity(comps / 3);
        let mut group_rot = Vec::with_capacity(comps / 3);
        let mut decoded_stride = 0usize;
        for first in (0..comps).step_by(3) {
            let rot = rotation_starts.get(first).copied().unwrap_or(false);
            group_dest.push(decoded_stride as u32);
            group_rot.push(rot);
            decoded_stride += if rot { 4 } else { 3 };
        }
        let channels = dec
            .chunks_exact(3)
            .enumerate()
            .map(|(i, d)| {
                let g = i % (comps / 3).max(1);
                let rotation = group_rot.get(g).copied().unwrap_or(false);
                let bits = [0, 1, 2].map(|i| d[i].mask.count_ones() as u8);
                let stored = rotation && d[0].index > 3;
                let index_bits = if stored { ROTATION_INDEX_BITS } else { 0 };
                let run = u32::from(bits[0]) + u32::from(bits[1]) + u32::from(bits[2]) + index_bits;
                ChannelDec {
                    off: [d[0].off, d[1].off, d[2].off],
                    mask: [d[0].mask, d[1].mask, d[2].mask],
                    scale: [d[0].scale, d[1].scale, d[2].scale],
                    bias: [d[0].bias, d[1].bias, d[2].bias],
                    index_bits,
                    fixed_index: if stored { 0 } else { u32::from(d[0].index & 3) },
                    one_load: run <= 57
                        && d[1].off == d[0].off + u32::from(bits[0])
                        && d[2].off == d[1].off + u32::from(bits[1])
                        && d[0].off >= index_bits,
                }
            })
            .collect();
        Ok(Quantized {
            channels,
            decoded_stride,
            group_dest,
            group_rot,
            components: comps,
            seg,
            dec,
            padded,
            parts,
        })
    }

    /// The decoder for key `k`: its segment's decode table and the key record's first bit.
    #[inline]
    pub(crate) fn key(&self, k: usize) -> KeyRef<'_> {
        let seg_len = self.parts.segment_len as usize;
        let s = k / seg_len;
        let (start, record) = self.seg.get(s).copied().unwrap_or_default();
        let dec = self
            .dec
            .get(s * self.components..(s + 1) * self.components)
            .unwrap_or_default();
        KeyRef {
            data: &self.padded,
            base: start + (k - s * seg_len) * record,
            dec,
        }
    }

    /// Key `k`'s segment and the first bit of its record, or `None` past the last key.
    #[inline]
    pub(crate) fn key_start(&self, k: usize) -> Option<(usize, usize)> {
        let seg_len = (self.parts.segment_len as usize).max(1);
        let s = k / seg_len;
        let &(start, record) = self.seg.get(s)?;
        Some((s, start + (k - s * seg_len) * record))
    }

    /// The decode table of four channels of one kind (all rotations, or all translations or scales)
    /// in segment `s`, channel `channel[l]` in lane `l` for the lanes set in `lanes`; the other lanes
    /// decode to zeros.
    pub(crate) fn lane_table(&self, s: usize, channel: [u32; 4], lanes: u8) -> LaneTable {
        let groups = self.components / 3;
        let channels = self
            .channels
            .get(s * groups..(s + 1) * groups)
            .unwrap_or_default();
        let mut t = LaneTable {
            one_load: true,
            ..LaneTable::default()
        };
        let (mut scale, mut bias) = ([[0.0f32; 4]; 3], [[0.0f32; 4]; 3]);
        for l in 0..4 {
            let Some(ch) = channels
                .get(channel[l] as usize)
                .filter(|_| lanes & (1 << l) != 0)
            else {
                continue;
            };
            // A rotation's fields start with its 2-bit index, when the record holds it.
            let first = ch.off[0] - ch.index_bits;
            t.at[l] = first;
            t.index_mask[l] = if ch.index_bits > 0 { 3 } else { 0 };
            t.index_fixed[l] = ch.fixed_index;
            for c in 0..3 {
                t.shift[c][l] = ch.off[c] - first;
                t.mask[c][l] = ch.mask[c];
                scale[c][l] = ch.scale[c];
                bias[c][l] = ch.bias[c];
            }
            t.one_load &= ch.one_load;
        }
        t.scale = scale.map(Vec4::from_array);
        t.bias = bias.map(Vec4::from_array);
        t
    }

    /// Decodes four channels of the key record starting at bit `base` with `table` (see
    /// [`Quantized::lane_table`]): one vector per component, lane `l` holding channel `l`'s value. For
    /// rotations the four vectors are x y z w as [`raw_from_smallest_three`] builds them; otherwise
    /// the fourth is zero. Each lane's values are those [`KeyRef::vec3`] and [`KeyRef::quat_raw`] give,
    /// bit for bit: the same operations, four lanes at a time.
    #[inline(always)]
    pub(crate) fn decode_lanes(&self, base: usize, table: &LaneTable, rotation: bool) -> [Vec4; 4] {
        let data = &self.padded[..];
        // Every field lies inside the data (checked when the payload was read), which is followed by
        // 8 zero bytes, so one 8-byte load from a field's first byte holds 57 bits or more of it.
        // Bit positions stay far below 2^61, so `byte + 8` cannot overflow and the bounds check is
        // one comparison.
        let read = |bit: usize| -> u64 {
            let byte = bit >> 3;
            match data.get(byte..byte + 8) {
                Some(b) => u64::from_le_bytes(b.try_into().unwrap_or_default()) >> (bit & 7),
                None => 0,
            }
        };
        let t = table;
        let mut q = [[0i32; 4]; 3];
        let mut index = [0i32; 4];
        if t.one_load {
            for l in 0..4 {
                let word = read(base + t.at[l] as usize);
                index[l] = ((word as u32 & t.index_mask[l]) | t.index_fixed[l]) as i32;
                for (c, q) in q.iter_mut().enumerate() {
                    q[l] = ((word >> t.shift[c][l]) as u32 & t.mask[c][l]) as i32;
                }
            }
        } else {
            for l in 0..4 {
                let at = base + t.at[l] as usize;
                index[l] = ((read(at) as u32 & t.index_mask[l]) | t.index_fixed[l]) as i32;
                for (c, q) in q.iter_mut().enumerate() {
                    q[l] = (read(at + t.shift[c][l] as usize) as u32 & t.mask[c][l]) as i32;
                }
            }
        }
        // Below 2^24, so the conversion is exact (as the scalar decoder's `u32 as f32`).
        finish_lanes(
            t,
            q.map(|q| Vec4::from_array(q.map(|x| x as f32))),
            Vec4::from_array(index.map(|i| i as f32)),
            rotation,
        )
    }

    /// [`Quantized::decode_lanes`] with AVX2, for a table whose lanes each read one 8-byte word
    /// ([`LaneTable::one_load`]): the four lanes' fields are shifted and masked in one 256-bit register
    /// (64 bits per lane) instead of one scalar shift and mask per lane and field. The integers are the
    /// same, and the float operations are [`finish_lanes`]', so are the results.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline]
    pub(crate) fn decode_lanes_avx2(
        &self,
        base: usize,
        table: &LaneTable,
        rotation: bool,
    ) -> [Vec4; 4] {
        use std::arch::x86_64::*;
        let t = table;
        let data = &self.padded[..];
        // The 8 bytes from each lane's first field's byte (see `decode_lanes` for the bounds).
        let word = |l: usize| -> i64 {
            let byte = (base + t.at[l] as usize) >> 3;
            match data.get(byte..byte + 8) {
                Some(b) => i64::from_le_bytes(b.try_into().unwrap_or_default()),
                None => 0,
            }
        };
        // Four u32 lanes widened to 64 bits.
        macro_rules! v4 {
            ($a:expr) => {{
                let a: &[u32; 4] = $a;
                _mm256_cvtepu32_epi64(_mm_setr_epi32(
                    a[0] as i32,
                    a[1] as i32,
                    a[2] as i32,
                    a[3] as i32,
                ))
            }};
        }
        let words = _mm256_set_epi64x(word(3), word(2), word(1), word(0));
        // Each lane's bit position inside its first byte.
        let phase = _mm256_and_si256(
            _mm256_add_epi64(_mm256_set1_epi64x(base as i64), v4!(&t.at)),
            _mm256_set1_epi64x(7),
        );
        let low_halves = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
        // A macro, not a closure: closures are not inlined into this function here.
        macro_rules! field {
            ($shift:expr, $mask:expr) => {{
                let v = _mm256_and_si256(
                    _mm256_srlv_epi64(words, _mm256_add_epi64(phase, $shift)),
                    $mask,
                );
                let low = _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(v, low_halves));
                Vec4::from(_mm_cvtepi32_ps(low))
            }};
        }
        let stored = field!(_mm256_setzero_si256(), v4!(&t.index_mask));
        // Stored and shared indices are 0-3 (exact in f32), and a lane has one or the other.
        let index = stored + Vec4::from_array(t.index_fixed.map(|i| i as f32));
        let q = [
            field!(v4!(&t.shift[0]), v4!(&t.mask[0])),
            field!(v4!(&t.shift[1]), v4!(&t.mask[1])),
            field!(v4!(&t.shift[2]), v4!(&t.mask[2])),
        ];
        finish_lanes(t, q, index, rotation)
    }

    /// Per component: the smallest and largest bit width over all segments.
    pub(crate) fn bit_range(&self, c: usize) -> (u8, u8) {
        let mut lo = u8::MAX;
        let mut hi = 0;
        for s in self
            .parts
            .segments
            .iter()
            .skip(c)
            .step_by(self.components.max(1))
        {
            lo = lo.min(s.bits);
            hi = hi.max(s.bits);
        }
        (lo.min(hi), hi)
    }
}

/// The float half of [`Quantized::decode_lanes`]: values `bias + scale * q` per component, and for a
/// rotation the dropped component `w = sqrt(max(0, 1 - x^2 - y^2 - z^2))` put back in the place the
/// index names, the operations and order of [`raw_from_smallest_three`] in every lane.
#[inline(always)]
fn finish_lanes(t: &LaneTable, q: [Vec4; 3], index: Vec4, rotation: bool) -> [Vec4; 4] {
    // Written out: array `map` is not inlined into the AVX2 caller.
    let v0 = t.bias[0] + t.scale[0] * q[0];
    let v1 = t.bias[1] + t.scale[1] * q[1];
    let v2 = t.bias[2] + t.scale[2] * q[2];
    if !rotation {
        return [v0, v1, v2, Vec4::ZERO];
    }
    let w = (Vec4::ONE - v0 * v0 - v1 * v1 - v2 * v2).max(Vec4::ZERO);
    let w = Vec4::new(w.x.sqrt(), w.y.sqrt(), w.z.sqrt(), w.w.sqrt());
    // The index names the dropped component; the other three follow in order.
    let is = |i: f32| index.cmpeq(Vec4::splat(i));
    let (i0, i1, i2, i3) = (is(0.0), is(1.0), is(2.0), is(3.0));
    [
        Vec4::select(i0, w, v0),
        Vec4::select(i0, v0, Vec4::select(i1, w, v1)),
        Vec4::select(i2, w, Vec4::select(i3, v2, v1)),
        Vec4::select(i3, w, v2),
    ]
}

/// One key's record, ready to decode components from.
pub(crate) struct KeyRef<'a> {
    data: &'a [u8],
    base: usize,
    dec: &'a [Dec],
}

impl KeyRef<'_> {
    #[inline]
    fn bits(&self, bit: usize) -> u64 {
        let byte = bit >> 3;
        let w = self
            .data
            .get(byte..byte + 8)
            .and_then(|s| <[u8; 8]>::try_from(s).ok())
            .unwrap_or_default();
        u64::from_le_bytes(w) >> (bit & 7)
    }
    /// Component `c`'s decoded value.
    #[inline]
    pub(crate) fn value(&self, c: usize) -> f32 {
        let Some(d) = self.dec.get(c) else { return 0.0 };
        let q = (self.bits(self.base + d.off as usize) as u32) & d.mask;
        d.bias + d.scale * q as f32
    }
    /// The three components starting at `c`.
    #[inline]
    pub(crate) fn vec3(&self, c: usize) -> glam::Vec3 {
        glam::Vec3::new(self.value(c), self.value(c + 1), self.value(c + 2))
    }
    /// The rotation whose first component is `c`.
    #[inline]
    pub(crate) fn quat(&self, c: usize) -> Quat {
        crate::rotation::normalize_rotation(self.quat_raw(c))
    }
    /// [`KeyRef::quat`] before normalisation (for callers that normalise after blending).
    #[inline]
    pub(crate) fn quat_raw(&self, c: usize) -> Quat {
        let Some(d) = self.dec.get(c) else {
            return Quat::IDENTITY;
        };
        let idx = if d.index <= 3 {
            u32::from(d.index)
        } else {
            (self.bits(self.base + (d.off as usize).saturating_sub(2)) & 3) as u32
        };
        raw_from_smallest_three(idx, [self.value(c), self.value(c + 1), self.value(c + 2)])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smallest_three_round_trips() {
        for q in [
            Quat::IDENTITY,
            Quat::from_xyzw(-0.9, 0.1, 0.3, 0.2).normalize(),
            Quat::from_xyzw(0.1, -0.2, -0.95, 0.1).normalize(),
            Quat::from_rotation_y(2.5),
        ] {
            let (i, v) = smallest_three(q);
            let back = from_smallest_three(u32::from(i), v);
            assert!(back.dot(q).abs() > 0.999_999, "{q} {back}");
            assert!(v
                .iter()
                .all(|x| x.abs() <= std::f32::consts::FRAC_1_SQRT_2 + 1e-6));
        }
    }

    #[test]
    fn pack_and_decode_agree() {
        // Two components (a rotation needs three; here: plain scalars), 3 keys, segments of 2.
        let starts = [false, false];
        let segs = vec![
            SegmentComponent {
                bits: 3,
                min: 0,
                extent: 255,
            },
            SegmentComponent {
                bits: 0,
                min: 0,
                extent: 255,
            },
            SegmentComponent {
                bits: 5,
                min: 0,
                extent: 255,
            },
            SegmentComponent {
                bits: 1,
                min: 0,
                extent: 255,
            },
        ];
        let q = [7, 0, 2, 0, 31, 1];
        let data = pack(3, 2, &segs, &[], &starts, &q, &[]);
        // Segment 0: 2 keys x 3 bits = 1 byte; segment 1: 1 key x 6 bits = 1 byte.
        assert_eq!(data, vec![0b0001_0111, 0b0011_1111]);
        let parts = QuantizedParts {
            segment_len: 2,
            ranges: vec![[0.0, 7.0], [1.0, 2.0]],
            segments: segs,
            rotation_index: Vec::new(),
            data,
        };
        let z = Quantized::new(parts, 3, &starts).unwrap();
        assert_eq!(z.key(0).value(0), 7.0);
        assert_eq!(z.key(1).value(0), 2.0);
        assert_eq!(z.key(1).value(1), 2.0); // zero bits: middle of the range
        assert_eq!(z.key(2).value(0), 7.0);
        assert_eq!(z.key(2).value(1), 3.0);
    }

    #[test]
    fn compact_rotation_ranges_cover_their_values_in_16_bits() {
        for (lo, hi) in [
            (-0.866f32, 0.866f32),
            (0.1, 0.1),
            (-1.0, 0.999),
            (0.123_456_7, 0.654_321),
            (-0.000_01, 0.000_01),
        ] {
            let r = compact_rotation_range(lo, hi).unwrap();
            // Covers, and is at most a step wider at each end.
            assert!(r[0] <= lo && r[0] + r[1] >= hi, "{lo} {hi} {r:?}");
            assert!(lo - r[0] < 1.0 / RANGE_UNITS, "{lo} {r:?}");
            assert!(r[0] + r[1] - hi <= 2.0 / RANGE_UNITS, "{hi} {r:?}");
            let u = compact_range_units(r).unwrap();
            assert_eq!(range_from_units(u), r);
        }
        // Outside the span a 16-bit pair can say: no compact form.
        assert_eq!(compact_rotation_range(-1.5, 0.0), None);
        assert_eq!(compact_rotation_range(-1.0, 1.0), None);
        assert_eq!(compact_rotation_range(f32::NAN, 0.0), None);
        assert_eq!(compact_range_units([0.1, 0.5]), None);
    }

    #[test]
    fn a_shared_index_takes_no_bits_in_the_key_records() {
        // One rotation (three components of 4 bits), 2 keys in one segment, both dropping z.
        let starts = [true, false, false];
        let seg = |bits| SegmentComponent {
            bits,
            min: 0,
            extent: 255,
        };
        let segs = vec![seg(4), seg(4), seg(4)];
        let q = [1, 2, 3, 4, 5, 6];
        let index = [2u8, 2];
        assert_eq!(shared_indices(2, 2, 1, &index), vec![2]);
        assert_eq!(shared_indices(2, 2, 1, &[2, 3]), vec![INDEX_PER_KEY]);
        let per_key = pack(2, 2, &segs, &[], &starts, &q, &index);
        let shared = pack(2, 2, &segs, &[2], &starts, &q, &index);
        // 14 bits per key against 12.
        assert_eq!((per_key.len(), shared.len()), (4, 3));
        // Key 0: x = 1, y = 2, z = 3 in the low bits, least significant first.
        assert_eq!(shared[0], 0x21);
        let parts = |data, rotation_index| QuantizedParts {
            segment_len: 2,
            ranges: vec![[-1.0, 1.875]; 3],
            segments: segs.clone(),
            rotation_index,
            data,
        };
        let a = Quantized::new(parts(shared, vec![2]), 2, &starts).unwrap();
        let b = Quantized::new(parts(per_key, vec![]), 2, &starts).unwrap();
        for k in 0..2 {
            let (qa, qb) = (a.key(k).quat_raw(0), b.key(k).quat_raw(0));
            assert_eq!(
                qa.to_array().map(f32::to_bits),
                qb.to_array().map(f32::to_bits)
            );
        }
        // Index 2: the rebuilt component is z, the stored ones x, y, w.
        let x = -1.0 + 1.875 / 15.0;
        assert_eq!(a.key(0).quat_raw(0).x, x);
        // Entries other than 0-3 and 255 are refused, and so is a table of the wrong length.
        assert!(Quantized::new(parts(vec![0; 3], vec![4]), 2, &starts).is_err());
        assert!(Quantized::new(parts(vec![0; 3], vec![2, 2]), 2, &starts).is_err());
    }

    #[test]
    fn rejects_bad_parts() {
        let starts = [false];
        let ok = QuantizedParts {
            segment_len: 4,
            ranges: vec![[0.0, 1.0]],
            segments: vec![SegmentComponent {
                bits: 8,
                min: 0,
                extent: 255,
            }],
            rotation_index: Vec::new(),
            data: vec![0; 4],
        };
        assert!(Quantized::new(ok.clone(), 4, &starts).is_ok());
        let mut p = ok.clone();
        p.segments[0].bits = 33;
        assert!(Quantized::new(p, 4, &starts).is_err());
        let mut p = ok.clone();
        p.ranges[0][1] = f32::INFINITY;
        assert!(Quantized::new(p, 4, &starts).is_err());
        let mut p = ok.clone();
        p.data.pop();
        assert!(Quantized::new(p, 4, &starts).is_err());
        let mut p = ok;
        p.ranges[0] = [3e38, 3e38];
        assert!(Quantized::new(p, 4, &starts).is_err());
    }
}
