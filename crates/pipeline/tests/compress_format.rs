//! Compressed clips in `.sinew` files: round trip, and a reader that rejects malformed compressed
//! payloads (bit widths above 24, non-finite ranges, data past the end) without panicking.

#![allow(clippy::unwrap_used)]

use sinew_core::format::{self, Asset, FormatErrorKind, Tag};
use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Clip, ClipBinding, Curve, JointDesc, Sampler, Skeleton, TrackCurves, Transform};
use sinew_pipeline::compress::{compress_clip, CompressOptions};

fn skeleton() -> Skeleton {
    let joint = |name: &str, parent: Option<&str>, y: f32| JointDesc {
        name: name.into(),
        parent: parent.map(Into::into),
        bind_local: Transform::from_translation(Vec3::Y * y),
        inverse_bind: None,
    };
    Skeleton::from_unordered(vec![
        joint("root", None, 1.0),
        joint("spine", Some("root"), 0.5),
        joint("head", Some("spine"), 0.5),
    ])
    .unwrap()
    .0
}

fn clip() -> Clip {
    clip_of(40)
}

/// [`clip`] with `keys` keys at 20 Hz.
fn clip_of(keys: usize) -> Clip {
    let times: Vec<f32> = (0..keys).map(|k| k as f32 / 20.0).collect();
    let wave = |f: f32| -> Vec<Quat> {
        times
            .iter()
            .map(|t| Quat::from_rotation_z((t * f).sin()))
            .collect()
    };
    Clip::from_curves(
        "sway",
        times[keys - 1],
        20.0,
        false,
        false,
        vec![
            TrackCurves {
                joint: "root".into(),
                translation: Curve::new(
                    times.clone(),
                    times.iter().map(|t| Vec3::new(*t, 1.0, 0.0)).collect(),
                ),
                rotation: Curve::new(times.clone(), wave(3.0)),
                ..Default::default()
            },
            TrackCurves {
                joint: "spine".into(),
                rotation: Curve::new(times.clone(), wave(5.0)),
                scale: Curve::new(
                    times.clone(),
                    times.iter().map(|t| Vec3::splat(1.0 + t * 0.1)).collect(),
                ),
                ..Default::default()
            },
        ],
    )
    .unwrap()
}

fn compressed_file() -> (Vec<u8>, Clip) {
    compressed_file_of(clip())
}

fn compressed_file_of(clip: Clip) -> (Vec<u8>, Clip) {
    let (c, r) = compress_clip(&clip, Some(&skeleton()), &CompressOptions::default());
    assert!(c.is_compressed(), "{r:?}");
    let asset = Asset {
        clips: vec![c.clone()],
        ..Default::default()
    };
    (format::write(&asset).unwrap(), c)
}

/// Recomputes the CLIP section's CRC and the header CRC after editing bytes.
fn fix_crcs(bytes: &mut [u8]) {
    let count = u32::from_le_bytes(bytes[32..36].try_into().unwrap()) as usize;
    for i in 0..count {
        let e = 48 + i * 32;
        let off = u64::from_le_bytes(bytes[e + 8..e + 16].try_into().unwrap()) as usize;
        let size = u64::from_le_bytes(bytes[e + 16..e + 24].try_into().unwrap()) as usize;
        let crc = crc32fast::hash(&bytes[off..off + size]);
        bytes[e + 24..e + 28].copy_from_slice(&crc.to_le_bytes());
    }
    let mut h = crc32fast::Hasher::new();
    h.update(&bytes[..44]);
    h.update(&bytes[48..48 + count * 32]);
    let crc = h.finalize();
    bytes[44..48].copy_from_slice(&crc.to_le_bytes());
}

fn clip_record_offset(bytes: &[u8]) -> usize {
    let s = format::sections(bytes).unwrap();
    s.iter().find(|s| s.tag == Tag::CLIPS).unwrap().offset as usize + 16
}

fn pad(n: usize) -> usize {
    n.div_ceil(16) * 16
}

/// Per component: whether it belongs to a rotation (16-bit range in a compact record).
fn rotation_components(c: &Clip) -> Vec<bool> {
    let n = c.quantized_parts().unwrap().ranges.len();
    let mut out = vec![false; n];
    for t in c.tracks() {
        if let sinew_core::Channel::Animated(o) = t.rotation {
            out[o as usize..o as usize + 3].fill(true);
        }
    }
    out
}

