//! Step 3, second part: the refinement of a state's bit widths, one bit at a time, with the
//! segments of one parity worked on side by side.

use super::eval::{Eval, SegmentState};
use super::trial::{Trial, MAX_PROBES};
use rayon::prelude::*;
use std::sync::{Mutex, PoisonError};

/// What refining one segment on a copy of the state gives back: the segment, what it wrote
/// (`None` when nothing was kept), its components' `blocked` and `probes` entries, and its joints'
/// `worst` entries.
type Refined = (
    usize,
    Option<SegmentState>,
    Vec<bool>,
    Vec<usize>,
    Vec<(f32, usize)>,
);

/// Rounds of one-bit reductions over every component of every segment. A reduction is kept when
/// the error it gives, as a fraction of the limit, is within the round's threshold; thresholds
/// rise over the first rounds (`thresholds`: [`super::search::THRESHOLDS`], or none for
/// `Effort::Fast`) so that the cheapest reductions are taken first, then stay at 1 until no
/// reduction is kept. A reduction that fails at threshold 1 is not tried again (errors only grow
/// as other widths shrink).
///
/// Within a round the even segments go first, then the odd ones; on each segment the components
/// go in order, each kept try committed before the next is worked out. A try reads and writes only
/// its segment's keys, the neighbouring keys its source times read, and those times (a time reads
/// the two keys around it, so at most two neighbouring segments), so segments two or more apart
/// are independent: with `par`, the segments of one parity are each refined on a copy of the
/// state that holds what they read ([`Eval::load_segment`]), side by side, and what they wrote is
/// copied back. Every try sees what it would see one at a time, so the result is the same at any
/// thread count.
pub(super) fn descend(eval: &mut Eval, par: bool, thresholds: &[f32]) {
    let nc = eval.layout.comps.len();
    let segs = eval.layout.seg_count;
    if nc == 0 || segs == 0 {
        return;
    }
    // Per segment, per component: failed at threshold 1 (not tried again), and where its last
    // failed try stopped (a time to measure first).
    let mut blocked = vec![false; nc * segs];
    let mut probes = vec![usize::MAX; nc * segs];
    // Per segment, per joint: the largest ratio of error to limit at the segment's source times,
    // and where (the first time tried of a component whose subtree has it). Kept up to date by
    // the kept tries on the segment; a kept try on a neighbouring segment can change a shared
    // time's error without updating it here, which only makes the guess worse.
    let nj = eval.nj;
    let mut worst = segment_worst(eval);
    let threads = rayon::current_num_threads();
    let side_by_side = par && threads > 1 && segs > 2;
    // Per thread of the pool: a copy of the state and a trial to refine segments in.
    let slots: Vec<Mutex<(Eval, Trial)>> = if side_by_side {
        (0..threads)
            .map(|_| Mutex::new((eval.empty_copy(), Trial::default())))
            .collect()
    } else {
        Vec::new()
    };
    let mut trial = Trial::default();
    let mut round = 0;
    loop {
        let limit = thresholds.get(round).copied().unwrap_or(1.0);
        round += 1;
        let mut changed = false;
        for parity in 0..2 {
            let segments: Vec<usize> = (parity..segs).step_by(2).collect();
            if side_by_side && segments.len() > 1 {
                let state: &Eval = eval;
                let (blocked_now, probes_now, worst_now) = (&blocked[..], &probes[..], &worst[..]);
                let done: Vec<Refined> = segments
                    .par_iter()
                    .map(|&s| {
                        let at = rayon::current_thread_index().unwrap_or(0) % slots.len();
                        let mut slot = slots[at].lock().unwrap_or_else(PoisonError::into_inner);
                        let (copy, trial) = &mut *slot;
                        let own = s * nc..(s + 1) * nc;
                        let mut b = blocked_now[own.clone()].to_vec();
                        let mut p = probes_now[own].to_vec();
                        let mut w = worst_now[s * nj..(s + 1) * nj].to_vec();
                        let kept = refine_segment(
                            copy,
                            Some(state),
                            trial,
                            s,
                            limit,
                            (&mut b, &mut p, &mut w),
                        );
                        (s, kept.then(|| copy.segment_state(s)), b, p, w)
                    })
                    .collect();
                for (s, written, b, p, w) in done {
                    let own = s * nc..(s + 1) * nc;
                    blocked[own.clone()].copy_from_slice(&b);
                    probes[own].copy_from_slice(&p);
                    worst[s * nj..(s + 1) * nj].copy_from_slice(&w);
                    if let Some(written) = written {
                        eval.store_segment(&written);
                        changed = true;
                    }
                }
            } else {
                for s in segments {
                    let own = s * nc..(s + 1) * nc;
                    changed |= refine_segment(
                        eval,
                        None,
                        &mut trial,
                        s,
                        limit,
                        (
                            &mut blocked[own.clone()],
                            &mut probes[own],
                            &mut worst[s * nj..(s + 1) * nj],
                        ),
                    );
                }
            }
        }
        if !changed && round >= thresholds.len() {
            break;
        }
    }
}

