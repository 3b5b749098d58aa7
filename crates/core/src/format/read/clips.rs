//! Decoders of the clip section: plain and compressed clip records.

use super::cursor::{f32s_of, Cur, Result, Strs};
use crate::clip::{Channel, Track};
use crate::format::error::FormatErrorKind as K;
use crate::format::write::{
    CLIP_ADDITIVE, CLIP_COMPACT, CLIP_LOOPING, CLIP_PACKED_SEGMENTS, CLIP_PACKED_TIMES,
    CLIP_QUANTIZED, CLIP_SHORT_TRACKS, CLIP_WHOLE_RANGES, ENCODING_F32, KIND_ANIMATED, KIND_BIND,
    KIND_CONSTANT, KIND_QUANTIZED, TRACK_RECORD,
};
use crate::Clip;
use glam::{Quat, Vec3};

pub(super) fn clips(c: &mut Cur, strs: &Strs) -> Result<Vec<Clip>> {
    let count = c.u32()?;
    let at = c.pos;
    let record = c.u32()?;
    if (record as usize) < TRACK_RECORD || record % 4 != 0 {
        return Err(c.err_at(
            at,
            K::BadValue {
                what: "track record size",
                value: record.into(),
            },
        ));
    }
    c.skip(8)?;
    // A clip needs at least its 32-byte header and one key time.
    let count = c.check_count(count.into(), 36, "clips")?;
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        out.push(clip(c, strs, record as usize)?);
    }
    Ok(out)
}

pub(super) fn channel(c: &mut Cur, n: usize) -> Result<(u8, [f32; 4], u32)> {
    let at = c.pos;
    let kind = c.u8()?;
    let encoding = c.u8()?;
    c.skip(2)?;
    if encoding != ENCODING_F32 {
        return Err(c.err_at(at + 1, K::UnsupportedEncoding { encoding }));
    }
    if kind > KIND_ANIMATED {
        return Err(c.err_at(
            at,
            K::BadValue {
                what: "channel kind",
                value: kind.into(),
            },
        ));
    }
    let raw: [u8; 16] = c.array()?;
    let mut v = [0f32; 4];
    for (o, f) in v.iter_mut().zip(f32s_of(&raw)) {
        *o = f;
    }
    let offset = u32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]);
    if kind == KIND_CONSTANT && !v[..n].iter().all(|x| x.is_finite()) {
        return Err(c.err_at(
            at + 4,
            K::NonFinite {
                what: "constant channel value",
            },
        ));
    }
    Ok((kind, v, offset))
}

pub(super) fn vec_channel((kind, v, offset): (u8, [f32; 4], u32)) -> Channel<Vec3> {
    match kind {
        KIND_BIND => Channel::Bind,
        KIND_CONSTANT => Channel::Constant(Vec3::new(v[0], v[1], v[2])),
        _ => Channel::Animated(offset),
    }
}

