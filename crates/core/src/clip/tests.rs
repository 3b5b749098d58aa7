//! Unit tests of clip data, binding and sampling.

use super::data::*;
use super::*;
use crate::compressed::QuantizedParts;
use crate::compressed::SegmentComponent;
use crate::skeleton::JointDesc;
use crate::skeleton::Skeleton;
use crate::Transform;
use glam::{Quat, Vec3};

fn skeleton() -> Skeleton {
    Skeleton::from_unordered(vec![
        JointDesc {
            name: "root".into(),
            parent: None,
            bind_local: Transform::from_translation(Vec3::new(0.0, 1.0, 0.0)),
            inverse_bind: None,
        },
        JointDesc {
            name: "arm".into(),
            parent: Some("root".into()),
            bind_local: Transform::from_translation(Vec3::new(1.0, 0.0, 0.0)),
            inverse_bind: None,
        },
    ])
    .unwrap()
    .0
}

fn walk(looping: bool) -> Clip {
    // Root x goes 0, 1, 4 at times 0, 0.5, 1.0; the arm rotates 0 -> 90 degrees about z.
    let duration = if looping { 1.5 } else { 1.0 };
    Clip::from_curves(
        "walk",
        duration,
        2.0,
        looping,
        false,
        vec![
            TrackCurves {
                joint: "root".into(),
                translation: Curve::new(
                    vec![0.0, 0.5, 1.0],
                    vec![Vec3::ZERO, Vec3::X, Vec3::X * 4.0],
                ),
                ..Default::default()
            },
            TrackCurves {
                joint: "arm".into(),
                rotation: Curve::new(
                    vec![0.0, 1.0],
                    vec![
                        Quat::IDENTITY,
                        Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
                    ],
                ),
                scale: Curve::new(vec![0.0], vec![Vec3::splat(2.0)]),
                ..Default::default()
            },
            TrackCurves {
                joint: "tail".into(),
                translation: Curve::new(vec![0.0], vec![Vec3::ONE]),
                ..Default::default()
            },
        ],
    )
    .unwrap()
}

fn sample(clip: &Clip, t: f32) -> Vec<Transform> {
    let s = skeleton();
    let b = ClipBinding::new(clip, &s);
    let mut out = vec![Transform::IDENTITY; s.len()];
    Sampler::new().sample(clip, &b, &s, t, &mut out).unwrap();
    out
}

#[test]
fn layout_is_union_of_key_times_and_constants_stored_once() {
    let c = walk(false);
    assert_eq!(c.times(), [0.0, 0.5, 1.0]);
    // root translation (3) + arm rotation (4); the arm's scale is a constant.
    assert_eq!(c.stride(), 7);
    assert_eq!(c.tracks()[1].scale, Channel::Constant(Vec3::splat(2.0)));
    assert_eq!(c.tracks()[0].rotation, Channel::Bind);
    // The arm rotation at 0.5 (not one of its keys) was filled in by interpolation: 45 degrees.
    let q = Quat::from_slice(&c.frames()[7 + 3..7 + 7]);
    assert!(q.angle_between(Quat::from_rotation_z(std::f32::consts::FRAC_PI_4)) < 1e-5);
}

#[test]
fn key_times_are_the_union_whether_curves_share_them_or_not() {
    let moving = |times: &[f32]| {
        let values = (0..times.len()).map(|i| Vec3::splat(i as f32)).collect();
        Curve::new(times.to_vec(), values)
    };
    let track = |joint: &str, t: &[f32], s: &[f32]| TrackCurves {
        joint: joint.into(),
        translation: moving(t),
        scale: moving(s),
        ..Default::default()
    };
    // Shared times (appended once), then other times, then the first ones again: the union.
    let c = Clip::from_curves(
        "c",
        2.0,
        30.0,
        false,
        false,
        vec![
            track("a", &[0.0, 1.0, 2.0], &[0.0, 1.0, 2.0]),
            track("b", &[0.5, 1.5], &[0.0, 1.0, 2.0]),
        ],
    )
    .unwrap();
    assert_eq!(c.times(), [0.0, 0.5, 1.0, 1.5, 2.0]);
    // -0 and +0 are not the same bits, so both curves are appended; the sort puts -0 first and
    // the dedup keeps it, as it did before identical times were skipped.
    let c = Clip::from_curves(
        "z",
        1.0,
        30.0,
        false,
        false,
        vec![
            track("a", &[-0.0, 1.0], &[-0.0, 1.0]),
            track("b", &[0.0, 1.0], &[0.0, 1.0]),
        ],
    )
    .unwrap();
    assert_eq!(c.times().len(), 2);
    assert_eq!(c.times()[0].to_bits(), (-0.0f32).to_bits());
}

