//! Unit tests of clip compression.

#![allow(clippy::unwrap_used)]
use super::eval::*;
use super::frames::thinned;
use super::metric::*;
use super::options::*;
use super::quantize::*;
use super::reduce::*;
use super::refine::descend;
use super::search::*;
use sinew_core::compressed::smallest_three;
use sinew_core::format::clip_record_size;
use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Clip, Skeleton, Transform};

use sinew_core::{Curve, JointDesc, TrackCurves};

/// The first widths of `layout` from the peers' tolerance, checked (with no probes).
pub(super) fn first_widths(ctx: &Ctx, layout: &Layout, work: &Work, compensate: bool) -> Vec<u8> {
    first_state(
        ctx,
        layout,
        work,
        0.001,
        compensate,
        true,
        &mut [None; PROBES],
    )
    .unwrap()
    .1
}

/// A chain of `n` joints, `bone` units apart along y.
pub(super) fn chain(n: usize, bone: f32) -> Skeleton {
    let joints = (0..n)
        .map(|i| JointDesc {
            name: format!("j{i}"),
            parent: i.checked_sub(1).map(|p| format!("j{p}")),
            bind_local: Transform::from_translation(Vec3::Y * if i == 0 { 0.0 } else { bone }),
            inverse_bind: None,
        })
        .collect();
    Skeleton::from_unordered(joints).unwrap().0
}

/// Tracks for the joints of `skeleton` from the `first` on, each swinging (by up to `amplitude`
/// rad) about a different axis at `times`; joint `path.0` also translating along `path.1`.
pub(super) fn swinging_tracks(
    skeleton: &Skeleton,
    times: &[f32],
    first: usize,
    amplitude: f32,
    path: Option<(usize, &dyn Fn(f32) -> Vec3)>,
) -> Vec<TrackCurves> {
    let times = times.to_vec();
    skeleton
        .names()
        .iter()
        .enumerate()
        .skip(first)
        .map(|(j, name)| {
            let axis = Vec3::new(1.0, j as f32 * 0.37, 0.5 - j as f32 * 0.11).normalize();
            let rotation = times
                .iter()
                .map(|t| {
                    Quat::from_axis_angle(axis, amplitude * (t * (2.0 + j as f32 * 0.7)).sin())
                })
                .collect();
            let translation = match path {
                Some((moving, path)) if moving == j => {
                    Curve::new(times.clone(), times.iter().map(|&t| path(t)).collect())
                }
                _ => Curve::default(),
            };
            TrackCurves {
                joint: name.clone(),
                rotation: Curve::new(times.clone(), rotation),
                translation,
                ..Default::default()
            }
        })
        .collect()
}

/// Every joint of `skeleton` swinging about a different axis, `keys` keys at 30 Hz.
fn swing(skeleton: &Skeleton, keys: usize) -> Clip {
    swing_moving(skeleton, keys, false)
}

/// [`swing`], with the root also moving (`moving`).
pub(super) fn swing_moving(skeleton: &Skeleton, keys: usize, moving: bool) -> Clip {
    let times: Vec<f32> = (0..keys).map(|k| k as f32 / 30.0).collect();
    let path = |t: f32| Vec3::new(t.sin(), 0.1 * t, (2.0 * t).cos());
    let tracks = swinging_tracks(skeleton, &times, 0, 0.6, moving.then_some((0, &path)));
    Clip::from_curves("swing", times[keys - 1], 30.0, false, false, tracks).unwrap()
}

fn compressed(clip: &Clip, skeleton: &Skeleton, tolerance: f32, compensate: bool) -> Clip {
    let source = clip.to_plain();
    let rig = Rig::new(&source, Some(skeleton), 0.1).unwrap();
    let mut work = Work::from_plain(&source);
    let options = CompressOptions {
        tolerance: Some(tolerance),
        error_distance: Some(0.1),
        key_reduction: true,
        effort: Effort::Default,
    };
    compress_work(
        &mut work, &source, None, &rig, tolerance, true, &options, compensate, false,
    )
    .unwrap()
    .1
}

#[test]
fn chain_compensation_keeps_the_tolerance_and_saves_bits_on_a_long_chain() {
    let skeleton = chain(8, 0.3);
    let clip = swing(&skeleton, 61);
    let tolerance = 0.001;
    let with = compressed(&clip, &skeleton, tolerance, true);
    let without = compressed(&clip, &skeleton, tolerance, false);
    for c in [&with, &without] {
        assert!(c.is_compressed());
        let worst = measure(&clip, c, Some(&skeleton), 0.1)
            .into_iter()
            .fold(0.0f32, f32::max);
        assert!(worst <= tolerance, "error {worst} above {tolerance}");
    }
    let (a, b) = (clip_record_size(&with), clip_record_size(&without));
    assert!(a < b, "compensated {a} B, uncompensated {b} B");
}

