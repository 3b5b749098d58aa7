//! Unit tests of the segments' climb before the refinement's first round ([`super::refine::climb`],
//! [`Eval::lower_segment`]): what it keeps is what quantizing from scratch gives, a rung that does
//! not hold leaves the state as it was (the refinement with it at any thread count: `tests.rs`,
//! whose helpers this file uses).

#![allow(clippy::unwrap_used)]
use super::eval::{Ctx, Eval};
use super::quantize::Layout;
use super::reduce::Work;
use super::refine::climb;
use super::tests::{first_widths, moving_chain};

/// Every value of a state that a segment's changes write, as bits (so that equality is exact).
fn written(e: &Eval) -> (Vec<u8>, Vec<Vec<u32>>, Vec<u32>) {
    let floats = e
        .dec
        .iter()
        .flatten()
        .copied()
        .chain(e.raw.iter().flatten().flat_map(|q| q.to_array()))
        .chain(e.key_rot.iter().flat_map(|q| q.to_array()))
        .chain(e.model.iter().flat_map(|m| m.to_cols_array()))
        .chain(e.local_aff.iter().flat_map(|m| m.to_cols_array()))
        .map(f32::to_bits)
        .collect();
    (e.bits.clone(), e.qi.clone(), floats)
}

/// Six moving joints, 200 keys in 13 segments of 16: `f` given the state at the whole clip's
/// first widths (its local poses filled in, as the refinement starts), and those widths.
fn at_first_widths(compensate: bool, f: impl FnOnce(&mut Eval, &[u8])) {
    let (source, rig) = moving_chain(6, 200);
    let work = Work::from_plain(&source);
    let ctx = Ctx::new(&rig, &source, source.times(), 0.001);
    let layout = Layout::new(&work, &rig, 16, compensate);
    let bits = first_widths(&ctx, &layout, &work, compensate);
    let mut e = Eval::new(&ctx, &layout, &work, bits.clone(), compensate);
    e.fill_local();
    f(&mut e, &bits);
}

#[test]
fn a_segment_climb_keeps_what_quantizing_from_scratch_gives() {
    // Each segment climbs from the whole clip's first widths; some hold rungs above them (the
    // clip's ladder stops at its hardest segment), and the state after them is, bit for bit, the
    // one built from scratch with the widths they reached.
    for compensate in [true, false] {
        at_first_widths(compensate, |e, bits| {
            let no_probes = vec![(0.0f32, 0usize); e.nj];
            let mut climbed = 0;
            for s in 0..e.layout.seg_count {
                let before = e.bits.clone();
                match climb(e, s, &no_probes) {
                    Some(worst) => {
                        climbed += 1;
                        assert!(worst.iter().all(|w| w.0 <= 1.0), "{worst:?}");
                        assert_ne!(e.bits, before, "segment {s} kept a rung without lowering");
                        assert!(e.bits.iter().zip(&before).all(|(a, b)| a <= b));
                    }
                    None => assert_eq!(e.bits, before, "segment {s}"),
                }
            }
            assert!(climbed > 0, "compensate {compensate}: no segment climbed");
            assert!(e.bits.iter().zip(bits).all(|(a, b)| a <= b));
            assert!(e.within());
            let fresh = Eval::new(
                e.ctx,
                e.layout,
                &Work::from_plain(e.ctx.like),
                e.bits.clone(),
                compensate,
            );
            assert_eq!(written(e), written(&fresh), "compensate {compensate}");
        });
    }
}

#[test]
fn a_rung_that_does_not_hold_leaves_the_state_as_it_was() {
    at_first_widths(true, |e, _| {
        let before = written(e);
        let nc = e.layout.comps.len();
        // Every component of a middle segment at 0 bits: far past the limits of a moving chain.
        let zeros = vec![0u8; nc];
        // With probes (a time in the segment measured first) and without.
        for probes in [&[][..], &[3][..]] {
            let (j, pos) = e.lower_segment(6, &zeros, 1.0, (probes, &[])).unwrap_err();
            assert!(j < e.nj && pos < e.seg_times[6].len());
            assert_eq!(written(e), before, "probes {probes:?}");
        }
        // Only the last joint's components lowered: it alone moves (a leaf of the chain), so a
        // failure is found there.
        let mut leaf_only = e.bits[6 * nc..7 * nc].to_vec();
        let leaf = e.nj - 1;
        for (c, b) in leaf_only.iter_mut().enumerate() {
            if e.joint[e.layout.comps[c].track] == leaf {
                *b = 0;
            }
        }
        let (j, _) = e.lower_segment(6, &leaf_only, 1.0, (&[], &[])).unwrap_err();
        assert_eq!(j, leaf);
        assert_eq!(written(e), before);
        // And a rung that holds changes the state (so that the comparison can tell).
        let mut one_down = e.bits[6 * nc..7 * nc].to_vec();
        let c = one_down.iter().position(|&b| b > 1).unwrap();
        one_down[c] -= 1;
        assert!(e
            .lower_segment(6, &one_down, f32::INFINITY, (&[], &[]))
            .is_ok());
        assert_ne!(written(e), before);
    });
}