#[test]
fn samples_exact_at_keys_and_linear_between() {
    let c = walk(false);
    assert_eq!(sample(&c, 0.5)[0].translation, Vec3::X);
    assert_eq!(sample(&c, 1.0)[0].translation, Vec3::X * 4.0);
    let mid = sample(&c, 0.75)[0].translation;
    assert!((mid - Vec3::X * 2.5).length() < 1e-6);
    // Bind value fills the root's rotation and scale; the arm keeps its bind translation.
    let p = sample(&c, 0.25);
    assert_eq!(p[0].rotation, Quat::IDENTITY);
    assert_eq!(p[1].translation, Vec3::X);
    assert_eq!(p[1].scale, Vec3::splat(2.0));
}

#[test]
fn non_looping_clamps_before_zero_and_after_end() {
    let c = walk(false);
    assert_eq!(sample(&c, -3.0)[0].translation, Vec3::ZERO);
    assert_eq!(sample(&c, 7.0)[0].translation, Vec3::X * 4.0);
}

#[test]
fn looping_wraps_and_interpolates_back_to_first_frame() {
    let c = walk(true);
    // Duration 1.5: from the last key (1.0, x=4) back to frame 0 (x=0) at 1.5.
    let p = sample(&c, 1.25)[0].translation;
    assert!((p - Vec3::X * 2.0).length() < 1e-6, "{p}");
    // 2.0 wraps to 0.5.
    assert_eq!(sample(&c, 2.0)[0].translation, Vec3::X);
    // -0.25 wraps to 1.25.
    let n = sample(&c, -0.25)[0].translation;
    assert!((n - Vec3::X * 2.0).length() < 1e-6, "{n}");
}

#[test]
fn binding_lists_unmatched_names_and_leaves_other_joints_alone() {
    let c = walk(false);
    let s = skeleton();
    let b = ClipBinding::new(&c, &s);
    assert_eq!(b.unmatched(), ["tail"]);
    assert_eq!(b.driven(), [0, 1]);
    let partial = Clip::from_curves(
        "arm only",
        1.0,
        1.0,
        false,
        false,
        vec![TrackCurves {
            joint: "arm".into(),
            translation: Curve::new(vec![0.0], vec![Vec3::Y]),
            ..Default::default()
        }],
    )
    .unwrap();
    let b = ClipBinding::new(&partial, &s);
    let marker = Transform::from_translation(Vec3::splat(9.0));
    let mut out = vec![marker; 2];
    Sampler::new()
        .sample(&partial, &b, &s, 0.3, &mut out)
        .unwrap();
    assert_eq!(out[0], marker);
    assert_eq!(out[1].translation, Vec3::Y);
}

#[test]
fn cursor_moves_forward_and_recovers_on_jumps_back() {
    let c = walk(false);
    let mut s = Sampler::new();
    assert_eq!(s.locate(&c, 0.1).0, 0);
    assert_eq!(s.locate(&c, 0.6).0, 1);
    assert_eq!(s.cursor, 1);
    assert_eq!(s.locate(&c, 0.2).0, 0);
    assert_eq!(s.locate(&c, 1.0), (2, 2, 0.0));
}

#[test]
fn rejects_bad_curves() {
    let bad = |curve: Curve<Vec3>| {
        Clip::from_curves(
            "x",
            1.0,
            1.0,
            false,
            false,
            vec![TrackCurves {
                joint: "a".into(),
                translation: curve,
                ..Default::default()
            }],
        )
    };
    assert!(matches!(
        bad(Curve::new(vec![0.0, 0.0], vec![Vec3::ZERO, Vec3::X])),
        Err(ClipError::BadTimes(_))
    ));
    assert!(matches!(
        bad(Curve::new(vec![0.0], vec![Vec3::NAN])),
        Err(ClipError::NonFinite(_))
    ));
    assert!(matches!(
        bad(Curve::new(vec![0.0, 2.0], vec![Vec3::ZERO, Vec3::X])),
        Err(ClipError::BadDuration(_))
    ));
    assert!(matches!(
        bad(Curve::new(vec![0.0], vec![])),
        Err(ClipError::LengthMismatch(_))
    ));
}

