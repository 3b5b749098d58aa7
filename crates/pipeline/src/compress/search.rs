//! The per-clip search over key budgets, segment lengths and bit widths, and the entry point.

use super::eval::{add_probe, Ctx, Eval, Probes, Sampled, PROBES};
use super::frames::{frame_keys, frames_first, thinned, Found, THINNING};
use super::metric::{
    clip_extent, errors_against, joint_limits, measure, skeleton_extent, within_limits, Rig,
};
use super::options::{
    ClipCompressionReport, CompressOptions, Effort, KeptPlain, DEFAULT_RELATIVE_DISTANCE,
    DEFAULT_RELATIVE_TOLERANCE, DESCENDED, FAST_KEY_BUDGET, FAST_REFINED_VOLUME, FIRST_RUNGS_DOWN,
    KEY_BUDGETS, MAX_DESCENDED, MAX_EXTRA_KEY_BUDGETS, MAX_EXTRA_SEGMENTS, PARALLEL_VOLUME,
    SHORT_CLIP,
};
use super::quantize::{Components, Layout};
use super::reduce::{reduce_keys, simplify_channels, Work};
use super::refine::descend;
use rayon::prelude::*;
use sinew_core::format::clip_record_size;
use sinew_core::{Channel, Clip, Skeleton};
use std::cell::OnceCell;

/// `f` over `items`, in order; in parallel (rayon) when `par`. The same results either way.
fn map_in_order<T: Send, R: Send>(
    items: Vec<T>,
    par: bool,
    f: impl Fn(T) -> R + Sync + Send,
) -> Vec<R> {
    if par {
        items.into_par_iter().map(f).collect()
    } else {
        items.into_iter().map(f).collect()
    }
}

/// Step 3, first part, for one layout: a uniform budget, on a ladder of factors 2^(1/4) from
/// `start`, whose a-priori bit widths ([`Layout::first_bits`]) measure within the limits while the
/// rung above does not (found by galloping and bisection both ways, so the largest such rung when
/// passing is monotone in the budget, as it nearly always is; the same widths are measured once);
/// returns the budget, the widths and the stored integers they give (per component, per key).
///
/// `probe`: the source times where the last failing checks stopped and where the last passing
/// ones had their largest errors (of this ladder or an earlier layout's), checked first by the
/// next check; updated here. A check's verdict does not depend on the order of its times, so
/// the answer is the same with any probes: they only make failing checks stop sooner (the hardest
/// pose of a clip is usually the same from one rung and layout to the next).
pub(super) fn first_state(
    ctx: &Ctx,
    layout: &Layout,
    work: &Work,
    start: f32,
    compensate: bool,
    par: bool,
    probe: &mut Probes,
) -> Option<(f32, Vec<u8>, Vec<Vec<u32>>)> {
    first_eval(ctx, layout, work, start, compensate, par, probe).map(|(b, e)| (b, e.bits, e.qi))
}