/// Offset of the track table inside the clip record of `bytes` (the file's only clip), from the
/// documented layout: after the key times, f32 or packed (flag bit 5: a 16-byte header whose bytes
/// 12 and 13 are the gap and residual widths, then key 0's residual and each further key's gap and
/// residual).
fn track_table_offset(bytes: &[u8], n: usize) -> usize {
    let rec = clip_record_offset(bytes);
    let flags = u32::from_le_bytes(bytes[rec + 4..rec + 8].try_into().unwrap());
    if flags & 32 != 0 {
        let (gap, res) = (bytes[rec + 44] as usize, bytes[rec + 45] as usize);
        pad(32 + 16 + (res + (n - 1) * (gap + res)).div_ceil(8))
    } else {
        pad(32 + 4 * n)
    }
}

/// Offset of the component ranges inside the clip record, from the documented layout.
fn ranges_offset(bytes: &[u8], c: &Clip) -> usize {
    let constants: usize = c
        .tracks()
        .iter()
        .map(|t| {
            use sinew_core::Channel::Constant;
            [
                matches!(t.translation, Constant(_)) as usize * 3,
                matches!(t.rotation, Constant(_)) as usize * 4,
                matches!(t.scale, Constant(_)) as usize * 3,
            ]
            .iter()
            .sum::<usize>()
        })
        .sum();
    let mut at = track_table_offset(bytes, c.times().len());
    // Short track table: a u16 name per track, then a byte of kinds per track.
    at = pad(at + 3 * c.tracks().len());
    pad(at + 4 * constants)
}

/// Offset of the segment entries inside the (compact) clip record, from the documented layout:
/// 4 bytes per rotation component's range, 8 per other component's.
fn segments_offset(bytes: &[u8], c: &Clip) -> usize {
    let ranges: usize = rotation_components(c)
        .iter()
        .map(|&r| if r { 4 } else { 8 })
        .sum();
    pad(ranges_offset(bytes, c) + ranges)
}

/// Offset of the per-segment rotation index table (compact records).
fn rotation_index_offset(bytes: &[u8], c: &Clip) -> usize {
    segments_offset(bytes, c) + packed_segments_len(bytes, c)
}

#[test]
fn compressed_clip_round_trips_and_header_says_1_5() {
    let (bytes, c) = compressed_file();
    assert_eq!(u16::from_le_bytes([bytes[10], bytes[11]]), 5);
    let back = format::read(&bytes).unwrap();
    assert_eq!(back.clips[0], c);
    let rec = clip_record_offset(&bytes);
    // Flags: bit 2 (compressed), bit 3 (compact), bit 4 (short track table), bit 5 (packed key
    // times), bit 6 (packed segment entries), and bit 7 exactly when every sub-range is the whole
    // range (this clip is one segment).
    let parts = c.quantized_parts().unwrap();
    assert_eq!(parts.segments.len(), parts.ranges.len());
    let whole = parts.segments.iter().all(|e| (e.min, e.extent) == (0, 255));
    assert_eq!(
        u32::from_le_bytes(bytes[rec + 4..rec + 8].try_into().unwrap()),
        124 | if whole { 128 } else { 0 }
    );
    // The packed key times decode, by the documented layout, to the clip's times bit for bit.
    assert_eq!(decode_packed_times(&bytes, rec, c.times().len()), c.times());
    // The short track table: u16 names (the clip's name is string 0, "root" and "spine" follow),
    // then one byte per track: 2 bits of kind per channel (0 bind, 1 constant, 3 quantized).
    let tt = rec + track_table_offset(&bytes, c.times().len());
    let u16_at = |i: usize| u16::from_le_bytes([bytes[i], bytes[i + 1]]);
    assert_eq!((u16_at(tt), u16_at(tt + 2)), (1, 2));
    // root: translation and rotation quantized, scale bind; spine: rotation and scale quantized.
    assert_eq!(bytes[tt + 4], 3 | 3 << 2);
    assert_eq!(bytes[tt + 5], 3 << 2 | 3 << 4);
    // The segment entries sit where docs/format.md says, and decode to the clip's.
    let parts = c.quantized_parts().unwrap();
    assert_eq!(packed_segments(&bytes, &c), segment_entries(&c));
    // Then the rotation index table: one byte per segment and rotation, each 0-3 or 255.
    let rotations = rotation_components(&c).iter().filter(|&&r| r).count() / 3;
    assert_eq!(rotations, 2);
    let at = rec + rotation_index_offset(&bytes, &c);
    let table = &bytes[at..at + parts.rotation_index.len()];
    assert_eq!(table, &parts.rotation_index[..]);
    assert_eq!(
        table.len(),
        rotations * parts.segments.len() / parts.ranges.len()
    );
    assert!(table.iter().all(|&i| i <= 3 || i == 255), "{table:?}");
    // A rotation range is two u16: (min + 1) and extent in units of 2^-15.
    let first_rot = rotation_components(&c).iter().position(|&r| r).unwrap();
    let ro = rec + ranges_offset(&bytes, &c) + 8 * first_rot;
    let u = |i: usize| f32::from(u16::from_le_bytes([bytes[ro + i], bytes[ro + i + 1]]));
    assert_eq!(u(0) / 32768.0 - 1.0, parts.ranges[first_rot][0]);
    assert_eq!(u(2) / 32768.0, parts.ranges[first_rot][1]);
}