#[test]
fn mirrored_and_stretched_joints_stay_within_the_tolerance() {
    // Chain compensation assumes model rotations are products of local rotations; a mirrored
    // or non-uniformly scaled joint breaks that, and the clip must still compress correctly.
    for scale in [Vec3::new(-1.0, 1.0, 1.0), Vec3::new(1.0, 2.5, 0.7)] {
        let joints = (0..6)
            .map(|i: usize| JointDesc {
                name: format!("j{i}"),
                parent: i.checked_sub(1).map(|p| format!("j{p}")),
                bind_local: Transform {
                    translation: Vec3::Y * if i == 0 { 0.0 } else { 0.3 },
                    rotation: Quat::IDENTITY,
                    scale: if i == 2 { scale } else { Vec3::ONE },
                },
                inverse_bind: None,
            })
            .collect();
        let skeleton = Skeleton::from_unordered(joints).unwrap().0;
        let clip = swing(&skeleton, 45);
        let (c, r) = compress_clip(&clip, Some(&skeleton), &CompressOptions::peers());
        assert!(c.is_compressed(), "{scale}: {r:?}");
        let worst = measure(&clip, &c, Some(&skeleton), 0.1)
            .into_iter()
            .fold(0.0f32, f32::max);
        assert!(worst <= 0.001, "{scale}: error {worst}");
        assert!(r.compressed_bytes < r.plain_bytes, "{scale}: {r:?}");
    }
}

#[test]
fn incremental_state_matches_a_fresh_evaluation() {
    // After the descent (thousands of tentative changes and undos), the kept state must be what
    // quantizing from scratch with the final bit widths gives, bit for bit.
    let (source, rig) = swinging_chain();
    let work = Work::from_plain(&source);
    let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
    for compensate in [true, false] {
        let layout = Layout::new(&work, &rig, 16, compensate);
        let bits = first_widths(&ctx, &layout, &work, compensate);
        let mut e = Eval::new(&ctx, &layout, &work, bits.clone(), compensate);
        descend(&mut e, true, &THRESHOLDS, false);
        assert!(
            e.bits.iter().zip(&bits).any(|(a, b)| a < b),
            "nothing descended"
        );
        let fresh = Eval::new(&ctx, &layout, &work, e.bits.clone(), compensate);
        assert_eq!(e.qi, fresh.qi);
        assert!(e.within() && fresh.within());
        assert_eq!(e.model.len(), fresh.model.len());
        for (a, b) in e.model.iter().zip(&fresh.model) {
            assert!(a.abs_diff_eq(*b, 0.0), "{a:?} != {b:?}");
        }
    }
}

#[test]
fn rotations_keep_their_dropped_component_where_two_components_trade_places() {
    // About an axis near x, half angle from 36 to 56 degrees: x overtakes w as the largest
    // component near 46 degrees, which moves every stored component to another slot.
    let axis = Vec3::new(1.0, 0.0, 0.3).normalize();
    let v: Vec<Quat> = (0..=40)
        .map(|d| Quat::from_axis_angle(axis, (72.0 + d as f32).to_radians()))
        .collect();
    let split = split_rotations(&v);
    assert!(split.windows(2).all(|p| p[0].0 == p[1].0), "index changes");
    for (q, (i, c)) in v.iter().zip(&split) {
        assert!(q.to_array()[usize::from(*i)].abs() >= MIN_DROPPED);
        let back = raw_rotation(*i, *c).normalize();
        assert!(back.dot(*q).abs() > 0.999_999, "{q} {back}");
    }
    let range = |s: &[(u8, [f32; 3])]| {
        (0..3)
            .map(|a| {
                let lo = s.iter().map(|x| x.1[a]).fold(f32::MAX, f32::min);
                let hi = s.iter().map(|x| x.1[a]).fold(f32::MIN, f32::max);
                hi - lo
            })
            .fold(0.0f32, f32::max)
    };
    let largest: Vec<(u8, [f32; 3])> = v.iter().map(|q| smallest_three(*q)).collect();
    // Largest-per-key: the first slot holds x (about 0.68) before the switch and y (0) after.
    assert!(largest.windows(2).any(|p| p[0].0 != p[1].0));
    assert!(range(&split) < 0.5 * range(&largest));
}

/// `f` run in a pool of `threads` threads.
pub(super) fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

/// `clip` compressed with `options` on pools of 1, 2 and 3 threads.
fn on_1_2_3_threads(
    clip: &Clip,
    skeleton: &Skeleton,
    options: &CompressOptions,
) -> Vec<(Clip, ClipCompressionReport)> {
    [1, 2, 3]
        .into_iter()
        .map(|threads| on_threads(threads, || compress_clip(clip, Some(skeleton), options)))
        .collect()
}

