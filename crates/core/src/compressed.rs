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

use crate::clip::ClipError;
use glam::Quat;

/// Largest bit width a component may use.
pub const MAX_BITS: u8 = 24;
/// Bits of the index of the largest quaternion component stored before each rotation.
pub const ROTATION_INDEX_BITS: u32 = 2;

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
    /// Per segment, per channel (group of three components): everything decoding it needs, side by
    /// side, so that [`Quantized::decode_into`] streams through one array.
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
    /// Their bit widths.
    bits: [u8; 3],
    scale: [f32; 3],
    bias: [f32; 3],
    /// Where the channel's values start in a decoded key.
    dest: u32,
    /// True for a rotation (its 2-bit index sits right before its first component).
    rotation: bool,
    /// The channel's bits (index and components, which are contiguous) fit one 8-byte load from
    /// any bit position (at most 57 bits).
    one_load: bool,
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
    let sign = if a[big] < 0.0 { -1.0 } else { 1.0 };
    let mut out = [0.0; 3];
    let mut k = 0;
    for (i, v) in a.iter().enumerate() {
        if i != big {
            out[k] = v * sign;
            k += 1;
        }
    }
    (big as u8, out)
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
/// true when component `c` is the first of a rotation (its 2-bit index comes right before it).
pub fn record_layout(bits: &[u8], rotation_starts: &[bool]) -> (Vec<u32>, u32) {
    let mut off = Vec::with_capacity(bits.len());
    let mut at = 0u32;
    for (c, &b) in bits.iter().enumerate() {
        if rotation_starts.get(c).copied().unwrap_or(false) {
            at += ROTATION_INDEX_BITS;
        }
        off.push(at);
        at += u32::from(b);
    }
    (off, at)
}

/// Packs quantized integers into the segment bitstreams [`QuantizedParts::data`] expects.
///
/// `q[k * components + c]` is key `k`'s integer for component `c` (below `2^bits` of its segment);
/// `index[k * rotations + r]` is key `k`'s largest-component index of rotation `r` (rotations in
/// component order). `segments` and `rotation_starts` as in [`QuantizedParts`] and [`record_layout`].
pub fn pack(
    keys: usize,
    segment_len: usize,
    segments: &[SegmentComponent],
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
        let (off, record) = record_layout(&bits, rotation_starts);
        let mut buf = vec![0u8; (record as usize * n).div_ceil(8) + 8];
        let mut put = |bit: usize, v: u32, nbits: u32| {
            for i in 0..nbits as usize {
                if (v >> i) & 1 == 1 {
                    buf[(bit + i) / 8] |= 1 << ((bit + i) % 8);
                }
            }
        };
        for k in 0..n {
            let base = k * record as usize;
            let mut r = 0;
            for c in 0..comps {
                if rotation_starts[c] {
                    let idx = index[(first + k) * rotations + r];
                    put(base + off[c] as usize - 2, u32::from(idx), 2);
                    r += 1;
                }
                put(
                    base + off[c] as usize,
                    q[(first + k) * comps + c],
                    u32::from(seg[c].bits),
                );
            }
        }
        buf.truncate((record as usize * n).div_ceil(8));
        out.extend_from_slice(&buf);
    }
    out
}