/// [`first_state`], returning the state itself: a check that passes has quantized every key and
/// computed every time, so it is the state [`Eval::new`] would build with those widths.
pub(super) fn first_eval<'a>(
    ctx: &'a Ctx<'a>,
    layout: &'a Layout,
    work: &Work,
    start: f32,
    compensate: bool,
    par: bool,
    probe: &mut Probes,
) -> Option<(f32, Eval<'a>)> {
    type Measured<'b> = Result<(Eval<'b>, usize), (Vec<u8>, usize)>;
    let measure = |bits: Vec<u8>, probe: Probes| -> Measured<'a> {
        let (e, verdict) = Eval::build(ctx, layout, work, bits, compensate, true, probe);
        match verdict {
            Ok(worst) => Ok((e, worst)),
            Err(i) => Err((e.bits, i)),
        }
    };
    // A check's verdict depends on the widths alone, and neighbouring rungs often have the same
    // widths (a clip with little motion: every component at 0 bits over many rungs): a rung whose
    // widths equal those of the state in hand passes, one whose widths failed before fails, and
    // only distinct widths are measured. The same verdicts, so the same result.
    let mut failed: Vec<Vec<u8>> = Vec::new();
    // A failing check's time, or a passing one's time of largest error, becomes the first probe
    // (the higher rung's when both of a pair are settled).
    let settle = |r: Measured<'a>, failed: &mut Vec<Vec<u8>>, probe: &mut Probes| match r {
        Ok((e, worst)) => {
            add_probe(probe, worst);
            Some(e)
        }
        Err((bits, i)) => {
            add_probe(probe, i);
            failed.push(bits);
            None
        }
    };
    // The start and the rung above are measured together (in parallel): the usual outcome, the
    // start passing and the rung above failing, then takes one round, and a rung measured in vain
    // is above a failing one, so it usually fails early too.
    // 2^(1/4): rungs finer than sqrt(2) start the refinement nearer its result (corpus clips -0.26%
    // in total at 0.001 @ 0.1, Fox Walk -4%; encoder time -9% to +4% per file).
    let step: f32 = std::f32::consts::SQRT_2.sqrt();
    let mut budget = start;
    let (bits0, bits1) = (layout.first_bits(budget), layout.first_bits(budget * step));
    let p = *probe;
    let (r0, r1) = if bits0 == bits1 {
        (measure(bits0, p), None)
    } else if par {
        let (a, b) = rayon::join(|| measure(bits0, p), || measure(bits1, p));
        (a, Some(b))
    } else {
        (measure(bits0, p), Some(measure(bits1, p)))
    };
    let mut found = settle(r0, &mut failed, probe);
    // The rung above: `None` when its widths are the start's (the same verdict and state).
    let up = r1.map(|r| settle(r, &mut failed, probe));
    if let Some(start_state) = found.take() {
        // The start's state is dropped as soon as the rung above replaces it: a long clip's
        // state is megabytes, and memory a process touches first costs a page fault per page.
        let mut lo_state = match up {
            None => start_state,
            Some(Some(e)) => {
                drop(start_state);
                e
            }
            Some(None) => return Some((budget, start_state)),
        };
        // Up: rung k is `start` times `step` k times (multiplied one at a time, as a rung-by-rung
        // climb computes it), at most `TOP`. Galloping (rungs 2, 4, 8, ...) then bisecting finds
        // the rung below the first failing one in about 2 log2(k) checks instead of k: clips with
        // little motion climb far (a 2-key clip reaches the top).
        const TOP: u32 = 33;
        let rung = |k: u32| (0..k).fold(start, |b, _| b * step);
        // Whether rung `k` passes; a newly measured passing state replaces `lo_state`.
        let passes =
            |k: u32, lo_state: &mut Eval<'a>, failed: &mut Vec<Vec<u8>>, probe: &mut Probes| {
                let bits = layout.first_bits(rung(k));
                if bits == lo_state.bits {
                    return true;
                }
                if failed.contains(&bits) {
                    return false;
                }
                match settle(measure(bits, *probe), failed, probe) {
                    Some(e) => {
                        *lo_state = e;
                        true
                    }
                    None => false,
                }
            };
        let mut lo = 1u32;
        let mut hi = None;
        let mut k = 2u32;
        while hi.is_none() && lo < TOP {
            if passes(k, &mut lo_state, &mut failed, probe) {
                lo = k;
                k = (k * 2).min(TOP);
            } else {
                hi = Some(k);
            }
        }
        if let Some(mut hi) = hi {
            while hi - lo > 1 {
                let mid = (lo + hi) / 2;
                if passes(mid, &mut lo_state, &mut failed, probe) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
        }
        budget = rung(lo);
        found = Some(lo_state);
    } else {
        // (The rung above cannot be the answer here: its state, if it passed, is not kept.)
        drop(up);
        // Down: rung k is `start` divided by `step` k times (one at a time, as a rung-by-rung
        // descent computes it), at most `BOTTOM`. Most layouts pass one to three rungs down,
        // measured one by one; below, galloping (rungs 5, 9, 17, ...) then bisecting finds the
        // highest passing rung (where passing is monotone in the budget, as it nearly always is:
        // the one a descent rung by rung finds) in about 2 log2(k) checks instead of k (a layout
        // starting from a budget far above its own, as after a work of little motion).
        const BOTTOM: u32 = 80;
        let rung = |k: u32| (0..k).fold(start, |b, _| b / step);
        let check = |k: u32, failed: &mut Vec<Vec<u8>>, probe: &mut Probes| {
            let bits = layout.first_bits(rung(k));
            if failed.contains(&bits) {
                return None;
            }
            settle(measure(bits, *probe), failed, probe)
        };
        // The lowest rung known to fail, and the highest known to pass with its state.
        let mut lo = 0u32;
        let mut hi = None;
        let mut k = 1u32;
        while hi.is_none() && lo < BOTTOM {
            match check(k, &mut failed, probe) {
                Some(e) => hi = Some((k, e)),
                None => {
                    lo = k;
                    k = if k < 3 { k + 1 } else { 2 * k - 1 }.min(BOTTOM);
                }
            }
        }
        if let Some((mut h, mut state)) = hi {
            while h - lo > 1 {
                let mid = (lo + h) / 2;
                let bits = layout.first_bits(rung(mid));
                if bits == state.bits {
                    h = mid;
                    continue;
                }
                match check(mid, &mut failed, probe) {
                    Some(e) => (h, state) = (mid, e),
                    None => lo = mid,
                }
            }
            budget = rung(h);
            found = Some(state);
        }
    }
    found.map(|e| (budget, e))
}