/// The sampler as it was before the work lists and the key cache, kept as the reference the new
/// loops must match bit for bit.
fn reference(clip: &Clip, b: &ClipBinding, sk: &Skeleton, t: f32, out: &mut [Transform]) {
    let t = clip.local_time(t);
    let (k0, k1, a) = Sampler::new().locate(clip, t);
    let bind = sk.bind_local();
    let lerp3 = |f0: &[f32], f1: &[f32], o: usize| {
        let v0 = Vec3::new(f0[o], f0[o + 1], f0[o + 2]);
        if a == 0.0 {
            v0
        } else {
            v0.lerp(Vec3::new(f1[o], f1[o + 1], f1[o + 2]), a)
        }
    };
    for (track, joint) in clip.tracks.iter().zip(&b.joint_of_track) {
        let Some(j) = *joint else { continue };
        let j = j as usize;
        let d = if clip.additive {
            Transform::IDENTITY
        } else {
            bind[j]
        };
        if let Some(q) = &clip.quantized {
            let (f0, f1) = (q.key(k0), q.key(k1));
            let v = |c: Channel<Vec3>, d: Vec3| match c {
                Channel::Bind => d,
                Channel::Constant(v) => v,
                Channel::Animated(o) if a == 0.0 => f0.vec3(o as usize),
                Channel::Animated(o) => f0.vec3(o as usize).lerp(f1.vec3(o as usize), a),
            };
            out[j] = Transform {
                translation: v(track.translation, d.translation),
                rotation: match track.rotation {
                    Channel::Bind => d.rotation,
                    Channel::Constant(r) => r,
                    Channel::Animated(o) if a == 0.0 => normalize_rotation(f0.quat_raw(o as usize)),
                    Channel::Animated(o) => {
                        nlerp(f0.quat_raw(o as usize), f1.quat_raw(o as usize), a)
                    }
                },
                scale: v(track.scale, d.scale),
            };
            continue;
        }
        let s = clip.stride;
        let (f0, f1) = (
            &clip.frames[k0 * s..(k0 + 1) * s],
            &clip.frames[k1 * s..(k1 + 1) * s],
        );
        let v = |c: Channel<Vec3>, d: Vec3| match c {
            Channel::Bind => d,
            Channel::Constant(v) => v,
            Channel::Animated(o) => lerp3(f0, f1, o as usize),
        };
        out[j] = Transform {
            translation: v(track.translation, d.translation),
            rotation: match track.rotation {
                Channel::Bind => d.rotation,
                Channel::Constant(r) => r,
                Channel::Animated(o) => {
                    let o = o as usize;
                    let q0 = Quat::from_slice(&f0[o..o + 4]);
                    if a == 0.0 {
                        q0
                    } else {
                        nlerp(q0, Quat::from_slice(&f1[o..o + 4]), a)
                    }
                }
            },
            scale: v(track.scale, d.scale),
        };
    }
}

use crate::transform::transform_bits as bits;

/// A compressed clip built by hand: root translation (3 components), arm rotation (3) and arm scale
/// (3), 5 keys in segments of 2, pseudo-random quantized values.
fn compressed(looping: bool, additive: bool) -> Clip {
    compressed_with(compressed_tracks(), looping, additive, &[0, 3, 7, 12, 16])
}

/// Both joints animate translation and rotation (and scale with `scale`): every block of the key
/// slots loads by transposition.
fn compressed_uniform(scale: bool, bits: &[u8]) -> Clip {
    let per = if scale { 9 } else { 6 };
    let tracks = ["root", "arm"]
        .iter()
        .enumerate()
        .map(|(i, n)| Track {
            joint: (*n).into(),
            translation: Channel::Animated((i * per) as u32),
            rotation: Channel::Animated((i * per + 3) as u32),
            scale: if scale {
                Channel::Animated((i * per + 6) as u32)
            } else {
                Channel::Bind
            },
        })
        .collect();
    compressed_with(tracks, true, false, bits)
}