/// One round's tries on segment `s`, component by component (`blocked`, `probes` and `worst`: the
/// segment's entries); true when one was kept. With `from`, `eval` is a copy of that state
/// ([`Eval::empty_copy`]): the tries read `from` until one is kept, which first loads the
/// segment's neighbourhood into the copy ([`Eval::load_segment`]), and the rest read and write the
/// copy; a segment where nothing is kept copies nothing.
fn refine_segment(
    eval: &mut Eval,
    from: Option<&Eval>,
    trial: &mut Trial,
    s: usize,
    limit: f32,
    (blocked, probes, worst): (&mut [bool], &mut [usize], &mut [(f32, usize)]),
) -> bool {
    let nc = eval.layout.comps.len();
    let mut kept = false;
    for (c, (blocked, probe)) in blocked.iter_mut().zip(probes.iter_mut()).enumerate() {
        let i = s * nc + c;
        let current: &Eval = match from {
            Some(state) if !kept => state,
            _ => eval,
        };
        if current.bits[i] == 0 || *blocked {
            continue;
        }
        // First where this try failed last, then the times where the state's error is largest
        // over the joints it can move (each joint's worst time in the segment, largest first).
        let j = current.joint[current.layout.comps[c].track];
        let mut first = [(f32::INFINITY, *probe); MAX_PROBES];
        let mut n = usize::from(*probe != usize::MAX);
        for &d in &current.subtree[j] {
            let (r, pos) = worst[d];
            if r <= 0.0 || first[..n].iter().any(|f| f.1 == pos) {
                continue;
            }
            // Insert by ratio, largest first, keeping at most MAX_PROBES.
            let at = first[..n].iter().position(|f| f.0 < r).unwrap_or(n);
            if at < MAX_PROBES {
                first.copy_within(at..MAX_PROBES - 1, at + 1);
                first[at] = (r, pos);
                n = (n + 1).min(MAX_PROBES);
            }
        }
        let probes: [usize; MAX_PROBES] = std::array::from_fn(|k| first[k].1);
        trial.run(current, s, c, current.bits[i] - 1, limit, &probes[..n]);
        if trial.worst <= limit {
            if let Some(state) = from.filter(|_| !kept) {
                eval.load_segment(state, s);
            }
            trial.commit(eval);
            kept = true;
            for (d, r, pos) in trial.moved_worst() {
                worst[d] = (r, pos);
            }
        } else {
            *blocked = limit >= 1.0;
            if trial.failed_at != usize::MAX {
                *probe = trial.failed_at;
            }
        }
    }
    kept
}

/// Per segment, per joint: the largest ratio of error to limit over the segment's source times,
/// and the time's position among them.
fn segment_worst(eval: &Eval) -> Vec<(f32, usize)> {
    let nj = eval.nj;
    let mut worst = vec![(0.0f32, 0usize); eval.layout.seg_count * nj];
    for (s, times) in eval.seg_times.iter().enumerate() {
        for (pos, &i) in times.iter().enumerate() {
            for j in 0..nj {
                let r = eval.joint_error(i, j) / eval.ctx.limits[j];
                let w = &mut worst[s * nj + j];
                if r > w.0 {
                    *w = (r, pos);
                }
            }
        }
    }
    worst
}