/// Where a refinement starts: a state already measured, first bit widths to build one from, or
/// (not refined) a state quantized at a budget and not measured ([`estimated_candidates`]).
pub(super) enum Start<'a> {
    State(Box<Eval<'a>>),
    Bits(Vec<u8>),
    Unmeasured(Box<Eval<'a>>, f32),
}

/// The thresholds of the first rounds of [`descend`] (fractions of the joints' limits).
pub(super) const THRESHOLDS: [f32; 4] = [0.5, 0.7, 0.85, 0.95];

/// Segment lengths tried for `n` keys: 16 and 32; up to [`SHORT_CLIP`] keys also 64 and the lengths
/// that split the keys into 1 to 4 segments of (nearly) equal size (segment headers weigh on short
/// clips; on long ones short segments follow the motion best).
pub(super) fn segment_candidates(n: usize) -> Vec<usize> {
    let n = n.max(1);
    let short = n <= SHORT_CLIP;
    let mut out: Vec<usize> = [16, 32]
        .into_iter()
        .chain(short.then_some(64))
        .chain((1..=4).filter(|_| short).map(|k| n.div_ceil(k)))
        .map(|l| l.clamp(1, n))
        .collect();
    out.sort_unstable();
    out.dedup();
    out
}

/// Steps 1 to 5 of the module docs: the result's record size, the result and its errors at the
/// source's times (time-major, one per joint); `None` when nothing met the limits.
///
/// Every key-reduction budget of [`KEY_BUDGETS`] (giving distinct kept keys) is a work; each work
/// has a layout per segment length of [`segment_candidates`]. [`estimated_candidates`] measures
/// one layout per work and estimates the others; the [`DESCENDED`] smallest are refined by
/// [`descend`], and the smallest result is kept (the first of equals). `Max` adds
/// [`exhaustive_candidates`]. `compensate`: quantize rotations with chain
/// compensation (only when every scale of the source poses is positive and uniform). `work`: the
/// source's, as [`Work::from_plain`] gives it; `sampled`: the source sampled at its times, when
/// known.
#[allow(clippy::too_many_arguments)]
pub(super) fn compress_work(
    work: &mut Work,
    source: &Clip,
    sampled: Option<&Sampled>,
    rig: &Rig,
    tolerance: f32,
    bind_allowed: bool,
    options: &CompressOptions,
    compensate: bool,
    climbs: bool,
) -> Option<Found> {
    if work.times.is_empty() {
        return None;
    }
    let times = source.times();
    let ctx = match sampled {
        Some(s) => Ctx::of_sampled(rig, source, times, tolerance, s),
        None => Ctx::new(rig, source, times, tolerance),
    };
    let compensate = compensate && ctx.uniform;
    let (src, origins) = (&ctx.src, ctx.origins.as_slice());
    let poses = simplify_channels(
        work,
        source,
        rig,
        src,
        origins,
        times,
        sampled.map(|s| s.poses.as_slice()),
        tolerance * 0.25,
        bind_allowed,
    );
    let base = work.clone();
    let effort = options.effort;
    let par = times.len() * rig.skeleton.len() >= PARALLEL_VOLUME;
    let budgets: Vec<f32> = match effort {
        Effort::Max => KEY_BUDGETS
            .iter()
            .chain(&MAX_EXTRA_KEY_BUDGETS)
            .copied()
            .collect(),
        Effort::Fast => vec![FAST_KEY_BUDGET],
        Effort::Default => KEY_BUDGETS.to_vec(),
    };
    // The works and layouts of the default search come first, in the default's order, so that
    // `Max` reaches the same candidates for them and can only add to them.
    let mut kept_sets: Vec<Vec<usize>> = Vec::new();
    let mut works: Vec<Work> = Vec::new();
    let mut default_works = 0;
    if options.key_reduction {
        // Each budget's reduction is independent of the others: computed in parallel, used in
        // order, on the poses the channel simplification leaves (the same work's, computed once).
        let known = poses.as_deref().filter(|_| base.times.as_slice() == times);
        let reduced: Vec<Vec<usize>> = map_in_order(budgets, par, |frac| {
            reduce_keys(&base, source, rig, src, origins, known, tolerance * frac)
        });
        for (bi, kept) in reduced.into_iter().enumerate() {
            if !kept_sets.contains(&kept) {
                let mut w = base.clone();
                w.keep(&kept);
                works.push(w);
                kept_sets.push(kept);
            }
            if bi < KEY_BUDGETS.len() {
                default_works = works.len();
            }
        }
    } else {
        works.push(base);
        default_works = 1;
    }
    // (work, segment length, part of the default search)
    let mut plan: Vec<(usize, usize, bool)> = Vec::new();
    for (wi, w) in works.iter().enumerate() {
        for l in segment_candidates(w.times.len()) {
            plan.push((wi, l, wi < default_works));
        }
    }
    if effort == Effort::Max {
        for (wi, w) in works.iter().enumerate() {
            let have = segment_candidates(w.times.len());
            for l in MAX_EXTRA_SEGMENTS {
                let l = l.clamp(1, w.times.len().max(1));
                if !have.contains(&l) {
                    plan.push((wi, l, false));
                }
            }
        }
        // Default layouts first (stable: their relative order is kept).
        plan.sort_by_key(|l| !l.2);
    }
    // The components of a set of kept keys are shared by its segment lengths' layouts.
    let bases: Vec<Components> = map_in_order((0..works.len()).collect(), par, |wi| {
        Components::new(&works[wi], rig, compensate)
    });
    let layouts: Vec<(usize, Layout, bool)> = map_in_order(plan, par, |(wi, l, core)| {
        (wi, Layout::with_segments(&bases[wi], l), core)
    });
    // `Fast` on a long clip: the ladder's widths (the refinement's work grows with the times),
    // and a chosen layout the ladder did not measure checked by the runtime's sampler alone.
    let refines = effort != Effort::Fast || times.len() * rig.skeleton.len() <= FAST_REFINED_VOLUME;
    let mut chosen: Vec<(usize, Start)> = estimated_candidates(
        &ctx,
        &layouts,
        &works,
        source,
        tolerance,
        compensate,
        par,
        (DESCENDED, refines),
    )
    .into_iter()
    .map(|(li, e, unmeasured)| match unmeasured {
        Some(budget) => (li, Start::Unmeasured(Box::new(e), budget)),
        None => (li, Start::State(Box::new(e))),
    })
    .collect();
    if effort == Effort::Max {
        for (li, bits) in
            exhaustive_candidates(&ctx, &layouts, &works, source, tolerance, compensate, par)
        {
            let known = chosen.iter().any(|(l, start)| match start {
                Start::State(e) | Start::Unmeasured(e, _) => *l == li && e.bits == bits,
                Start::Bits(b) => *l == li && *b == bits,
            });
            if !known {
                chosen.push((li, Start::Bits(bits)));
            }
        }
    }
    // The refinements are independent: run in parallel, the smallest kept (the first of equals
    // in candidate order, so the result does not depend on the thread count).
    // One refinement (`Fast` and `Default`) spreads its own tries over the threads; `Max`'s
    // several candidates are refined side by side instead.
    let alone = par && chosen.len() == 1;
    let refined: Vec<Option<Found>> = map_in_order(chosen, par, |(li, start)| {
        let (wi, layout, _) = &layouts[li];
        let w = &works[*wi];
        let holds = |c: Clip| {
            let errors = errors_against(rig, src, origins, &c, times);
            within_limits(&errors, &ctx.limits).then(|| (clip_record_size(&c), c, errors))
        };
        let mut e = match start {
            Start::State(e) => *e,
            Start::Bits(bits) => Eval::new(&ctx, layout, w, bits, compensate),
            Start::Unmeasured(e, budget) => {
                // Where the runtime's check does not hold, the layout's ladder from its
                // budget, as the default measures it.
                return e.encode(w).and_then(holds).or_else(|| {
                    drop(e);
                    let mut probe = [None; PROBES];
                    let measured =
                        first_eval(&ctx, layout, w, budget, compensate, alone, &mut probe);
                    measured.and_then(|(_, e)| e.encode(w)).and_then(holds)
                });
            }
        };
        // The starting widths and stored integers: encoded only if the refined state does not
        // hold at every source time (it always has on the corpus); an unrefined state is its
        // own start.
        let start = refines.then(|| (e.bits.clone(), e.qi.clone()));
        // Fast: every round at threshold 1 (no graded first rounds): 15-25% less work for
        // 0.3-2.2% more bytes on the corpus's clips (docs/performance.md, session 10).
        let thresholds: &[f32] = if effort == Effort::Fast {
            &[]
        } else {
            &THRESHOLDS
        };
        if refines {
            descend(&mut e, alone, thresholds, climbs);
        }
        e.encode(w).and_then(holds).or_else(|| {
            let (bits, qi) = start?;
            layout.encode(&bits, &qi, w, ctx.like).and_then(holds)
        })
    });
    let mut best: Option<Found> = None;
    for found in refined.into_iter().flatten() {
        if best.as_ref().is_none_or(|b| found.0 < b.0) {
            best = Some(found);
        }
    }
    best
}

/// The default search's candidates: per work, the first bit widths of its first layout are
/// measured ([`first_state`]), and the budget they reached gives every other layout of the work its
/// a-priori widths and so its size, without measuring them (the budget depends on the kept keys
/// far more than on the segment length). The `count` smallest layouts (by that size; the first of
/// equals) are then measured from that budget. Returns (layout, first bit widths).
/// Without `measures`, a chosen layout its work's ladder did not measure is not measured either:
/// its state is quantized at that budget ([`Eval::quantized`]) and returned with the budget, for
/// a caller that checks its encoding with the runtime's sampler (and measures it from the
/// budget only if that fails).
#[allow(clippy::too_many_arguments)]
pub(super) fn estimated_candidates<'a>(
    ctx: &'a Ctx<'a>,
    layouts: &'a [(usize, Layout, bool)],
    works: &[Work],
    source: &Clip,
    tolerance: f32,
    compensate: bool,
    par: bool,
    (count, measures): (usize, bool),
) -> Vec<(usize, Eval<'a>, Option<f32>)> {
    // (estimated size, layout, budget, the measured state if any)
    let mut sized: Vec<(usize, usize, f32, Option<Eval<'a>>)> = Vec::new();
    // The first layout's ladder starts `FIRST_RUNGS_DOWN` rungs below the tolerance (one at a
    // time, as a descent computes it); the next works' start where the one before ended.
    let mut start =
        (0..FIRST_RUNGS_DOWN).fold(tolerance, |b, _| b / std::f32::consts::SQRT_2.sqrt());
    let mut probe = [None; PROBES];
    let mut budget_of: Vec<Option<f32>> = vec![None; works.len()];
    for (li, (wi, layout, core)) in layouts.iter().enumerate() {
        if !core {
            continue;
        }
        let w = &works[*wi];
        let (budget, bits, measured) = match budget_of[*wi] {
            Some(b) => (b, layout.first_bits(b), None),
            None => {
                let Some((b, e)) = first_eval(ctx, layout, w, start, compensate, par, &mut probe)
                else {
                    continue;
                };
                start = b;
                budget_of[*wi] = Some(b);
                (b, e.bits.clone(), Some(e))
            }
        };
        let Some(size) = layout.record_size(&bits, w, source) else {
            continue;
        };
        sized.push((size, li, budget, measured));
        // A measured state whose layout is already out of the `count` smallest stays out (later
        // layouts only add to those before it): dropped now rather than kept through the next
        // works' ladders (a long clip's state is megabytes, each page a page fault when first
        // touched). The same layouts are chosen, with the same states.
        if sized.len() > count {
            let mut keys: Vec<(usize, usize)> = sized.iter().map(|f| (f.0, f.1)).collect();
            keys.sort_unstable();
            let last_chosen = count.checked_sub(1).map(|i| keys[i]);
            for f in &mut sized {
                if last_chosen.is_none_or(|last| (f.0, f.1) > last) {
                    f.3 = None;
                }
            }
        }
    }
    sized.sort_by_key(|f| (f.0, f.1));
    sized.truncate(count);
    // The chosen layouts' own first widths, measured from their work's budget, side by side
    // when there are several, else with the rung above measured beside the start; the probes
    // of the ladders so far first (a layout's hardest poses are usually another's).
    let alone = par && count == 1;
    map_in_order(sized, par && count > 1, |(_, li, budget, measured)| {
        let (wi, layout, _) = &layouts[li];
        match measured {
            Some(e) => Some((li, e, None)),
            None if !measures => {
                let bits = layout.first_bits(budget);
                let e = Eval::quantized(ctx, layout, &works[*wi], bits, compensate);
                Some((li, e, Some(budget)))
            }
            None => {
                let mut probe = probe;
                first_eval(
                    ctx,
                    layout,
                    &works[*wi],
                    budget,
                    compensate,
                    alone,
                    &mut probe,
                )
                .map(|(_, e)| (li, e, None))
            }
        }
    })
    .into_iter()
    .flatten()
    .collect()
}

/// `Max`'s extra candidates: every layout measured with its first widths, the [`MAX_DESCENDED`]
/// smallest. Returns (layout, first bit widths).
pub(super) fn exhaustive_candidates(
    ctx: &Ctx,
    layouts: &[(usize, Layout, bool)],
    works: &[Work],
    source: &Clip,
    tolerance: f32,
    compensate: bool,
    par: bool,
) -> Vec<(usize, Vec<u8>)> {
    let mut firsts: Vec<(usize, usize, Vec<u8>)> = Vec::new();
    let mut start = tolerance;
    let mut probe = [None; PROBES];
    for (li, (wi, layout, _)) in layouts.iter().enumerate() {
        let w = &works[*wi];
        let Some((budget, bits, _)) =
            first_state(ctx, layout, w, start, compensate, par, &mut probe)
        else {
            continue;
        };
        start = budget;
        let Some(size) = layout.record_size(&bits, w, source) else {
            continue;
        };
        firsts.push((size, li, bits));
    }
    firsts.sort_by_key(|f| (f.0, f.1));
    firsts
        .into_iter()
        .take(MAX_DESCENDED)
        .map(|f| (f.1, f.2))
        .collect()
}

/// The `p` quantile of `errors` (the value a sort would put at rank ceil(n p)); reorders them.
/// A selection, not a sort: a long capture's errors are about 100,000 values.
pub(super) fn percentile(errors: &mut [f32], p: f32) -> f32 {
    if errors.is_empty() {
        return 0.0;
    }
    let i = ((errors.len() as f32 * p).ceil() as usize).clamp(1, errors.len()) - 1;
    *errors.select_nth_unstable_by(i, f32::total_cmp).1
}

/// The search on the source's frames first ([`frames_first`]; its result, when one holds, for
/// `Fast` and `Default`), then, where it did not hold (or the frames are more than half of the
/// times) and the source does not thin, the search with the frames as the only candidate keys,
/// measured at every time ([`frame_keys`]), then on a source of thinned times, then (when it
/// found nothing that holds at every source time, or for `Max`) on the whole source; the smallest
/// result, with its
/// errors at every source time. `whole`: the source sampled at its times.
///
/// When the search on the frames does not hold and the source thins, the thinned source is
/// searched next (docs/performance.md, session 31: zombie.ms3d's export at the default tolerance
/// 6,657 -> 6,386 bytes in 0.6x the time). Where it does not thin (captures at 0.001 @ 0.1, whose
/// every time moves), [`frame_keys`] keeps the frames' advantage (no key between frames) and
/// measures every time, so that its result holds: until session 35, more rounds on the frames and
/// the times where each failed, which on some captures failed four times over and fell back to the
/// whole source at twice the bytes (docs/performance.md, session 35).
fn search(
    source: &Clip,
    whole: &Sampled,
    rig: &Rig,
    tolerance: f32,
    bind_allowed: bool,
    options: &CompressOptions,
) -> Option<Found> {
    let on = |clip: &Clip,
              sampled: Option<&Sampled>,
              tolerance: f32,
              options: &CompressOptions,
              climbs: bool| {
        let work = Work::from_plain(clip);
        let at = (clip, sampled, rig, tolerance);
        compensated_first(&work, at, bind_allowed, options, climbs)
    };
    let mut found: Vec<Found> = Vec::new();
    let times = source.times();
    let (src, origins) = (&*whole.points, whole.origins.as_slice());
    // The thinned source, made when first needed: after a first round on the frames that did not
    // hold (where the source thins, it is searched instead of more rounds), or after the frames.
    let thin_source = OnceCell::new();
    let thin = || {
        thin_source.get_or_init(|| {
            let poses = Some(whole.poses.as_slice());
            thinned(source, rig, src, origins, poses, tolerance)
        })
    };
    let at_frames = |options: &CompressOptions| {
        frames_first(
            source,
            rig,
            src,
            origins,
            tolerance,
            |clip, sampled, tolerance| on(clip, Some(sampled), tolerance, options, false),
        )
    };
    found.extend(at_frames(options));
    if !found.is_empty() && options.effort != Effort::Max {
        return found.pop();
    }
    if options.effort == Effort::Max {
        // The default's result on the frames too, so that `Max` is never larger.
        let default = CompressOptions {
            effort: Effort::Default,
            ..options.clone()
        };
        found.extend(at_frames(&default));
    }
    // Where the frames did not hold and the source does not thin: the frames as candidate keys,
    // every time measured (for `Max`, one more candidate).
    if options.effort == Effort::Max || thin().is_none() {
        found.extend(frame_keys((source, whole), rig, tolerance, |work| {
            let at = (source, Some(whole), rig, tolerance);
            compensated_first(work, at, bind_allowed, options, true)
        }));
        if !found.is_empty() && options.effort != Effort::Max {
            return found.pop();
        }
    }
    if let Some((_, thin)) = thin() {
        let limits = joint_limits(src, rig.skeleton.len(), tolerance);
        // Its errors at every source time (those at the thinned times are the search's), kept
        // with the clip when each is within its joint's limit: they are the report's.
        let holds = |(size, c, _): Found| {
            let errors = errors_against(rig, src, origins, &c, times);
            within_limits(&errors, &limits).then_some((size, c, errors))
        };
        let reduced = tolerance * (1.0 - THINNING);
        let thin_sampled = Sampled::new(rig, thin, thin.times());
        found.extend(on(thin, Some(&thin_sampled), reduced, options, false).and_then(holds));
        if options.effort == Effort::Max {
            // The default's result on the thinned source too, so that `Max` is never larger.
            let default = CompressOptions {
                effort: Effort::Default,
                ..options.clone()
            };
            found.extend(on(thin, Some(&thin_sampled), reduced, &default, false).and_then(holds));
        }
    }
    if found.is_empty() || options.effort == Effort::Max {
        found.extend(on(source, Some(whole), tolerance, options, true));
    }
    // The smallest (the first of equals, in the order tried).
    let mut best: Option<Found> = None;
    for f in found {
        if best.as_ref().is_none_or(|b| f.0 < b.0) {
            best = Some(f);
        }
    }
    best
}

/// [`compress_work`] on a copy of `work`, measured against `source` (`sampled` at its times when
/// known) at `tolerance`: with chain compensation, or without it where that finds nothing.
pub(super) fn compensated_first(
    work: &Work,
    (source, sampled, rig, tolerance): (&Clip, Option<&Sampled>, &Rig, f32),
    bind_allowed: bool,
    options: &CompressOptions,
    climbs: bool,
) -> Option<Found> {
    [true, false].into_iter().find_map(|compensate| {
        compress_work(
            &mut work.clone(),
            source,
            sampled,
            rig,
            tolerance,
            bind_allowed,
            options,
            compensate,
            climbs,
        )
    })
}

/// Compresses one clip within the tolerance (see the module docs) and reports what it reached.
///
/// `skeleton` gives the joint hierarchy for the error metric, the bind values for bind elision and the
/// extent for the default tolerance; without it every track is its own root and no channel is elided
/// to the bind value (except identity differences of an additive clip). When the compressed clip
/// would not be smaller than the plain one, the plain clip is returned (`report.compressed == false`).
pub fn compress_clip(
    clip: &Clip,
    skeleton: Option<&Skeleton>,
    options: &CompressOptions,
) -> (Clip, ClipCompressionReport) {
    // A plain clip is its own source (not copied: a long capture is megabytes).
    let decoded;
    let source: &Clip = if clip.is_compressed() {
        decoded = clip.to_plain();
        &decoded
    } else {
        clip
    };
    let extent = skeleton.map_or_else(|| clip_extent(source), skeleton_extent);
    let tolerance = options
        .tolerance
        .filter(|t| t.is_finite() && *t > 0.0)
        .unwrap_or(DEFAULT_RELATIVE_TOLERANCE * extent);
    let distance = options
        .error_distance
        .filter(|t| t.is_finite() && *t >= 0.0)
        .unwrap_or(DEFAULT_RELATIVE_DISTANCE * extent);
    let mut best: Option<Found> = None;
    let rig = Rig::new(source, skeleton, distance);
    let whole = rig
        .as_ref()
        .map(|rig| (rig, Sampled::new(rig, source, source.times())));
    if let Some((rig, whole)) = &whole {
        best = search(source, whole, rig, tolerance, skeleton.is_some(), options);
    }
    let plain_bytes = clip_record_size(source);
    let (kept_plain_because, error_limit) = match (&best, &whole) {
        (Some((size, ..)), _) if *size < plain_bytes => (None, None),
        // (A clip without key times has nothing to encode.)
        (None, Some((rig, whole))) if !source.times().is_empty() => {
            let limits = joint_limits(&whole.points, rig.skeleton.len(), tolerance);
            let tightest = limits.iter().copied().fold(tolerance, f32::min);
            (Some(KeptPlain::ToleranceNotHeld), Some(tightest))
        }
        _ => (Some(KeptPlain::NotSmaller), None),
    };
    let (out, measured, compressed_bytes) = match best {
        Some((size, clip, errors)) if size < plain_bytes => (clip, Some(errors), size),
        _ => (source.clone(), None, plain_bytes),
    };
    // The source's points are the ones the search measured against ([`measure`] computes them
    // the same way).
    let mut errors = match (measured, &whole) {
        (Some(errors), _) => errors,
        (None, Some((rig, whole))) => {
            errors_against(rig, &whole.points, &whole.origins, &out, source.times())
        }
        (None, None) => measure(source, &out, skeleton, distance),
    };
    let max_error = errors.iter().copied().fold(0.0, f32::max);
    let p99_error = percentile(&mut errors, 0.99);
    let animated_joints = source
        .tracks()
        .iter()
        .filter(|t| {
            matches!(t.translation, Channel::Animated(_))
                || matches!(t.rotation, Channel::Animated(_))
                || matches!(t.scale, Channel::Animated(_))
        })
        .count();
    let samples = source.times().len();
    // A clip without an animated channel (a single pose: one key, or every channel constant) still
    // stores one pose of each joint it drives: that is its raw size, not 0.
    let posed_joints = if animated_joints > 0 {
        animated_joints
    } else {
        source
            .tracks()
            .iter()
            .filter(|t| {
                !matches!(t.translation, Channel::Bind)
                    || !matches!(t.rotation, Channel::Bind)
                    || !matches!(t.scale, Channel::Bind)
            })
            .count()
    };
    let raw_bytes = 40 * posed_joints * samples;
    let report = ClipCompressionReport {
        clip: clip.name().to_owned(),
        raw_bytes,
        plain_bytes,
        compressed_bytes,
        ratio: raw_bytes as f32 / compressed_bytes.max(1) as f32,
        max_error,
        p99_error,
        tolerance,
        error_distance: distance,
        animated_joints,
        samples,
        kept_keys: out.times().len(),
        bytes_per_joint_sample: compressed_bytes as f32 / (animated_joints * samples).max(1) as f32,
        compressed: out.is_compressed(),
        kept_plain_because,
        error_limit,
    };
    (out, report)
}
