//! Unit tests of key reduction against the way it was measured before, and of the channel
//! simplification's shortcut (a file apart from `tests.rs`, whose helpers it uses).

#![allow(clippy::unwrap_used)]
use super::metric::{point_error, Rig};
use super::reduce::{greedy_keys, reduce_keys, Replacement, WChan, Work};
use super::tests::{chain, swing_moving};
use sinew_core::clip::nlerp;
use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Clip, Transform};

/// [`reduce_keys`] as it was written before it stopped at the first joint over the budget:
/// every joint's interpolated pose, its error points, then the errors.
fn reduce_keys_whole_poses(
    work: &Work,
    like: &Clip,
    rig: &Rig,
    src: &[Vec<[Vec3; 3]>],
    origins: &[Vec3],
    budget: f32,
) -> Vec<usize> {
    let n = work.times.len();
    let plain = work.plain(like).unwrap();
    let poses = rig.poses(&plain, &work.times);
    let (mut m, mut pts) = (Vec::new(), Vec::new());
    let mut lerped = poses[0].clone();
    let ok = |a: usize, b: usize| -> bool {
        let (ta, tb) = (work.times[a], work.times[b]);
        for (k, src_k) in src.iter().enumerate().take(b).skip(a + 1) {
            let x = (work.times[k] - ta) / (tb - ta);
            for (j, out) in lerped.iter_mut().enumerate() {
                let (p, q) = (poses[a][j], poses[b][j]);
                *out = Transform {
                    translation: p.translation.lerp(q.translation, x),
                    rotation: nlerp(p.rotation, q.rotation, x),
                    scale: p.scale.lerp(q.scale, x),
                };
            }
            rig.points_of(&lerped, rig.origins_at(origins, k), &mut m, &mut pts);
            if point_error(src_k, &pts).any(|e| e > budget) {
                return false;
            }
        }
        true
    };
    greedy_keys(n, ok)
}

#[test]
fn stopping_at_the_first_joint_over_the_budget_keeps_the_same_keys() {
    // Chains of 3 and 7 joints, moving and not, over budgets from a few ulps of motion to
    // more than the motion: the same kept keys as measuring every joint first, and budgets
    // where few and where most keys are kept, so the comparison can tell.
    let mut kept_counts = Vec::new();
    for (joints, moving) in [(3, false), (7, true)] {
        let skeleton = chain(joints, 0.4);
        let source = swing_moving(&skeleton, 90, moving).to_plain();
        let rig = Rig::new(&source, Some(&skeleton), 0.1).unwrap();
        let poses = rig.poses(&source, source.times());
        let (src, origins) = rig.source_points(&poses);
        let work = Work::from_plain(&source);
        for budget in [1e-6, 1e-4, 1e-3, 1e-2, 0.1] {
            let kept = reduce_keys(&work, &source, &rig, &src, &origins, None, budget);
            assert_eq!(
                kept,
                reduce_keys_whole_poses(&work, &source, &rig, &src, &origins, budget),
                "{joints} joints, budget {budget}"
            );
            kept_counts.push(kept.len());
        }
    }
    assert!(kept_counts.iter().any(|&k| k <= 10), "{kept_counts:?}");
    assert!(kept_counts.iter().any(|&k| k >= 60), "{kept_counts:?}");
}

#[test]
fn a_channel_replaced_in_the_pose_is_what_the_sampler_gives_for_the_changed_track() {
    // The channel simplification tries a track with one channel made constant (or the bind
    // value) by replacing that channel in the poses it holds, instead of sampling the changed
    // track. Every channel of every track of a chain keyed in translation, rotation and scale,
    // replaced by a constant and by the bind value: the same poses as the runtime sampler's for
    // the changed clip, bit for bit, at the key times and between them.
    let skeleton = chain(4, 0.4);
    let source = swing_moving(&skeleton, 12, true).to_plain();
    let rig = Rig::new(&source, Some(&skeleton), 0.1).unwrap();
    let mut work = Work::from_plain(&source);
    for (i, t) in work.tracks.iter_mut().enumerate() {
        let s = |k: usize| Vec3::splat(1.0 + 0.05 * (k as f32 * 0.7 + i as f32).sin());
        t.s = WChan::Keys((0..12).map(s).collect());
        if i == 2 {
            t.t = WChan::Keys(
                (0..12)
                    .map(|k| Vec3::new(0.1, 0.4, 0.01 * k as f32))
                    .collect(),
            );
        }
    }
    let mut times: Vec<f32> = work.times.clone();
    times.extend(work.times.windows(2).map(|w| 0.37 * w[0] + 0.63 * w[1]));
    let bits = |t: Transform| {
        let (a, b, c) = (t.translation, t.rotation, t.scale);
        [a.x, a.y, a.z, b.x, b.y, b.z, b.w, c.x, c.y, c.z].map(f32::to_bits)
    };
    let before = rig.poses(&work.plain(&source).unwrap(), &times);
    let mut changed = 0;
    for i in 0..work.tracks.len() {
        let j = usize::from(skeleton.find(&work.tracks[i].joint).unwrap());
        let bind = skeleton.bind_local()[j];
        for ch in 0..3 {
            for constant in [false, true] {
                let mut track = work.tracks[i].clone();
                match (ch, constant) {
                    (0, false) => track.t = WChan::Bind,
                    (0, true) => track.t = WChan::Constant(Vec3::new(0.2, 0.3, -0.1)),
                    (1, false) => track.r = WChan::Bind,
                    (1, true) => {
                        track.r = WChan::Constant(
                            Quat::from_rotation_z(0.3) * Quat::from_rotation_x(0.2),
                        );
                    }
                    (_, false) => track.s = WChan::Bind,
                    (_, true) => track.s = WChan::Constant(Vec3::new(1.1, 0.9, 1.0)),
                }
                let value = Replacement::of(ch, &track, bind).unwrap();
                let mut other = work.clone();
                other.tracks[i] = track;
                let after = rig.poses(&other.plain(&source).unwrap(), &times);
                for k in 0..times.len() {
                    let replaced = value.applied(before[k][j]);
                    assert_eq!(
                        bits(replaced),
                        bits(after[k][j]),
                        "track {i}, channel {ch}, time {k}"
                    );
                    changed += usize::from(bits(replaced) != bits(before[k][j]));
                }
            }
        }
    }
    // The replacements changed the poses (the comparison can tell).
    assert!(changed > 500, "{changed}");
}
