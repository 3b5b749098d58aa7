//! Unit tests of how the encoder keeps its states: which it keeps while it searches, and the
//! local poses a checked build leaves out (a file apart from `tests.rs`, whose helpers it uses).

#![allow(clippy::unwrap_used)]
use super::eval::{Ctx, Eval, PROBES};
use super::quantize::Layout;
use super::reduce::Work;
use super::search::{estimated_candidates, first_state};
use super::tests::{moving_chain, on_threads};
use sinew_core::glam::{Affine3A, Vec3A};

#[test]
fn the_candidates_chosen_are_the_first_of_a_longer_list() {
    // estimated_candidates drops a measured state as soon as its layout is out of the `count`
    // smallest: the one candidate it returns is the first of those it returns for every layout,
    // with the same widths and stored integers.
    const TOLERANCE: f32 = 0.01;
    let (source, rig) = moving_chain(6, 90);
    let ctx = Ctx::new(&rig, &source, source.times(), TOLERANCE);
    let base = Work::from_plain(&source);
    let n = base.times.len();
    let works: Vec<Work> = [1usize, 2, 3]
        .iter()
        .map(|&every| {
            let mut w = base.clone();
            w.keep(
                &(0..n)
                    .filter(|i| i % every == 0 || *i == n - 1)
                    .collect::<Vec<_>>(),
            );
            w
        })
        .collect();
    let layouts: Vec<(usize, Layout, bool)> = (0..works.len())
        .flat_map(|wi| [8, 16, 32].map(|l| (wi, l)))
        .map(|(wi, l)| (wi, Layout::new(&works[wi], &rig, l, true), true))
        .collect();
    let pick = |count: usize| -> Vec<(usize, Vec<u8>, Vec<Vec<u32>>)> {
        estimated_candidates(
            &ctx,
            &layouts,
            &works,
            &source,
            TOLERANCE,
            true,
            false,
            (count, true),
        )
        .into_iter()
        .map(|(li, e, _)| (li, e.bits, e.qi))
        .collect()
    };
    let (one, all) = (pick(1), pick(layouts.len()));
    assert_eq!(one.len(), 1);
    // Layouts of two works (the third keeps too few keys for the tolerance), so states of
    // both works' ladders were measured, and dropped where their layouts lost.
    assert_eq!(all.len(), 6);
    assert_eq!(one[0], all[0]);
}

#[test]
fn the_local_poses_filled_in_are_those_the_model_transforms_were_computed_from() {
    // A long clip's checked build computes the model transforms alone; `fill_local` then computes
    // the local poses. Each model transform is its parent's times its local pose, bit for bit, as
    // the build multiplied them, at 1, 2 and 3 threads (time by time, and in chunks side by
    // side), with the same local poses at every thread count. A shorter clip's checked build
    // keeps the local poses it computed (time by time, or side by side from 16 Ki joint-times):
    // `fill_local` computes the same ones again.
    for (joints, keys) in [(6, 90), (6, 3000), (24, 3000)] {
        let long = joints * keys >= 64 * 1024;
        let (source, rig) = moving_chain(joints, keys);
        let work = Work::from_plain(&source);
        let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
        let layout = Layout::new(&work, &rig, 16, true);
        let (_, bits, _) =
            first_state(&ctx, &layout, &work, 0.001, true, true, &mut [None; PROBES]).unwrap();
        let locals = |threads: usize| {
            on_threads(threads, || {
                let (mut e, verdict) = Eval::build(
                    &ctx,
                    &layout,
                    &work,
                    bits.clone(),
                    true,
                    true,
                    [None; PROBES],
                );
                assert!(verdict.is_ok());
                if long {
                    assert!(e.local_aff.is_empty(), "a long clip's check keeps none");
                } else {
                    let kept = std::mem::take(&mut e.local_aff);
                    assert_eq!(kept.len(), e.model.len(), "a short clip's check keeps them");
                    e.fill_local();
                    assert_eq!(bit_patterns(&e.local_aff), bit_patterns(&kept));
                }
                e.fill_local();
                let nj = e.nj;
                assert_eq!(e.local_aff.len(), e.model.len());
                // (The anchor's model transform is about the source's anchor at that time.)
                let anchor = rig.anchors[0];
                for (i, (local, model)) in
                    e.local_aff.chunks(nj).zip(e.model.chunks(nj)).enumerate()
                {
                    for d in 0..nj {
                        let parent = e.parent(d).map_or(Affine3A::IDENTITY, |p| model[p]);
                        let mut again = parent * local[d];
                        if d == anchor {
                            again.translation -= Vec3A::from(ctx.origins[i]);
                        }
                        assert_eq!(again.to_cols_array(), model[d].to_cols_array());
                    }
                }
                bit_patterns(&e.local_aff)
            })
        };
        let one = locals(1);
        assert_eq!(one.len(), keys * joints);
        for threads in [2, 3] {
            assert_eq!(locals(threads), one, "{joints} x {keys}, {threads} threads");
        }
    }
}