#[test]
fn reader_rejects_a_bad_rotation_index_entry_and_a_compact_flag_alone() {
    let (bytes, c) = compressed_file();
    let rec = clip_record_offset(&bytes);
    let mut b = bytes.clone();
    b[rec + rotation_index_offset(&bytes, &c)] = 7;
    fix_crcs(&mut b);
    let e = format::read(&b).unwrap_err();
    assert_eq!(e.section, "CLIP");
    assert!(
        matches!(
            e.kind,
            FormatErrorKind::Invalid(_) | FormatErrorKind::CountTooLarge { .. }
        ),
        "{e}"
    );
    // Bit 3 without bit 2 is not a layout.
    let mut b = bytes;
    b[rec + 4..rec + 8].copy_from_slice(&8u32.to_le_bytes());
    fix_crcs(&mut b);
    let e = format::read(&b).unwrap_err();
    assert!(e.to_string().contains("clip flags"), "{e}");
}

/// The key times of a packed block (clip flag bit 5) at `rec + 32`, decoded as docs/format.md
/// says: f64 step, u32 first frame, u8 gap and residual widths; then key 0's residual and, per
/// further key, its gap less one and its residual, least significant bit first; a time is the f32
/// of `frame * step` (in f64) plus its residual in units of the last place.
fn decode_packed_times(bytes: &[u8], rec: usize, n: usize) -> Vec<f32> {
    let at = rec + 32;
    let step = f64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
    let mut frame = u64::from(u32::from_le_bytes(
        bytes[at + 8..at + 12].try_into().unwrap(),
    ));
    let (gap, res) = (bytes[at + 12] as usize, bytes[at + 13] as usize);
    let data = &bytes[at + 16..];
    let mut bit = 0;
    let mut read = |w: usize| -> u64 {
        let v = (0..w).fold(0u64, |v, b| {
            v | (u64::from(data[(bit + b) / 8] >> ((bit + b) % 8) & 1) << b)
        });
        bit += w;
        v
    };
    (0..n)
        .map(|k| {
            if k > 0 {
                frame += read(gap) + 1;
            }
            let r = read(res);
            let r = if r >> (res - 1) & 1 == 1 {
                r as i64 - (1i64 << res)
            } else {
                r as i64
            };
            let grid = (frame as f64 * step) as f32;
            f32::from_bits((i64::from(grid.to_bits()) + r) as u32)
        })
        .collect()
}

/// The segment entries of the (packed, flag bit 6) record as (bits, start, length), decoded as
/// docs/format.md says: 5-bit widths, least significant bit first, then the starts, then the
/// lengths, both left out (0 and 255) with flag bit 7.
fn packed_segments(bytes: &[u8], c: &Clip) -> Vec<(u8, u8, u8)> {
    let rec = clip_record_offset(bytes);
    let flags = u32::from_le_bytes(bytes[rec + 4..rec + 8].try_into().unwrap());
    assert_ne!(flags & 64, 0, "packed segment entries");
    let at = rec + segments_offset(bytes, c);
    let e = c.quantized_parts().unwrap().segments.len();
    let w = (5 * e).div_ceil(8);
    (0..e)
        .map(|i| {
            let bits = (0..5).fold(0u8, |v, b| {
                v | ((bytes[at + (5 * i + b) / 8] >> ((5 * i + b) % 8) & 1) << b)
            });
            if flags & 128 != 0 {
                (bits, 0, 255)
            } else {
                (bits, bytes[at + w + i], bytes[at + w + e + i])
            }
        })
        .collect()
}

/// The clip's segment entries as (bits, start, length).
fn segment_entries(c: &Clip) -> Vec<(u8, u8, u8)> {
    c.quantized_parts()
        .map(|p| {
            p.segments
                .iter()
                .map(|e| (e.bits, e.min, e.extent))
                .collect()
        })
        .unwrap_or_default()
}

