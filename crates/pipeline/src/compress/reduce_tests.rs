//! Unit tests of key reduction against the way it was measured before (a file apart from
//! `tests.rs`, whose helpers it uses).

#![allow(clippy::unwrap_used)]
use super::metric::{point_error, Rig};
use super::reduce::{greedy_keys, reduce_keys, Work};
use super::tests::{chain, swing_moving};
use sinew_core::clip::nlerp;
use sinew_core::glam::Vec3;
use sinew_core::{Clip, Transform};

/// [`reduce_keys`] as it was written before it stopped at the first joint over the budget:
/// every joint's interpolated pose, its error points, then the errors.
fn reduce_keys_whole_poses(
    work: &Work,
    like: &Clip,
    rig: &Rig,
    src: &[Vec<[Vec3; 3]>],
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
            rig.points_of(&lerped, &mut m, &mut pts);
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
        let src = rig.all_points(&rig.poses(&source, source.times()));
        let work = Work::from_plain(&source);
        for budget in [1e-6, 1e-4, 1e-3, 1e-2, 0.1] {
            let kept = reduce_keys(&work, &source, &rig, &src, budget);
            assert_eq!(
                kept,
                reduce_keys_whole_poses(&work, &source, &rig, &src, budget),
                "{joints} joints, budget {budget}"
            );
            kept_counts.push(kept.len());
        }
    }
    assert!(kept_counts.iter().any(|&k| k <= 10), "{kept_counts:?}");
    assert!(kept_counts.iter().any(|&k| k >= 60), "{kept_counts:?}");
}