#[test]
fn the_same_clip_compresses_to_the_same_bytes_at_any_thread_count_and_effort() {
    // Layouts, key reductions, first-width rungs and refinements run in parallel; the result
    // must not depend on how many threads there are.
    // 8 joints x 130 keys: above PARALLEL_VOLUME, so the parallel paths run.
    let skeleton = chain(8, 0.3);
    let clip = swing(&skeleton, 130);
    assert!(clip.times().len() * skeleton.len() >= PARALLEL_VOLUME);
    for effort in [Effort::Fast, Effort::Default, Effort::Max] {
        let options = CompressOptions {
            effort,
            ..CompressOptions::peers()
        };
        let runs = on_1_2_3_threads(&clip, &skeleton, &options);
        assert!(runs[0].0.is_compressed(), "{effort:?}");
        assert!(runs[0].1.max_error <= 0.001, "{effort:?}: {:?}", runs[0].1);
        for r in &runs[1..] {
            assert_eq!(r.0, runs[0].0, "{effort:?}");
            assert_eq!(r.1, runs[0].1, "{effort:?}");
        }
    }
}

#[test]
fn max_effort_is_never_larger_than_the_default() {
    let skeleton = chain(5, 0.4);
    for keys in [20, 45, 90] {
        let clip = swing(&skeleton, keys);
        let size = |effort| {
            let options = CompressOptions {
                effort,
                ..CompressOptions::peers()
            };
            compress_clip(&clip, Some(&skeleton), &options)
                .1
                .compressed_bytes
        };
        let (fast, default, max) = (size(Effort::Fast), size(Effort::Default), size(Effort::Max));
        assert!(max <= default, "{keys} keys: max {max} > default {default}");
        assert!(fast > 0 && default > 0, "{keys} keys");
    }
}

#[test]
fn constant_channels_at_the_bind_value_are_stored_as_bind() {
    // Sources often key every joint, most at its rest value: such a channel arrives constant and
    // costs 12 or 16 bytes as a constant, nothing as a bind channel. One that differs from the
    // bind value by more than the tolerance stays constant.
    let skeleton = chain(4, 0.3);
    let swinging = swing(&skeleton, 31);
    let times = swinging.times().to_vec();
    let bent = Quat::from_rotation_z(0.2);
    let mut tracks: Vec<TrackCurves> = (0..2)
        .map(|j| TrackCurves {
            joint: format!("j{j}"),
            rotation: Curve::new(
                times.clone(),
                (0..times.len())
                    .map(|k| Quat::from_rotation_x(0.5 * (k as f32 * 0.2 + j as f32).sin()))
                    .collect(),
            ),
            ..Default::default()
        })
        .collect();
    let hold = |v: Vec3| Curve::new(times.clone(), vec![v; times.len()]);
    tracks.push(TrackCurves {
        joint: "j2".into(),
        translation: hold(Vec3::Y * 0.3),
        rotation: Curve::new(times.clone(), vec![Quat::IDENTITY; times.len()]),
        scale: hold(Vec3::ONE),
    });
    tracks.push(TrackCurves {
        joint: "j3".into(),
        translation: hold(Vec3::Y * 0.3),
        rotation: Curve::new(times.clone(), vec![bent; times.len()]),
        scale: hold(Vec3::ONE),
    });
    let clip =
        Clip::from_curves("hold", times[times.len() - 1], 30.0, false, false, tracks).unwrap();
    let source = clip.to_plain();
    assert!(matches!(
        source.tracks()[2].translation,
        sinew_core::Channel::Constant(_)
    ));
    let (c, r) = compress_clip(&clip, Some(&skeleton), &CompressOptions::peers());
    assert!(c.is_compressed(), "{r:?}");
    assert!(r.max_error <= 0.001, "{r:?}");
    use sinew_core::Channel::{Bind, Constant};
    let t = &c.tracks()[2];
    assert!(matches!(
        (t.translation, t.rotation, t.scale),
        (Bind, Bind, Bind)
    ));
    let t = &c.tracks()[3];
    assert!(matches!((t.translation, t.scale), (Bind, Bind)));
    match t.rotation {
        Constant(q) => assert!(q.angle_between(bent) < 1e-5, "{q}"),
        other => panic!("j3 rotation {other:?}"),
    }
    // Without a skeleton there is no bind value: the held channels stay constants.
    let (c, _) = compress_clip(&clip, None, &CompressOptions::peers());
    let t = &c.tracks()[2];
    assert!(matches!(t.translation, Constant(v) if v == Vec3::Y * 0.3));
    assert!(matches!(t.scale, Constant(v) if v == Vec3::ONE));
}