fn compressed_tracks() -> Vec<Track> {
    vec![
        Track {
            joint: "root".into(),
            translation: Channel::Animated(0),
            rotation: Channel::Constant(Quat::from_rotation_y(0.3)),
            scale: Channel::Bind,
        },
        Track {
            joint: "arm".into(),
            translation: Channel::Bind,
            rotation: Channel::Animated(3),
            scale: Channel::Animated(6),
        },
        Track {
            joint: "tail".into(),
            translation: Channel::Animated(9),
            rotation: Channel::Bind,
            scale: Channel::Bind,
        },
    ]
}

/// A compressed clip built by hand over `tracks`: 5 keys in segments of 2, bit widths cycling
/// through `bits`, pseudo-random quantized values and rotation indices.
fn compressed_with(tracks: Vec<Track>, looping: bool, additive: bool, bits: &[u8]) -> Clip {
    compressed_layout(tracks, looping, additive, bits, true)
}

/// [`compressed_with`]; with `shared` false every key stores every rotation index (the layout of
/// files before 1.4) instead of storing a segment's shared index once.
fn compressed_layout(
    tracks: Vec<Track>,
    looping: bool,
    additive: bool,
    bits: &[u8],
    shared: bool,
) -> Clip {
    let starts = rotation_starts(&tracks).unwrap();
    let keys = 5;
    let comps = starts.len();
    let rotations = starts.iter().filter(|&&r| r).count();
    let segs: Vec<SegmentComponent> = (0..3 * comps)
        .map(|i| SegmentComponent {
            bits: bits[i % bits.len()],
            min: (i * 13 % 40) as u8,
            extent: 200,
        })
        .collect();
    let mut x = 0x9e37_79b9u32;
    let mut q = Vec::new();
    for k in 0..keys {
        for c in 0..comps {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            let bits = segs[(k / 2) * comps + c].bits;
            q.push(if bits == 0 { 0 } else { x % (1 << bits) });
        }
    }
    // Even rotations keep one index through each segment (stored once per segment), odd ones
    // change it from key to key (stored in every key).
    let index: Vec<u8> = (0..keys * rotations)
        .map(|i| {
            let (k, r) = (i / rotations.max(1), i % rotations.max(1));
            if r % 2 == 0 {
                ((k / 2 + r + 1) % 4) as u8
            } else {
                [0u8, 3, 1, 2, 3][i % 5]
            }
        })
        .collect();
    let shared = if shared {
        crate::compressed::shared_indices(keys, 2, rotations, &index)
    } else {
        Vec::new()
    };
    let data = crate::compressed::pack(keys, 2, &segs, &shared, &starts, &q, &index);
    let mut ranges = vec![[-0.5f32, 1.0]; comps];
    if !starts.first().copied().unwrap_or(true) {
        ranges[0] = [-3.0, 7.5];
    }
    Clip::from_quantized(
        "c".into(),
        if looping { 1.25 } else { 1.0 },
        4.0,
        looping,
        additive,
        vec![0.0, 0.25, 0.5, 0.75, 1.0],
        tracks,
        QuantizedParts {
            segment_len: 2,
            ranges,
            segments: segs,
            rotation_index: shared,
            data,
        },
    )
    .unwrap()
}