/// Each transform's twelve floats as bit patterns (for comparisons bit for bit).
fn bit_patterns(transforms: &[Affine3A]) -> Vec<[u32; 12]> {
    transforms
        .iter()
        .map(|m| m.to_cols_array().map(f32::to_bits))
        .collect()
}

#[test]
fn a_state_quantized_without_its_times_stores_what_a_build_stores() {
    // `Eval::quantized` (fast's unmeasured layouts) quantizes every key and computes no time: its
    // stored integers and decoded values are a checked build's, key for key, at 1 to 3 threads
    // (6 joints x 3,000 keys: its keys in chunks side by side on two and three), and so is the
    // clip it encodes, with and without chain compensation.
    let (source, rig) = moving_chain(6, 3000);
    let work = Work::from_plain(&source);
    let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
    for compensate in [true, false] {
        let layout = Layout::new(&work, &rig, 32, compensate);
        let bits = layout.first_bits(0.0004);
        let (built, _) = on_threads(1, || {
            Eval::build(
                &ctx,
                &layout,
                &work,
                bits.clone(),
                compensate,
                true,
                [None; PROBES],
            )
        });
        let dec_bits = |e: &Eval| -> Vec<Vec<u32>> {
            e.dec
                .iter()
                .map(|d| d.iter().map(|x| x.to_bits()).collect())
                .collect()
        };
        assert!(built.qi.iter().flatten().any(|&q| q != 0));
        let clip = built.encode(&work).unwrap();
        for threads in [1, 2, 3] {
            let quantized = on_threads(threads, || {
                Eval::quantized(&ctx, &layout, &work, bits.clone(), compensate)
            });
            assert_eq!(quantized.qi, built.qi, "{threads} threads");
            assert_eq!(dec_bits(&quantized), dec_bits(&built), "{threads} threads");
            assert_eq!(quantized.encode(&work).unwrap(), clip, "{threads} threads");
        }
    }
}

#[test]
fn without_measures_a_layout_its_ladder_did_not_measure_comes_quantized_at_the_budget() {
    // Two layouts of one work, both chosen: the first is measured by the work's ladder either
    // way; without `measures` the second is not measured but quantized at the budget the
    // ladder reached, at its own a-priori widths.
    let (source, rig) = moving_chain(6, 400);
    let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
    let works = vec![Work::from_plain(&source)];
    let layouts: Vec<(usize, Layout, bool)> = [16, 32]
        .map(|l| (0, Layout::new(&works[0], &rig, l, true), true))
        .into_iter()
        .collect();
    let pick = |measures: bool| {
        estimated_candidates(
            &ctx,
            &layouts,
            &works,
            &source,
            0.001,
            true,
            false,
            (2, measures),
        )
    };
    let (measured, unmeasured) = (pick(true), pick(false));
    assert_eq!(measured.len(), 2);
    assert_eq!(unmeasured.len(), 2);
    assert!(measured.iter().all(|c| c.2.is_none()));
    let first = |c: &[(usize, Eval, Option<f32>)]| c.iter().position(|x| x.0 == 0).unwrap();
    let (m0, u0) = (&measured[first(&measured)], &unmeasured[first(&unmeasured)]);
    assert_eq!(u0.2, None);
    assert_eq!((&u0.1.bits, &u0.1.qi), (&m0.1.bits, &m0.1.qi));
    let u1 = unmeasured.iter().find(|x| x.0 == 1).unwrap();
    let budget = u1.2.unwrap();
    assert_eq!(u1.1.bits, layouts[1].1.first_bits(budget));
    let (built, _) = Eval::build(
        &ctx,
        &layouts[1].1,
        &works[0],
        u1.1.bits.clone(),
        true,
        false,
        [None; PROBES],
    );
    assert_eq!(u1.1.qi, built.qi);
}