/// The refinement one try at a time, in its documented order (the even segments, then the odd
/// ones; on each, component by component, each kept try committed before the next is worked out):
/// the reference the side-by-side schedule of [`descend`] must reproduce.
fn descend_one_at_a_time(eval: &mut Eval) {
    let nc = eval.layout.comps.len();
    let segs = eval.layout.seg_count;
    let mut blocked = vec![false; nc * segs];
    let mut trial = super::trial::Trial::default();
    let mut round = 0;
    loop {
        let limit = THRESHOLDS.get(round).copied().unwrap_or(1.0);
        round += 1;
        let mut changed = false;
        for s in (0..segs).step_by(2).chain((1..segs).step_by(2)) {
            for c in 0..nc {
                let i = s * nc + c;
                if eval.bits[i] == 0 || blocked[i] {
                    continue;
                }
                trial.run(eval, s, c, eval.bits[i] - 1, limit, &[]);
                if trial.worst <= limit {
                    trial.commit(eval);
                    changed = true;
                } else {
                    blocked[i] = limit >= 1.0;
                }
            }
        }
        if !changed && round >= THRESHOLDS.len() {
            break;
        }
    }
}

/// A five-joint chain swinging over 40 keys: its source clip and rig.
fn swinging_chain() -> (Clip, Rig) {
    let skeleton = chain(5, 0.4);
    let source = swing(&skeleton, 40).to_plain();
    let rig = Rig::new(&source, Some(&skeleton), 0.1).unwrap();
    (source, rig)
}

/// A moving, swinging chain of `joints` joints with `keys` keys: its source clip and rig.
pub(super) fn moving_chain(joints: usize, keys: usize) -> (Clip, Rig) {
    let skeleton = chain(joints, 0.35);
    let source = swing_moving(&skeleton, keys, true).to_plain();
    let rig = Rig::new(&source, Some(&skeleton), 0.1).unwrap();
    (source, rig)
}