#[test]
fn work_lists_and_key_cache_match_the_reference_bit_for_bit() {
    let sk = skeleton();
    let mut clips = vec![walk(false), walk(true)];
    // Both joints animate translation and rotation (one block loads by transposition), in either
    // track order, so that each joint's run ends the frame once; and with scale too.
    for names in [["root", "arm"], ["arm", "root"]] {
        for with_scale in [false, true] {
            let times = vec![0.0, 0.3, 0.45, 1.0];
            let tracks = names
                .iter()
                .enumerate()
                .map(|(i, n)| {
                    let f = i as f32 + 1.0;
                    let scale = if with_scale {
                        Curve::new(
                            times.clone(),
                            times.iter().map(|&t| Vec3::splat(1.0 + t * f)).collect(),
                        )
                    } else {
                        Curve::default()
                    };
                    TrackCurves {
                        joint: (*n).into(),
                        translation: Curve::new(
                            times.clone(),
                            times.iter().map(|&t| Vec3::new(t, -f * t, 2.0)).collect(),
                        ),
                        rotation: Curve::new(
                            times.clone(),
                            times
                                .iter()
                                .map(|&t| Quat::from_rotation_y(t * f * 2.0))
                                .collect(),
                        ),
                        scale,
                    }
                })
                .collect();
            clips.push(Clip::from_curves("uniform", 1.0, 4.0, true, false, tracks).unwrap());
        }
    }
    for (l, a) in [(false, false), (true, false), (false, true)] {
        let c = compressed(l, a);
        clips.push(c.to_plain());
        clips.push(c);
    }
    // Uniform channels (whole blocks by transposition); the last with channels too wide for
    // one 8-byte read.
    for (scale, bits) in [
        (false, &[0u8, 3, 7, 12, 16][..]),
        (true, &[5, 9, 14][..]),
        (true, &[24, 23, 24, 1][..]),
    ] {
        let c = compressed_uniform(scale, bits);
        clips.push(c.to_plain());
        clips.push(c);
    }
    // Forward at 60 Hz past the end, keys exactly, backwards, jumps and negative times.
    let mut times: Vec<f32> = (0..100).map(|i| i as f32 / 60.0).collect();
    times.extend([
        0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 0.9, 0.1, -0.3, 2.6, 0.5, 0.5, 7.0,
    ]);
    times.extend((0..40).map(|i| 1.5 - i as f32 / 30.0));
    for clip in &clips {
        let b = ClipBinding::new(clip, &sk);
        let mut sampler = Sampler::new();
        for &t in &times {
            let marker = Transform::from_translation(Vec3::splat(9.0));
            let mut got = vec![marker; sk.len()];
            let mut want = vec![marker; sk.len()];
            sampler.sample(clip, &b, &sk, t, &mut got).unwrap();
            reference(clip, &b, &sk, t, &mut want);
            assert_eq!(bits(&got), bits(&want), "{} at {t}", clip.name());
        }
    }
    // At a key time the stored value comes back exactly (compressed: the decoded key, normalised).
    let c = compressed(false, false);
    let q = c.quantized.as_deref().unwrap();
    let mut out = vec![Transform::IDENTITY; sk.len()];
    Sampler::new()
        .sample(&c, &ClipBinding::new(&c, &sk), &sk, 0.5, &mut out)
        .unwrap();
    assert_eq!(out[0].translation, q.key(2).vec3(0));
    assert_eq!(out[1].rotation, q.key(2).quat(3));
    assert_eq!(out[1].scale, q.key(2).vec3(6));
}

#[test]
fn compressed_keys_decode_to_the_same_bits_four_lanes_at_a_time_on_every_instruction_set() {
    // Ten joints in a chain (blocks of four: full, full, half), nine of them driven; one without
    // an animated rotation and two with scale, so blocks have full, partial and mixed lanes.
    let joints = (0..10)
        .map(|i| JointDesc {
            name: format!("j{i}"),
            parent: (i > 0).then(|| format!("j{}", i - 1)),
            bind_local: Transform::from_translation(Vec3::new(0.0, 1.0, i as f32 * 0.1)),
            inverse_bind: None,
        })
        .collect();
    let sk = Skeleton::from_unordered(joints).unwrap().0;
    let mut next = 0u32;
    let mut take = || {
        next += 3;
        next - 3
    };
    let tracks: Vec<Track> = (0..9)
        .map(|i| Track {
            joint: format!("j{i}"),
            translation: Channel::Animated(take()),
            rotation: if i == 5 {
                Channel::Bind
            } else {
                Channel::Animated(take())
            },
            scale: if i == 2 || i == 7 {
                Channel::Animated(take())
            } else {
                Channel::Bind
            },
        })
        .collect();
    // Narrow widths (one 8-byte read per lane) and, in some segments, channels too wide for one.
    let mut one_load_seen = [false; 2];
    for widths in [&[0u8, 3, 7, 12, 16, 1][..], &[24, 5, 23, 24, 9, 24, 2][..]] {
        let clip = compressed_with(tracks.clone(), true, false, widths);
        let b = ClipBinding::new(&clip, &sk);
        assert_eq!(
            b.decode.iter().map(|d| d.lanes.count_ones()).sum::<u32>(),
            9 + 8 + 2
        );
        let (mut fast, mut portable) = (Sampler::new(), Sampler::new());
        for i in 0..90 {
            let t = i as f32 / 60.0;
            let marker = Transform::from_translation(Vec3::splat(9.0));
            let mut want = vec![marker; sk.len()];
            reference(&clip, &b, &sk, t, &mut want);
            let mut got = vec![marker; sk.len()];
            fast.sample(&clip, &b, &sk, t, &mut got).unwrap();
            assert_eq!(bits(&got), bits(&want), "{t}");
            let mut got = vec![marker; sk.len()];
            crate::cpu::baseline(|| portable.sample(&clip, &b, &sk, t, &mut got)).unwrap();
            assert_eq!(bits(&got), bits(&want), "portable {t}");
            for table in &fast.cache.tables {
                one_load_seen[usize::from(table.one_load)] = true;
            }
        }
    }
    assert_eq!(one_load_seen, [true, true]);
}