/// Bytes of the packed segment block, padding included.
fn packed_segments_len(bytes: &[u8], c: &Clip) -> usize {
    let rec = clip_record_offset(bytes);
    let flags = u32::from_le_bytes(bytes[rec + 4..rec + 8].try_into().unwrap());
    let e = c.quantized_parts().unwrap().segments.len();
    let seg = rec + segments_offset(bytes, c);
    let end = seg + (5 * e).div_ceil(8) + if flags & 128 != 0 { 0 } else { 2 * e };
    pad(end - rec) - (seg - rec)
}

/// The same file in the layout of format 1.4, built by hand from the documented layouts: key
/// times as f32 (the clip's own), the track table in the 8-byte form (u32 name, four kind bytes
/// per track) and segment entries as three bytes (width, start, length). The CLIP section must be
/// the last.
fn to_1_4(bytes: &[u8], c: &Clip) -> Vec<u8> {
    let rec = clip_record_offset(bytes);
    let tt = rec + track_table_offset(bytes, c.times().len());
    let tracks = c.tracks().len();
    let mut times: Vec<u8> = c.times().iter().flat_map(|t| t.to_le_bytes()).collect();
    times.resize(pad(32 + times.len()) - 32, 0);
    let mut table = Vec::new();
    for t in 0..tracks {
        let name = u16::from_le_bytes([bytes[tt + 2 * t], bytes[tt + 2 * t + 1]]);
        let k = bytes[tt + 2 * tracks + t];
        table.extend_from_slice(&u32::from(name).to_le_bytes());
        table.extend_from_slice(&[k & 3, (k >> 2) & 3, (k >> 4) & 3, 0]);
    }
    table.resize(pad(table.len()), 0);
    let seg = rec + segments_offset(bytes, c);
    let mut entries: Vec<u8> = packed_segments(bytes, c)
        .into_iter()
        .flat_map(|(b, m, e)| [b, m, e])
        .collect();
    entries.resize(pad(entries.len()), 0);
    let mut out = bytes[..rec + 32].to_vec();
    out.extend_from_slice(&times);
    out.extend_from_slice(&table);
    out.extend_from_slice(&bytes[tt + pad(3 * tracks)..seg]);
    out.extend_from_slice(&entries);
    out.extend_from_slice(&bytes[seg + packed_segments_len(bytes, c)..]);
    let delta = out.len() as i64 - bytes.len() as i64;
    let flags =
        u32::from_le_bytes(out[rec + 4..rec + 8].try_into().unwrap()) & !(16 | 32 | 64 | 128);
    out[rec + 4..rec + 8].copy_from_slice(&flags.to_le_bytes());
    out[10..12].copy_from_slice(&4u16.to_le_bytes());
    let file_size = out.len() as u64;
    out[16..24].copy_from_slice(&file_size.to_le_bytes());
    let count = u32::from_le_bytes(out[32..36].try_into().unwrap()) as usize;
    for i in 0..count {
        let e = 48 + i * 32;
        if &out[e..e + 4] == b"CLIP" {
            let size = u64::from_le_bytes(out[e + 16..e + 24].try_into().unwrap());
            out[e + 16..e + 24].copy_from_slice(&((size as i64 + delta) as u64).to_le_bytes());
        }
    }
    fix_crcs(&mut out);
    out
}

#[test]
fn a_clip_of_several_segments_stores_its_sub_ranges() {
    // 400 keys: segments of 16 or 32 keys, so sub-ranges narrower than the clip's.
    let (bytes, c) = compressed_file_of(clip_of(400));
    let parts = c.quantized_parts().unwrap();
    assert!(
        parts.segments.len() >= 13 * parts.ranges.len(),
        "{}",
        parts.segments.len()
    );
    assert!(parts.segments.iter().any(|e| (e.min, e.extent) != (0, 255)));
    let rec = clip_record_offset(&bytes);
    let flags = u32::from_le_bytes(bytes[rec + 4..rec + 8].try_into().unwrap());
    assert_eq!(flags & (64 | 128), 64);
    assert_eq!(packed_segments(&bytes, &c), segment_entries(&c));
    assert_eq!(format::read(&bytes).unwrap().clips[0], c);
    // And in the 1.4 layout, three bytes per entry.
    assert_eq!(format::read(&to_1_4(&bytes, &c)).unwrap().clips[0], c);
}

#[test]
fn a_1_4_record_reads_as_the_same_clip() {
    let (bytes, c) = compressed_file();
    let old = to_1_4(&bytes, &c);
    assert!(old.len() > bytes.len(), "{} vs {}", old.len(), bytes.len());
    let rec = clip_record_offset(&old);
    assert_eq!(
        u32::from_le_bytes(old[rec + 4..rec + 8].try_into().unwrap()),
        12
    );
    let back = format::read(&old).unwrap();
    assert_eq!(back.clips[0], c);
}