#[test]
fn a_long_clip_builds_side_by_side_the_state_and_verdict_of_one_thread() {
    // 6 joints x 3,000 keys: above the volume from which `Eval::build` quantizes keys and
    // computes times in chunks side by side (more than one block of times). On one thread it
    // builds time by time; on two and three, block by block: the same state, value for value,
    // and the same verdicts, for widths that pass, that fail early and that fail late.
    let (source, rig) = moving_chain(6, 3000);
    assert!(source.times().len() * rig.skeleton.len() >= 16 * 1024);
    let work = Work::from_plain(&source);
    let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
    let layout = Layout::new(&work, &rig, 16, true);
    let (budget, bits, _) =
        first_state(&ctx, &layout, &work, 0.001, true, true, &mut [None; PROBES]).unwrap();
    let step = std::f32::consts::SQRT_2.sqrt();
    let mut failing = bits.clone();
    // Every width of the last segment one bit down: a check that fails late.
    let nc = layout.comps.len();
    for w in &mut failing[(layout.seg_count - 1) * nc..] {
        *w = w.saturating_sub(3);
    }
    let widths = [
        bits.clone(),
        layout.first_bits(budget * step.powi(4)),
        failing,
    ];
    let build = |threads: usize, bits: &Vec<u8>, check: bool| {
        on_threads(threads, || {
            let (e, verdict) = Eval::build(
                &ctx,
                &layout,
                &work,
                bits.clone(),
                true,
                check,
                [None; PROBES],
            );
            let state = (
                e.qi.clone(),
                e.dec
                    .iter()
                    .map(|d| d.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                    .collect::<Vec<_>>(),
                e.key_rot
                    .iter()
                    .map(|q| q.to_array().map(f32::to_bits))
                    .collect::<Vec<_>>(),
                e.model
                    .iter()
                    .map(|m| m.to_cols_array().map(f32::to_bits))
                    .collect::<Vec<_>>(),
            );
            (state, verdict.is_ok(), verdict.ok())
        })
    };
    let mut verdicts = Vec::new();
    for bits in &widths {
        for check in [false, true] {
            let one = build(1, bits, check);
            for threads in [2, 3] {
                let many = build(threads, bits, check);
                assert_eq!(one.1, many.1, "verdict, {threads} threads");
                assert_eq!(
                    one.2, many.2,
                    "time of the largest error, {threads} threads"
                );
                if one.1 {
                    assert_eq!(one.0, many.0, "state, {threads} threads");
                }
            }
            if check {
                verdicts.push(one.1);
            }
        }
    }
    // Passing and failing widths both occur, so the comparison can tell.
    assert_eq!(verdicts, [true, false, false]);
}

#[test]
fn the_side_by_side_refinement_makes_the_decisions_of_one_try_at_a_time() {
    // Six joints whose root also moves, 200 keys: 13 segments of 16, so that each parity holds
    // several segments (translations and rotations, whole subtrees under compensation).
    let (source, rig) = moving_chain(6, 200);
    let work = Work::from_plain(&source);
    let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
    for compensate in [true, false] {
        let layout = Layout::new(&work, &rig, 16, compensate);
        assert_eq!(layout.seg_count, 13);
        let bits = first_widths(&ctx, &layout, &work, compensate);
        let mut want = Eval::new(&ctx, &layout, &work, bits.clone(), compensate);
        descend_one_at_a_time(&mut want);
        assert!(want.bits.iter().zip(&bits).filter(|(a, b)| a < b).count() > 20);
        let model_bits = |e: &Eval| -> Vec<u32> {
            e.model
                .iter()
                .flat_map(|m| m.to_cols_array())
                .map(f32::to_bits)
                .collect()
        };
        for par in [false, true] {
            let mut got = Eval::new(&ctx, &layout, &work, bits.clone(), compensate);
            descend(&mut got, par, &THRESHOLDS, false);
            assert_eq!(
                got.bits, want.bits,
                "compensate {compensate}, parallel {par}"
            );
            assert_eq!(got.qi, want.qi);
            assert_eq!(model_bits(&got), model_bits(&want));
        }
        // With the segments' climb first (another path: the comparison is of the climb), the
        // same on one thread (in place) and on two and three (on copies, side by side).
        let climbed = |threads: usize| {
            on_threads(threads, || {
                let mut e = Eval::new(&ctx, &layout, &work, bits.clone(), compensate);
                descend(&mut e, threads > 1, &THRESHOLDS, true);
                assert!(e.within());
                (e.bits.clone(), e.qi.clone(), model_bits(&e))
            })
        };
        let one = climbed(1);
        assert_ne!(one.0, want.bits, "compensate {compensate}");
        for threads in [2, 3] {
            assert_eq!(climbed(threads), one, "{threads} threads");
        }
    }
}

#[test]
fn tries_two_segments_apart_do_not_see_each_other() {
    // What the side-by-side refinement relies on: a kept try changes nothing that a try on a segment two or
    // more away reads, so the second try measures the same, bit for bit, before and after the
    // first is committed. Tries on neighbouring segments do see each other (so that this test
    // can tell).
    let (source, rig) = moving_chain(5, 120);
    let work = Work::from_plain(&source);
    let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
    let layout = Layout::new(&work, &rig, 16, true);
    let segs = layout.seg_count;
    let nc = layout.comps.len();
    assert_eq!(segs, 8);
    let bits = first_widths(&ctx, &layout, &work, true);
    let measure = |e: &Eval, s: usize, c: usize| -> u32 {
        let mut t = super::trial::Trial::default();
        t.run(
            e,
            s,
            c,
            e.bits[s * nc + c].saturating_sub(2),
            f32::INFINITY,
            &[],
        );
        t.worst.to_bits()
    };
    let (mut apart, mut near_differ) = (0, 0);
    // The root's translation and rotation components, and one of the last joint's rotation.
    for c1 in [0, 3, nc - 1] {
        for s1 in 0..segs {
            let mut after = Eval::new(&ctx, &layout, &work, bits.clone(), true);
            let mut t = super::trial::Trial::default();
            t.run(
                &after,
                s1,
                c1,
                after.bits[s1 * nc + c1].saturating_sub(2),
                f32::INFINITY,
                &[],
            );
            t.commit(&mut after);
            let before = Eval::new(&ctx, &layout, &work, bits.clone(), true);
            for c2 in [0, 4, nc - 2] {
                for s2 in 0..segs {
                    let (x, y) = (measure(&before, s2, c2), measure(&after, s2, c2));
                    if s1.abs_diff(s2) >= 2 {
                        assert_eq!(x, y, "try ({c1}, {s1}) then ({c2}, {s2})");
                        apart += 1;
                    } else if x != y {
                        near_differ += 1;
                    }
                }
            }
        }
    }
    // 3 x 3 component pairs x the 42 segment pairs of 8 segments that are two or more apart.
    assert_eq!(apart, 378);
    assert!(near_differ > 10, "{near_differ}");
}

#[test]
fn a_refinement_spread_over_the_threads_compresses_to_the_same_bytes_at_any_thread_count() {
    // From PARALLEL_VOLUME on, the one refined candidate's tries are spread over the threads
    // (the segments of one parity side by side): a clip just above it and a long one.
    let skeleton = chain(6, 0.3);
    for keys in [300, 3400] {
        let clip = swing_moving(&skeleton, keys, true);
        assert!(clip.times().len() * skeleton.len() >= PARALLEL_VOLUME);
        let runs = on_1_2_3_threads(&clip, &skeleton, &CompressOptions::peers());
        assert!(runs[0].0.is_compressed());
        assert!(runs[0].1.max_error <= 0.001, "{:?}", runs[0].1);
        for r in &runs[1..] {
            assert_eq!(r.0, runs[0].0, "{keys} keys");
            assert_eq!(r.1, runs[0].1, "{keys} keys");
        }
    }
}

#[test]
fn a_refinement_side_by_side_finishes_alone_when_the_other_threads_are_busy() {
    // The calling thread never waits for a helper of the refinement to start: with the pool's
    // other thread held by a job that waits for the compression to end (as another clip's or
    // mesh's work can hold it), the clip compresses on the calling thread alone, to the same
    // bytes as on one thread.
    let skeleton = chain(6, 0.3);
    let clip = swing_moving(&skeleton, 300, true);
    let options = CompressOptions::peers();
    let alone = on_1_2_3_threads(&clip, &skeleton, &options).swap_remove(0);
    let done = std::sync::atomic::AtomicBool::new(false);
    let busy = on_threads(2, || {
        rayon::scope(|scope| {
            scope.spawn(|_| {
                while !done.load(std::sync::atomic::Ordering::Acquire) {
                    std::thread::yield_now();
                }
            });
            let out = compress_clip(&clip, Some(&skeleton), &options);
            done.store(true, std::sync::atomic::Ordering::Release);
            out
        })
    });
    assert!(busy.0.is_compressed());
    assert_eq!(busy.0, alone.0);
    assert_eq!(busy.1, alone.1);
}

#[test]
fn the_times_a_try_measures_first_change_neither_its_verdict_nor_what_it_commits() {
    // Tries on every segment and on the root's, a middle joint's and the last joint's
    // components, two bits down, at an infinite cap (the worst ratio, bit for bit) and at caps
    // around it (the verdict), measured in time order and with the times measured first in
    // reverse, repeated, out of range: the same result, and a kept try commits the same state.
    let (source, rig) = moving_chain(5, 120);
    let work = Work::from_plain(&source);
    let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
    let layout = Layout::new(&work, &rig, 16, true);
    let nc = layout.comps.len();
    let bits = first_widths(&ctx, &layout, &work, true);
    let state = Eval::new(&ctx, &layout, &work, bits, true);
    let (mut kept, mut failed) = (0, 0);
    for c in [0, 3, nc / 2, nc - 1] {
        for s in 0..layout.seg_count {
            let times = state.seg_times[s].len();
            let bits = state.bits[s * nc + c].saturating_sub(2);
            let orders: [Vec<usize>; 3] = [
                Vec::new(),
                (0..times).rev().collect(),
                vec![times / 2, times + 7, times / 2, 0, times.saturating_sub(1)],
            ];
            let run = |order: &[usize], cap: f32| {
                let mut t = super::trial::Trial::default();
                t.run(&state, s, c, bits, cap, order);
                let mut after = Eval::new(&ctx, &layout, &work, state.bits.clone(), true);
                let worst = t.worst;
                if worst <= cap {
                    t.commit(&mut after);
                }
                (worst.to_bits(), after.qi, after.bits)
            };
            let (reference, ..) = run(&[], f32::INFINITY);
            let worst = f32::from_bits(reference);
            for cap in [f32::INFINITY, worst * 1.01, worst * 0.99, worst * 0.5] {
                let plain = run(&[], cap);
                if cap < worst {
                    failed += 1;
                } else {
                    kept += 1;
                }
                for order in &orders {
                    let with = run(order, cap);
                    assert_eq!(with.1, plain.1, "segment {s} component {c} cap {cap}");
                    assert_eq!(with.2, plain.2);
                    if cap >= worst {
                        assert_eq!(with.0, plain.0, "segment {s} component {c}");
                    } else {
                        assert_eq!(f32::from_bits(with.0), f32::INFINITY);
                    }
                }
            }
        }
    }
    assert!(kept > 0 && failed > 0, "{kept} kept, {failed} failed");
}

#[test]
fn a_probe_changes_no_first_width_verdict() {
    // The same checks with no probes and with every time (and some out of range) as either probe
    // or both: the same verdicts, and for passing widths the same stored integers and the same
    // time of the largest error; and the ladder reaches the same budget and widths.
    let (source, rig) = swinging_chain();
    let work = Work::from_plain(&source);
    let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
    let times = source.times().len();
    let (mut passed, mut failed) = (0, 0);
    for compensate in [true, false] {
        let layout = Layout::new(&work, &rig, 16, compensate);
        for rung in 0..12 {
            let budget = 0.0002 * std::f32::consts::SQRT_2.powi(rung);
            let build = |probe| {
                let (e, verdict) = Eval::build(
                    &ctx,
                    &layout,
                    &work,
                    layout.first_bits(budget),
                    compensate,
                    true,
                    probe,
                );
                verdict.map(|worst| (worst, e.qi))
            };
            let plain = build([None; PROBES]);
            match &plain {
                Ok(_) => passed += 1,
                Err(_) => failed += 1,
            }
            let probes = (0..=times + 3).flat_map(|p| {
                let q = (times + 3 - p).min(times / 2);
                let mut both = [None; PROBES];
                add_probe(&mut both, q);
                add_probe(&mut both, p);
                let mut last = [None; PROBES];
                last[PROBES - 1] = Some(p);
                [both, last]
            });
            for probe in probes {
                let with = build(probe);
                assert_eq!(with.is_ok(), plain.is_ok(), "rung {rung} probe {probe:?}");
                if let (Ok(a), Ok(b)) = (&with, &plain) {
                    assert_eq!(a, b);
                }
            }
        }
        let alone = first_state(
            &ctx,
            &layout,
            &work,
            0.001,
            compensate,
            true,
            &mut [None; PROBES],
        );
        let mut probe = [None; PROBES];
        add_probe(&mut probe, times / 3);
        add_probe(&mut probe, times / 2);
        let probed = first_state(&ctx, &layout, &work, 0.001, compensate, true, &mut probe);
        assert_eq!(alone, probed);
    }
    // Both verdicts occur, so the comparison can tell.
    assert!(passed > 0 && failed > 0, "{passed} passed, {failed} failed");
}

#[test]
fn the_ladder_reaches_the_rung_a_rung_by_rung_climb_reaches() {
    // first_state climbs (and descends) by galloping and bisection; a climb one rung at a time from the same
    // start (the same f32 budgets: `start` times 2^(1/4), multiplied one rung at a time) stops
    // below the first failing rung. Where passing is monotone in the budget (checked here over
    // the rungs climbed), both give the same budget and widths, from starts far below the result
    // (a long climb) to just below it, and from above it (the way down, from far above: many
    // rungs of the same widths, which the ladder measures once).
    let (source, rig) = swinging_chain();
    let work = Work::from_plain(&source);
    let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
    let step: f32 = std::f32::consts::SQRT_2.sqrt();
    let layout = Layout::new(&work, &rig, 16, true);
    let passes = |budget: f32| {
        Eval::build(
            &ctx,
            &layout,
            &work,
            layout.first_bits(budget),
            true,
            true,
            [None; PROBES],
        )
        .1
        .is_ok()
    };
    let mut climbs = Vec::new();
    let mut repeated = 0;
    for start in [
        1e-7f32, 1e-6, 1e-5, 1e-4, 5e-4, 7e-4, 0.001, 0.01, 1.0, 100.0,
    ] {
        let got = first_state(
            &ctx,
            &layout,
            &work,
            start,
            true,
            false,
            &mut [None; PROBES],
        );
        // Rung by rung.
        let mut budget = start;
        let expected = if passes(budget) {
            let mut k = 0;
            while k < 33 && passes(budget * step) {
                budget *= step;
                k += 1;
            }
            climbs.push(k);
            // Monotone above: every rung up to the top fails once one has.
            let mut b = budget * step;
            for _ in k..33 {
                assert!(!passes(b), "start {start}: passing is not monotone here");
                b *= step;
            }
            Some(budget)
        } else {
            let found = (0..80).find_map(|_| {
                let above = layout.first_bits(budget);
                budget /= step;
                repeated += usize::from(layout.first_bits(budget) == above);
                passes(budget).then_some(budget)
            });
            // Monotone below: the rungs under the first passing one pass too (the ladder
            // gallops down and bisects).
            if let Some(b) = found {
                let mut below = b;
                for _ in 0..12 {
                    below /= step;
                    assert!(passes(below), "start {start}: passing is not monotone here");
                }
            }
            found
        };
        let got_budget = got.as_ref().map(|g| g.0);
        assert_eq!(got_budget, expected, "start {start}");
        if let (Some(g), Some(b)) = (got, expected) {
            assert_eq!(g.1, layout.first_bits(b), "start {start}");
        }
    }
    // Long climbs and short ones were compared.
    assert!(climbs.iter().any(|&k| k >= 8), "{climbs:?}");
    assert!(climbs.iter().any(|&k| k <= 2), "{climbs:?}");
    // Ways down crossed rungs of repeated widths (the ones the ladder does not measure again).
    assert!(repeated >= 10, "{repeated}");
}

#[test]
fn record_size_is_the_size_of_the_encoded_record() {
    // The search ranks candidates by `Layout::record_size` without encoding them: it must be the
    // size `clip_record_size` gives the encoded clip, for any bit widths (shared and per-key
    // rotation indices, one or many segments, compact or not).
    let (source, rig) = moving_chain(7, 90);
    let work = Work::from_plain(&source);
    let mut seed = 7u32;
    let mut next = || {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        seed >> 8
    };
    let mut checked = 0;
    for compensate in [true, false] {
        // The segment lengths share one set of components (and the record's prefix size).
        let base = Components::new(&work, &rig, compensate);
        for seg in [1, 5, 16, 32, 90] {
            let layout = Layout::with_segments(&base, seg);
            for _ in 0..4 {
                let bits: Vec<u8> = (0..layout.sub.len()).map(|_| (next() % 17) as u8).collect();
                let qi: Vec<Vec<u32>> = (0..layout.comps.len())
                    .map(|c| {
                        (0..layout.keys)
                            .map(|k| {
                                let b = bits[(k / layout.seg_len) * layout.comps.len() + c];
                                next() & ((1u32 << b) - 1)
                            })
                            .collect()
                    })
                    .collect();
                let clip = layout.encode(&bits, &qi, &work, &source).unwrap();
                assert_eq!(
                    layout.record_size(&bits, &work, &source),
                    Some(clip_record_size(&clip)),
                    "segments of {seg}, compensate {compensate}"
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 40);
}

#[test]
fn a_rotation_lever_reaches_through_joints_that_do_not_compensate() {
    // j0 -> j1 (no quantized rotation: a helper like CMU's LHipJoint) -> j2 -> j3, bones of 0.3,
    // error points 0.1 from their joints. j0's orientation error is passed on by j1 to j2's
    // position (0.6 from j0) and so to its error points (0.7); j2 compensates, so nothing below it
    // is reached. With every joint compensating, the lever is one bone and the child's points.
    let skeleton = chain(4, 0.3);
    let clip = swing(&skeleton, 10);
    let rig = Rig::new(&clip.to_plain(), Some(&skeleton), 0.1).unwrap();
    let all = rig.levers(&[true, true, true, true]);
    let helper = rig.levers(&[true, false, true, true]);
    let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
    assert!(
        close(all[0], 0.4) && close(all[1], 0.4) && close(all[2], 0.4),
        "{all:?}"
    );
    assert!(
        close(all[3], 0.1),
        "a leaf's lever is its error points' distance: {all:?}"
    );
    assert!(
        close(helper[0], 0.7),
        "through the helper to j2: {helper:?}"
    );
    assert!(close(helper[1], 0.4) && close(helper[2], 0.4), "{helper:?}");
}

/// [`swing`] with `extra` slerped keys inserted in every interval, as an importer adds keys where a
/// file's own interpolation needs them.
pub(super) fn densified_swing(skeleton: &Skeleton, keys: usize, extra: usize) -> Clip {
    let coarse = swing(skeleton, keys).to_plain();
    let times = coarse.times();
    let rig = Rig::new(&coarse, Some(skeleton), 0.1).unwrap();
    let poses = rig.poses(&coarse, times);
    let mut dense_times = Vec::new();
    let mut dense: Vec<Vec<Quat>> = vec![Vec::new(); skeleton.len()];
    for k in 0..times.len() {
        let steps = if k + 1 < times.len() { extra + 1 } else { 1 };
        for i in 0..steps {
            let u = i as f32 / (extra + 1) as f32;
            let t = times[k] + u * times.get(k + 1).map_or(0.0, |n| n - times[k]);
            dense_times.push(t);
            for (j, track) in dense.iter_mut().enumerate() {
                let a = poses[k][j].rotation;
                let b = poses.get(k + 1).map_or(a, |p| p[j].rotation);
                track.push(a.slerp(b, u));
            }
        }
    }
    let tracks = skeleton
        .names()
        .iter()
        .zip(dense)
        .map(|(name, rotation)| TrackCurves {
            joint: name.clone(),
            rotation: Curve::new(dense_times.clone(), rotation),
            ..Default::default()
        })
        .collect();
    let last = *dense_times.last().unwrap();
    Clip::from_curves("dense", last, 30.0, false, false, tracks).unwrap()
}

#[test]
fn the_search_runs_on_thinned_times_and_its_result_holds_at_every_source_time() {
    let skeleton = chain(6, 0.3);
    let clip = densified_swing(&skeleton, 31, 7).to_plain();
    assert_eq!(clip.times().len(), 30 * 8 + 1);
    let rig = Rig::new(&clip, Some(&skeleton), 0.1).unwrap();
    let poses = rig.poses(&clip, clip.times());
    let (src, origins) = rig.source_points(&poses);
    // At 0.01 the slerped keys are within 1% of the tolerance of their neighbours' interpolation:
    // the thinned source keeps far fewer than four fifths of the times, all of them source times.
    let (kept, thin) = thinned(&clip, &rig, &src, &origins, None, 0.01).unwrap();
    assert_eq!(kept.len(), thin.times().len());
    assert!(
        thin.times().len() * 5 < clip.times().len() * 4,
        "{}",
        thin.times().len()
    );
    assert!(thin.times().iter().all(|t| clip.times().contains(t)));
    let options = CompressOptions {
        tolerance: Some(0.01),
        error_distance: Some(0.1),
        ..CompressOptions::default()
    };
    let (c, r) = compress_clip(&clip, Some(&skeleton), &options);
    assert!(c.is_compressed());
    // Measured at every source time, the thinned ones included.
    let worst = measure(&clip, &c, Some(&skeleton), 0.1)
        .into_iter()
        .fold(0.0f32, f32::max);
    assert!(worst <= 0.01, "error {worst}");
    assert_eq!(r.max_error, worst);
    assert!(c.times().iter().all(|t| clip.times().contains(t)));
    // At a tolerance where slerp and nlerp differ by more than 1% of it, nothing is left out.
    assert!(thinned(&clip, &rig, &src, &origins, None, 1e-7).is_none());
}