impl Quantized {
    /// Validates `parts` for `keys` keys and the given component layout, and builds decode tables.
    pub(crate) fn new(
        parts: QuantizedParts,
        keys: usize,
        rotation_starts: &[bool],
    ) -> Result<Quantized, ClipError> {
        let bad = |m: String| Err(ClipError::BadCompressed(m));
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
            let (off, record) = record_layout(&bits, rotation_starts);
            for (c, e) in entries.iter().enumerate() {
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
                let run = u32::from(bits[0])
                    + u32::from(bits[1])
                    + u32::from(bits[2])
                    + if rotation { ROTATION_INDEX_BITS } else { 0 };
                ChannelDec {
                    off: [d[0].off, d[1].off, d[2].off],
                    mask: [d[0].mask, d[1].mask, d[2].mask],
                    bits,
                    scale: [d[0].scale, d[1].scale, d[2].scale],
                    bias: [d[0].bias, d[1].bias, d[2].bias],
                    dest: group_dest.get(g).copied().unwrap_or(0),
                    rotation,
                    one_load: run <= 57
                        && d[1].off == d[0].off + u32::from(bits[0])
                        && d[2].off == d[1].off + u32::from(bits[1])
                        && (!rotation || d[0].off >= ROTATION_INDEX_BITS),
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

    /// Decodes the channels `only` (channel numbers: component / 3) of key `k` into `out` (at least
    /// [`Quantized::decoded_stride`] floats, each channel at its place in the decoded layout): per
    /// channel, the values [`KeyRef::vec3`] and [`KeyRef::quat_raw`] give, bit for bit. A sampler
    /// decodes only the channels its binding reads (a masked layer, a partial skeleton).
    pub(crate) fn decode_into(&self, k: usize, only: &[u32], out: &mut [f32]) {
        let groups = self.components / 3;
        let seg_len = (self.parts.segment_len as usize).max(1);
        let s = k / seg_len;
        let (Some(&(start, record)), Some(channels)) = (
            self.seg.get(s),
            self.channels.get(s * groups..(s + 1) * groups),
        ) else {
            return;
        };
        let base = start + (k - s * seg_len) * record;
        let data = &self.padded[..];
        // Every field lies inside the data (checked when the payload was read), which is followed by
        // 8 zero bytes, so one 8-byte load from a field's first byte holds 57 bits or more of it.
        let read = |bit: usize| -> u64 {
            data.get(bit >> 3..)
                .and_then(<[u8]>::first_chunk::<8>)
                .map_or(0, |b| u64::from_le_bytes(*b))
                >> (bit & 7)
        };
        for ch in only.iter().filter_map(|&c| channels.get(c as usize)) {
            let (index, q) = if ch.one_load {
                // Index (for a rotation) and the three components, in one load.
                let first = base + ch.off[0] as usize;
                let at = if ch.rotation { first - 2 } else { first };
                let mut word = read(at);
                let index = if ch.rotation {
                    let i = (word & 3) as u32;
                    word >>= 2;
                    i
                } else {
                    0
                };
                let q0 = word as u32 & ch.mask[0];
                word >>= ch.bits[0];
                let q1 = word as u32 & ch.mask[1];
                word >>= ch.bits[1];
                (index, [q0, q1, word as u32 & ch.mask[2]])
            } else {
                let index = if ch.rotation {
                    (read((base + ch.off[0] as usize).saturating_sub(2)) & 3) as u32
                } else {
                    0
                };
                let q = [0, 1, 2].map(|i| read(base + ch.off[i] as usize) as u32 & ch.mask[i]);
                (index, q)
            };
            let v = [0, 1, 2].map(|i| ch.bias[i] + ch.scale[i] * q[i] as f32);
            let dest = ch.dest as usize;
            if ch.rotation {
                let q = raw_from_smallest_three(index, v);
                if let Some(o) = out.get_mut(dest..dest + 4) {
                    o.copy_from_slice(&q.to_array());
                }
            } else if let Some(o) = out.get_mut(dest..dest + 3) {
                o.copy_from_slice(&v);
            }
        }
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
        crate::clip::normalize_rotation(self.quat_raw(c))
    }
    /// [`KeyRef::quat`] before normalisation (for callers that normalise after blending).
    #[inline]
    pub(crate) fn quat_raw(&self, c: usize) -> Quat {
        let Some(d) = self.dec.get(c) else {
            return Quat::IDENTITY;
        };
        let idx = (self.bits(self.base + d.off as usize - 2) & 3) as u32;
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
        let data = pack(3, 2, &segs, &starts, &q, &[]);
        // Segment 0: 2 keys x 3 bits = 1 byte; segment 1: 1 key x 6 bits = 1 byte.
        assert_eq!(data, vec![0b0001_0111, 0b0011_1111]);
        let parts = QuantizedParts {
            segment_len: 2,
            ranges: vec![[0.0, 7.0], [1.0, 2.0]],
            segments: segs,
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