pub(super) fn clip(c: &mut Cur, strs: &Strs, record: usize) -> Result<Clip> {
    c.align()?;
    let start = c.pos;
    let name = strs.read(c, "clip name string")?;
    let flags = c.u32()?;
    let variants = CLIP_COMPACT
        | CLIP_SHORT_TRACKS
        | CLIP_PACKED_TIMES
        | CLIP_PACKED_SEGMENTS
        | CLIP_WHOLE_RANGES;
    let known = CLIP_LOOPING | CLIP_ADDITIVE | CLIP_QUANTIZED | variants;
    // The compact layout, the short track table, packed times and packed segment entries are
    // variants of the compressed layout; whole ranges a variant of packed entries.
    if flags & !known != 0
        || (flags & variants != 0 && flags & CLIP_QUANTIZED == 0)
        || (flags & CLIP_WHOLE_RANGES != 0 && flags & CLIP_PACKED_SEGMENTS == 0)
    {
        return Err(c.err_at(
            start + 4,
            K::BadValue {
                what: "clip flags",
                value: flags.into(),
            },
        ));
    }
    let duration = c.f32()?;
    let sample_rate = c.f32()?;
    if !duration.is_finite() || !sample_rate.is_finite() {
        return Err(c.err_at(
            start + 8,
            K::NonFinite {
                what: "clip duration or sample rate",
            },
        ));
    }
    if flags & CLIP_QUANTIZED != 0 {
        return compressed_clip(c, strs, start, name, flags, duration, sample_rate);
    }
    let key_count = c.u32()?;
    let stride = c.u32()?;
    let track_count = c.u32()?;
    c.skip(4)?;
    let times = c.f32s(key_count.into(), "key times")?;
    c.align()?;
    let track_count = c.check_count(track_count.into(), record, "tracks")?;
    let mut tracks = Vec::with_capacity(track_count);
    for _ in 0..track_count {
        let t0 = c.pos;
        let joint = strs.read(c, "track joint string")?;
        let translation = vec_channel(channel(c, 3)?);
        let (kind, v, offset) = channel(c, 4)?;
        let rotation = match kind {
            KIND_BIND => Channel::Bind,
            KIND_CONSTANT => Channel::Constant(Quat::from_array(v)),
            _ => Channel::Animated(offset),
        };
        let scale = vec_channel(channel(c, 3)?);
        c.skip(record - (c.pos - t0))?;
        tracks.push(Track {
            joint,
            translation,
            rotation,
            scale,
        });
    }
    c.align()?;
    let frame_floats = u64::from(key_count).saturating_mul(stride.into());
    let frames = c.f32s(frame_floats, "frame floats")?;
    Clip::from_parts(
        name,
        duration,
        sample_rate,
        flags & CLIP_LOOPING != 0,
        flags & CLIP_ADDITIVE != 0,
        times,
        tracks,
        stride as usize,
        frames,
    )
    .map_err(|e| c.err_at(start, K::Invalid(e.to_string())))
}

/// A packed key-time block (clip flag bit 5) of `n` keys. Layout: docs/format.md.
fn packed_times(c: &mut Cur, n: u32) -> Result<Vec<f32>> {
    use crate::format::times::{data_len, unpack, UnpackError};
    let at = c.pos;
    let step = f64::from_bits(c.u64()?);
    let first = c.u32()?;
    let [gap_bits, residual_bits, _, _]: [u8; 4] = c.array()?;
    use crate::format::times::{MAX_BITS, MIN_RESIDUAL_BITS};
    let widths_ok = gap_bits <= MAX_BITS && (MIN_RESIDUAL_BITS..=MAX_BITS).contains(&residual_bits);
    if !widths_ok {
        return Err(c.err_at(
            at + 12,
            K::BadValue {
                what: "packed key time bit widths",
                value: u64::from(u16::from_le_bytes([gap_bits, residual_bits])),
            },
        ));
    }
    let n = n as usize;
    // Every key takes at least one bit (the residual width is at least 1): the bytes present bound
    // the key count before anything is allocated.
    let data = c.elements(data_len(n, gap_bits, residual_bits), 1, "packed key times")?;
    unpack(step, first, gap_bits, residual_bits, data, n).map_err(|e| {
        c.err_at(
            at,
            K::Invalid(match e {
                UnpackError::Step => "packed key times: step is not a positive number".into(),
                UnpackError::Width => "packed key times: bit width above 32".into(),
                UnpackError::Short => "packed key times: data too short".into(),
                UnpackError::Time => "packed key times: a time is not a finite number >= 0".into(),
            }),
        )
    })
}