#[test]
fn reader_rejects_bad_packed_key_times() {
    let (bytes, _) = compressed_file();
    let at = clip_record_offset(&bytes) + 32;
    let bad = |edit: &dyn Fn(&mut Vec<u8>)| {
        let mut b = bytes.clone();
        edit(&mut b);
        fix_crcs(&mut b);
        let e = format::read(&b).unwrap_err();
        assert_eq!(e.section, "CLIP");
        e.to_string()
    };
    // A step that is not a positive number.
    for step in [f64::NAN, 0.0, -0.05, f64::INFINITY] {
        let e = bad(&|b| b[at..at + 8].copy_from_slice(&step.to_le_bytes()));
        assert!(e.contains("step") || e.contains("time"), "{step}: {e}");
    }
    // Widths above 32, and a residual width of 0.
    for (i, w) in [(12, 33u8), (13, 33), (13, 0)] {
        let e = bad(&|b| b[at + i] = w);
        assert!(e.contains("bit widths"), "{e}");
    }
    // A first frame so far out that the times are no longer finite, or no longer increasing
    // against nothing: the step raised so far that times overflow f32.
    let e = bad(&|b| b[at..at + 8].copy_from_slice(&1e300f64.to_le_bytes()));
    assert!(e.contains("time"), "{e}");
}

#[test]
fn reader_rejects_bit_widths_above_24() {
    let (mut bytes, c) = compressed_file();
    let at = clip_record_offset(&bytes) + segments_offset(&bytes, &c);
    // The first entry's width is the low 5 bits of the first byte: 31.
    bytes[at] |= 31;
    fix_crcs(&mut bytes);
    let e = format::read(&bytes).unwrap_err();
    // Either the data length no longer matches or the width is refused: never a panic or a clip.
    assert_eq!(e.section, "CLIP");
    assert!(
        matches!(
            e.kind,
            FormatErrorKind::Invalid(_) | FormatErrorKind::CountTooLarge { .. }
        ),
        "{e}"
    );
}

#[test]
fn reader_rejects_non_finite_ranges() {
    let (mut bytes, c) = compressed_file();
    // The first component is the root's translation: an f32 range even in a compact record.
    assert!(!rotation_components(&c)[0]);
    let at = clip_record_offset(&bytes) + ranges_offset(&bytes, &c);
    bytes[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    fix_crcs(&mut bytes);
    let e = format::read(&bytes).unwrap_err();
    assert!(e.to_string().contains("range"), "{e}");
}

#[test]
fn reader_rejects_data_past_the_end() {
    let (mut bytes, _) = compressed_file();
    // Claim more keys than the record holds: key times, segments and data all run past the section.
    let rec = clip_record_offset(&bytes);
    bytes[rec + 16..rec + 20].copy_from_slice(&100_000u32.to_le_bytes());
    fix_crcs(&mut bytes);
    let e = format::read(&bytes).unwrap_err();
    assert!(
        matches!(e.kind, FormatErrorKind::CountTooLarge { .. }),
        "{e}"
    );
}

#[test]
fn every_single_byte_corruption_of_the_clip_section_is_an_error_or_a_usable_clip() {
    let (bytes, _) = compressed_file();
    let s = format::sections(&bytes).unwrap();
    let clip = s.iter().find(|s| s.tag == Tag::CLIPS).unwrap();
    let sk = skeleton();
    let mut accepted = 0;
    for at in clip.offset as usize..(clip.offset + clip.size) as usize {
        for x in [0x01u8, 0x80, 0xFF] {
            let mut b = bytes.clone();
            b[at] ^= x;
            fix_crcs(&mut b);
            if let Ok(asset) = format::read(&b) {
                accepted += 1;
                for c in &asset.clips {
                    let binding = ClipBinding::new(c, &sk);
                    let mut out = vec![Transform::IDENTITY; sk.len()];
                    for t in [-1.0, 0.0, 0.37, 1.0, 5.0] {
                        Sampler::new()
                            .sample(c, &binding, &sk, t, &mut out)
                            .unwrap();
                    }
                    let _ = c.to_plain();
                }
            }
        }
    }
    // Flipping quantized data bits gives another valid clip: some corruptions must be accepted.
    assert!(accepted > 0);
    for len in 0..bytes.len() {
        assert!(format::read(&bytes[..len]).is_err());
    }
}