#[test]
fn a_restricted_binding_decodes_only_its_channels_and_samples_the_same_values() {
    let sk = skeleton();
    for c in [
        compressed(false, false),
        compressed(true, false),
        compressed(false, true),
    ] {
        let full = ClipBinding::new(&c, &sk);
        for keep in [0u16, 1] {
            let part = full.restricted(|j| j == keep);
            let lanes =
                |b: &ClipBinding| -> u32 { b.decode.iter().map(|d| d.lanes.count_ones()).sum() };
            assert!(lanes(&part) < lanes(&full));
            let (mut a, mut b) = (Sampler::new(), Sampler::new());
            for i in 0..40 {
                let t = i as f32 * 0.037;
                let marker = Transform::from_translation(Vec3::splat(9.0));
                let mut want = vec![marker; sk.len()];
                let mut got = vec![marker; sk.len()];
                a.sample(&c, &full, &sk, t, &mut want).unwrap();
                b.sample(&c, &part, &sk, t, &mut got).unwrap();
                let j = keep as usize;
                assert_eq!(bits(&got[j..j + 1]), bits(&want[j..j + 1]), "{t}");
                // The other joint is not written.
                assert_eq!(got[1 - j], marker);
            }
        }
    }
}

#[test]
fn key_cache_decodes_only_when_the_cursor_passes_a_key() {
    let c = compressed(false, false);
    let sk = skeleton();
    let b = ClipBinding::new(&c, &sk);
    let mut out = vec![Transform::IDENTITY; sk.len()];
    let mut s = Sampler::new();
    s.sample(&c, &b, &sk, 0.1, &mut out).unwrap();
    assert_eq!(s.cache.keys, [0, 1]);
    s.sample(&c, &b, &sk, 0.3, &mut out).unwrap();
    // Key 1 stays in its slot; key 2 replaces key 0.
    assert_eq!(s.cache.keys, [2, 1]);
    assert_eq!(s.cache.owner, Some((c.id.0, b.id.0)));
    // Another clip (same layout, new payload) invalidates the cache.
    let other = compressed(false, false);
    let ob = ClipBinding::new(&other, &sk);
    s.sample(&other, &ob, &sk, 0.3, &mut out).unwrap();
    assert_eq!(s.cache.owner, Some((other.id.0, ob.id.0)));
    assert_ne!(other.id.0, c.id.0);
    assert_eq!(s.cache.keys, [1, 2]);
    // So does another binding of the same clip (a restricted one has its own plan).
    let half = b.restricted(|j| j == 0);
    s.sample(&c, &half, &sk, 0.3, &mut out).unwrap();
    assert_eq!(s.cache.owner, Some((c.id.0, half.id.0)));
}