/// The compressed clip record (clip flag bit 2), from its key count on. Layout: docs/format.md.
pub(super) fn compressed_clip(
    c: &mut Cur,
    strs: &Strs,
    start: usize,
    name: String,
    flags: u32,
    duration: f32,
    sample_rate: f32,
) -> Result<Clip> {
    use crate::compressed::{range_from_units, QuantizedParts, SegmentComponent};
    let key_count = c.u32()?;
    let comp_at = c.pos;
    let components = c.u32()?;
    let track_count = c.u32()?;
    let seg_at = c.pos;
    let segment_len = c.u32()?;
    if segment_len == 0 {
        return Err(c.err_at(
            seg_at,
            K::BadValue {
                what: "segment length",
                value: 0,
            },
        ));
    }
    let times = if flags & CLIP_PACKED_TIMES != 0 {
        packed_times(c, key_count)?
    } else {
        c.f32s(key_count.into(), "key times")?
    };
    c.align()?;
    let short = flags & CLIP_SHORT_TRACKS != 0;
    let track_count = c.check_count(track_count.into(), if short { 3 } else { 8 }, "tracks")?;
    let mut kinds = Vec::with_capacity(track_count);
    let mut names = Vec::with_capacity(track_count);
    let bad_kind = |c: &Cur, at: usize, value: u64| {
        c.err_at(
            at,
            K::BadValue {
                what: "compressed channel kind",
                value,
            },
        )
    };
    let valid = |k: &[u8]| {
        k.iter()
            .all(|&x| matches!(x, KIND_BIND | KIND_CONSTANT | KIND_QUANTIZED))
    };
    if short {
        // All names (u16 string indices), then one byte of kinds per track (2 bits per channel).
        for _ in 0..track_count {
            let at = c.pos;
            let index = c.u16()?;
            names.push(strs.get(c, at, index.into(), "track joint string")?);
        }
        for _ in 0..track_count {
            let at = c.pos;
            let b = c.u8()?;
            let k = [b & 3, (b >> 2) & 3, (b >> 4) & 3, b >> 6];
            if k[3] != 0 || !valid(&k[..3]) {
                return Err(bad_kind(c, at, b.into()));
            }
            kinds.push(k);
        }
    } else {
        for _ in 0..track_count {
            names.push(strs.read(c, "track joint string")?);
            let at = c.pos;
            let k: [u8; 4] = c.array()?;
            if !valid(&k[..3]) {
                return Err(bad_kind(c, at, u32::from_le_bytes(k).into()));
            }
            kinds.push(k);
        }
    }
    c.align()?;
    let const_floats: u64 = kinds
        .iter()
        .map(|k| {
            [3u64, 4, 3]
                .iter()
                .zip(k)
                .filter(|(_, &x)| x == KIND_CONSTANT)
                .map(|(n, _)| n)
                .sum::<u64>()
        })
        .sum();
    let const_at = c.pos;
    let constants = c.f32s(const_floats, "constant floats")?;
    if !constants.iter().all(|v| v.is_finite()) {
        return Err(c.err_at(
            const_at,
            K::NonFinite {
                what: "constant channel value",
            },
        ));
    }
    c.align()?;
    let mut tracks = Vec::with_capacity(track_count);
    let mut ci = 0usize;
    let mut take = |n: usize| {
        let v = constants.get(ci..ci + n).unwrap_or(&[0.0; 4][..n]).to_vec();
        ci += n;
        v
    };
    for (joint, k) in names.into_iter().zip(&kinds) {
        // Animated channels are numbered below, once every track is known.
        let translation = match k[0] {
            KIND_CONSTANT => Channel::Constant(Vec3::from_slice(&take(3))),
            KIND_QUANTIZED => Channel::Animated(0),
            _ => Channel::Bind,
        };
        let rotation = match k[1] {
            KIND_CONSTANT => Channel::Constant(Quat::from_slice(&take(4))),
            KIND_QUANTIZED => Channel::Animated(0),
            _ => Channel::Bind,
        };
        let scale = match k[2] {
            KIND_CONSTANT => Channel::Constant(Vec3::from_slice(&take(3))),
            KIND_QUANTIZED => Channel::Animated(0),
            _ => Channel::Bind,
        };
        tracks.push(Track {
            joint,
            translation,
            rotation,
            scale,
        });
    }
    // Number the components in order (translation, rotation, scale per track).
    let mut next = 0u32;
    let mut rotations = Vec::new();
    for t in &mut tracks {
        if let Channel::Animated(o) = &mut t.translation {
            *o = next;
            next += 3;
        }
        if let Channel::Animated(o) = &mut t.rotation {
            *o = next;
            rotations.push(next);
            next += 3;
        }
        if let Channel::Animated(o) = &mut t.scale {
            *o = next;
            next += 3;
        }
    }
    if next != components {
        return Err(c.err_at(
            comp_at,
            K::BadValue {
                what: "component count",
                value: components.into(),
            },
        ));
    }
    let compact = flags & CLIP_COMPACT != 0;
    let rotation_comps: Vec<bool> = {
        let mut v = vec![false; next as usize];
        for &r in &rotations {
            for i in r..r + 3 {
                if let Some(x) = v.get_mut(i as usize) {
                    *x = true;
                }
            }
        }
        v
    };
    let ranges: Vec<[f32; 2]> = if compact {
        // 16-bit pairs for rotation components, f32 pairs for the others.
        let rot = rotation_comps.iter().filter(|&&r| r).count() as u64;
        let bytes = (u64::from(components) - rot) * 8 + rot * 4;
        let raw = c.elements(bytes, 1, "component ranges")?;
        let mut out = Vec::with_capacity(rotation_comps.len());
        let mut at = 0usize;
        for &is_rot in &rotation_comps {
            let n = if is_rot { 4 } else { 8 };
            let mut b = [0u8; 8];
            if let Some(src) = raw.get(at..at + n) {
                b[..n].copy_from_slice(src);
            }
            at += n;
            out.push(if is_rot {
                range_from_units([
                    u16::from_le_bytes([b[0], b[1]]),
                    u16::from_le_bytes([b[2], b[3]]),
                ])
            } else {
                [
                    f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                    f32::from_le_bytes([b[4], b[5], b[6], b[7]]),
                ]
            });
        }
        out
    } else {
        let range_floats = c.f32s(u64::from(components) * 2, "component ranges")?;
        range_floats.chunks_exact(2).map(|r| [r[0], r[1]]).collect()
    };
    c.align()?;
    let seg_count = u64::from(key_count).div_ceil(u64::from(segment_len));
    let entries = seg_count.saturating_mul(components.into());
    let segments: Vec<SegmentComponent> = if flags & CLIP_PACKED_SEGMENTS != 0 {
        // 5-bit widths, then (unless whole ranges) the starts, then the lengths.
        let widths = c.elements(
            entries.saturating_mul(5).div_ceil(8),
            1,
            "segment bit widths",
        )?;
        let (mins, extents): (&[u8], &[u8]) = if flags & CLIP_WHOLE_RANGES != 0 {
            (&[], &[])
        } else {
            let m = c.elements(entries, 1, "segment range starts")?;
            let e = c.elements(entries, 1, "segment range lengths")?;
            (m, e)
        };
        // `entries` is at most 8/5 of the width bytes present, so it fits in memory.
        (0..entries as usize)
            .map(|i| {
                let bits = (0..5).fold(0u8, |v, b| {
                    let at = i * 5 + b;
                    v | (widths.get(at / 8).map_or(0, |x| x >> (at % 8) & 1) << b)
                });
                SegmentComponent {
                    bits,
                    min: mins.get(i).copied().unwrap_or(0),
                    extent: extents.get(i).copied().unwrap_or(255),
                }
            })
            .collect()
    } else {
        c.elements(entries, 3, "segment component entries")?
            .chunks_exact(3)
            .map(|b| SegmentComponent {
                bits: b[0],
                min: b[1],
                extent: b[2],
            })
            .collect()
    };
    c.align()?;
    let rotation_index = if compact {
        let v = c
            .elements(
                seg_count.saturating_mul(rotations.len() as u64),
                1,
                "rotation index entries",
            )?
            .to_vec();
        c.align()?;
        v
    } else {
        Vec::new()
    };
    // The data's exact length follows from the bit widths: per segment, ceil(record bits * keys / 8)
    // (a shared rotation index takes no bits in the records).
    let comps = components as usize;
    let mut needed = 0u64;
    for (s, seg) in segments.chunks(comps.max(1)).enumerate() {
        let stored = if compact {
            rotation_index
                .iter()
                .skip(s * rotations.len())
                .take(rotations.len())
                .filter(|&&i| i > 3)
                .count()
        } else {
            rotations.len()
        };
        let bits: u64 = seg.iter().map(|e| u64::from(e.bits)).sum::<u64>() + 2 * stored as u64;
        let first = s as u64 * u64::from(segment_len);
        let keys = u64::from(segment_len).min(u64::from(key_count).saturating_sub(first));
        needed = needed.saturating_add((bits * keys).div_ceil(8));
    }
    let data = c.elements(needed, 1, "compressed data bytes")?.to_vec();
    let parts = QuantizedParts {
        segment_len,
        ranges,
        segments,
        rotation_index,
        data,
    };
    Clip::from_quantized(
        name,
        duration,
        sample_rate,
        flags & CLIP_LOOPING != 0,
        flags & CLIP_ADDITIVE != 0,
        times,
        tracks,
        parts,
    )
    .map_err(|e| c.err_at(start, K::Invalid(e.to_string())))
}