#[test]
fn a_segment_shared_rotation_index_decodes_as_the_same_index_stored_per_key() {
    // Same integers and indices, two layouts: every key decodes to the same bits, and the shared
    // layout is two bits per key shorter for each rotation that keeps its index in a segment.
    let tracks = || {
        (0..5)
            .map(|i| Track {
                joint: format!("j{i}"),
                translation: Channel::Bind,
                rotation: Channel::Animated(3 * i),
                scale: Channel::Bind,
            })
            .collect::<Vec<_>>()
    };
    let bits = [0, 5, 9, 16];
    let shared = compressed_layout(tracks(), true, false, &bits, true);
    let per_key = compressed_layout(tracks(), true, false, &bits, false);
    let (a, b) = (shared.to_plain(), per_key.to_plain());
    assert_eq!(a.times(), b.times());
    for t in [0.0, 0.1, 0.25, 0.6, 0.99] {
        let sk = Skeleton::from_unordered(
            (0..5)
                .map(|i| crate::JointDesc {
                    name: format!("j{i}"),
                    parent: None,
                    bind_local: Transform::IDENTITY,
                    inverse_bind: None,
                })
                .collect(),
        )
        .unwrap()
        .0;
        let pose = |c: &Clip| {
            let binding = ClipBinding::new(c, &sk);
            let mut out = vec![Transform::IDENTITY; sk.len()];
            Sampler::new()
                .sample(c, &binding, &sk, t, &mut out)
                .unwrap();
            out.iter()
                .map(|x| x.rotation.to_array().map(f32::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(pose(&shared), pose(&per_key), "t = {t}");
    }
    let (ps, pk) = (
        shared.quantized_parts().unwrap(),
        per_key.quantized_parts().unwrap(),
    );
    // 5 keys in segments of 2: 3 segments; rotations 0, 2, 4 share their index in every segment.
    assert_eq!(
        ps.rotation_index
            .iter()
            .enumerate()
            .filter(|(i, &x)| i % 5 % 2 == 0 && x <= 3)
            .count(),
        9
    );
    assert!(pk.rotation_index.is_empty());
    assert!(
        ps.data.len() < pk.data.len(),
        "{} {}",
        ps.data.len(),
        pk.data.len()
    );
}

#[test]
fn layer_blocks_hold_the_driven_joints_with_the_sample_layer_bits() {
    // Six joints over two blocks; the clip drives joints 0, 2 and 5 (the last block partly).
    let joints: Vec<JointDesc> = (0..6)
        .map(|j| JointDesc {
            name: format!("j{j}"),
            parent: (j > 0).then(|| format!("j{}", j - 1)),
            bind_local: Transform::from_translation(Vec3::new(j as f32, 1.0, 0.0)),
            inverse_bind: None,
        })
        .collect();
    let six = Skeleton::from_unordered(joints).unwrap().0;
    let times = vec![0.0, 0.4, 1.0];
    let tracks = [0usize, 2, 5]
        .iter()
        .map(|&j| {
            let f = j as f32 + 1.0;
            TrackCurves {
                joint: format!("j{j}"),
                translation: Curve::new(
                    times.clone(),
                    times.iter().map(|&t| Vec3::new(t * f, -t, 0.5)).collect(),
                ),
                rotation: Curve::new(
                    times.clone(),
                    times
                        .iter()
                        .map(|&t| Quat::from_rotation_x(t * f) * Quat::from_rotation_z(0.3 * t))
                        .collect(),
                ),
                ..Default::default()
            }
        })
        .collect();
    let plain = Clip::from_curves("six", 1.0, 30.0, true, false, tracks).unwrap();
    let cases = [
        (plain, six.clone()),
        (compressed(true, false), skeleton()),
        (compressed(false, false), skeleton()),
    ];
    for (clip, sk) in cases {
        let binding = ClipBinding::new(&clip, &sk);
        let (mut a, mut b) = (Sampler::new(), Sampler::new());
        let mut blocks = crate::PoseBlocks::new(sk.len());
        for t in [0.0, 0.1, 0.4, 0.55, 0.99, 1.3] {
            let mut want = sk.bind_local().to_vec();
            a.sample_layer(&clip, &binding, &sk, t, &mut want).unwrap();
            b.sample_layer_blocks(&clip, &binding, t, &mut blocks)
                .unwrap();
            let held: Vec<crate::JointIndex> = (0..sk.len() as crate::JointIndex)
                .filter(|&j| blocks.holds(j as usize))
                .collect();
            assert_eq!(held, binding.driven(), "{} at {t}", clip.name());
            let mut got = sk.bind_local().to_vec();
            assert!(blocks.write_transforms(&mut got));
            assert_eq!(bits(&got), bits(&want), "{} at {t}", clip.name());
        }
        let mut wrong = crate::PoseBlocks::new(sk.len() + 1);
        assert!(b
            .sample_layer_blocks(&clip, &binding, 0.0, &mut wrong)
            .is_err());
    }
}
