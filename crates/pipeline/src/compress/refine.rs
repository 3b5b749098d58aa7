//! Step 3, second part: the refinement of a state's bit widths, one bit at a time, with the
//! segments of one parity worked on side by side.

use super::eval::Eval;
use super::segment::SegmentState;
use super::trial::{Trial, MAX_PROBES};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError, RwLock};

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
/// as other widths shrink). With `climbs`, each segment first climbs a ladder of its own in the
/// first round, before its components' tries ([`climb`]; it reads and writes what a try on the
/// segment does).
///
/// Within a round the even segments go first, then the odd ones; on each segment the components
/// go in order, each kept try committed before the next is worked out. A try reads and writes only
/// its segment's keys, the neighbouring keys its source times read, and those times (a time reads
/// the two keys around it, so at most two neighbouring segments), so segments two or more apart
/// are independent: with `par`, the segments of one parity are each refined on a copy of the
/// state that holds what they read ([`Eval::load_segment`]), side by side, and what they wrote is
/// copied back. Every try sees what it would see one at a time, so the result is the same at any
/// thread count.
pub(super) fn descend(eval: &mut Eval, par: bool, thresholds: &[f32], climbs: bool) {
    eval.fill_local();
    let nc = eval.layout.comps.len();
    let segs = eval.layout.seg_count;
    if nc == 0 || segs == 0 {
        return;
    }
    // Per segment, per component: failed at threshold 1 (not tried again), and where its last
    // failed try stopped (a time to measure first).
    let blocked = vec![false; nc * segs];
    let probes = vec![usize::MAX; nc * segs];
    // Per segment, per joint: the largest ratio of error to limit at the segment's source times,
    // and where (the first time tried of a component whose subtree has it). Kept up to date by
    // the kept tries on the segment; a kept try on a neighbouring segment can change a shared
    // time's error without updating it here, which only makes the guess worse.
    let worst = segment_worst(eval);
    // Threads that can take a segment of a parity (at most half the segments each).
    let threads = rayon::current_num_threads().min(segs.div_ceil(2));
    let mut state = State {
        eval,
        blocked,
        probes,
        worst,
    };
    if par && threads > 1 && segs > 2 {
        side_by_side(state, threads, thresholds, climbs);
        return;
    }
    let mut trial = Trial::default();
    each_round(thresholds, climbs, |parity, round| {
        let mut changed = false;
        for s in (parity..segs).step_by(2) {
            changed |= state.refine_in_place(&mut trial, s, round);
        }
        changed
    });
}

/// One round of [`descend`] as a phase sees it: its threshold, and whether each segment first
/// climbs ([`climb`]: the first round).
#[derive(Clone, Copy)]
struct Round {
    limit: f32,
    climb: bool,
}

/// The rounds of [`descend`]: `phase(parity, round)` refines the segments of one parity in the
/// round (true when it kept a try); the graded rounds, then rounds at 1 until one keeps nothing.
fn each_round(thresholds: &[f32], climbs: bool, mut phase: impl FnMut(usize, Round) -> bool) {
    let mut round = 0;
    loop {
        let limit = thresholds.get(round).copied().unwrap_or(1.0);
        let climb = round == 0 && climbs;
        round += 1;
        let mut changed = false;
        for parity in 0..2 {
            changed |= phase(parity, Round { limit, climb });
        }
        if !changed && round >= thresholds.len() {
            break;
        }
    }
}

/// Rungs a segment's climb goes up at most ([`climb`]): 2^(40/4), a thousand times its budget.
const CLIMB_RUNGS: usize = 40;

/// Segment `s`'s own ladder: its budget (the largest a-priori bound its widths give,
/// [`super::quantize::Layout::first_bound`]) raised a rung (2^(1/4)) at a time, every component
/// whose bound one bit lower is within the raised budget lowered, all of them at once
/// ([`Eval::lower_segment`]), while the segment holds within the limits (the clip's ladder's
/// verdict, whatever the round's threshold). Where a rung does not hold, the components that move
/// the joint where it failed (its own and its ancestors') stay where they are from then on, and
/// the rung is tried again without them; the climb ends when every component that could be
/// lowered stays. The whole clip's ladder stops where its hardest segment and joint do; most
/// segments and chains hold rungs more, which their tries one component at a time would otherwise
/// find one kept try (a subtree requantized and measured) at a time. Returns, per joint, the
/// largest ratio of error to limit at the segment's times and its position, after the last rung
/// kept; `None` when none was.
pub(super) fn climb(
    eval: &mut Eval,
    s: usize,
    worst: &[(f32, usize)],
) -> Option<Vec<(f32, usize)>> {
    // The times of the segment's largest errors, largest first, measured first; then where a
    // rung failed.
    let mut probes: Vec<(f32, usize)> = worst.iter().copied().filter(|w| w.0 > 0.0).collect();
    probes.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut probes: Vec<usize> = probes.into_iter().map(|w| w.1).collect();
    dedup_keep_order(&mut probes);
    probes.truncate(MAX_PROBES);
    let layout = eval.layout;
    let nc = layout.comps.len();
    let mut current = eval.bits[s * nc..(s + 1) * nc].to_vec();
    let mut stays: Vec<bool> = current.iter().map(|&b| b == 0).collect();
    // Each component's joint.
    let joint_of: Vec<usize> = (0..nc).map(|c| eval.joint[layout.comps[c].track]).collect();
    let step = std::f32::consts::SQRT_2.sqrt();
    let mut budget = (0..nc)
        .map(|c| layout.first_bound(s, c, current[c]))
        .fold(0.0f32, f32::max);
    let mut kept = None;
    let mut rungs = 0;
    let mut again = false;
    while rungs < CLIMB_RUNGS && stays.iter().any(|&x| !x) {
        if !again {
            budget *= step;
            rungs += 1;
        }
        again = false;
        let bits: Vec<u8> = (0..nc)
            .map(|c| {
                let mut b = current[c];
                while !stays[c] && b > 0 && layout.first_bound(s, c, b - 1) <= budget {
                    b -= 1;
                }
                b
            })
            .collect();
        if bits == current {
            continue;
        }
        let known = kept.as_deref().unwrap_or(worst);
        match eval.lower_segment(s, &bits, 1.0, (&probes, known)) {
            Ok(worst) => {
                kept = Some(worst);
                current = bits;
                for (c, &b) in current.iter().enumerate() {
                    stays[c] |= b == 0;
                }
            }
            Err((j, pos)) => {
                for c in 0..nc {
                    stays[c] |= eval.subtree[joint_of[c]].contains(&j);
                }
                if !probes.contains(&pos) {
                    probes.insert(0, pos);
                    probes.truncate(MAX_PROBES);
                }
                again = true;
            }
        }
    }
    kept
}

/// The state a refinement works on, and its bookkeeping per segment ([`descend`]).
struct State<'e, 'a> {
    eval: &'e mut Eval<'a>,
    blocked: Vec<bool>,
    probes: Vec<usize>,
    worst: Vec<(f32, usize)>,
}

impl State<'_, '_> {
    /// One round's tries on segment `s` of the state itself ([`refine_segment`]).
    fn refine_in_place(&mut self, trial: &mut Trial, s: usize, round: Round) -> bool {
        let (nc, nj) = (self.eval.layout.comps.len(), self.eval.nj);
        let own = s * nc..(s + 1) * nc;
        refine_segment(
            self.eval,
            None,
            trial,
            s,
            round,
            (
                &mut self.blocked[own.clone()],
                &mut self.probes[own],
                &mut self.worst[s * nj..(s + 1) * nj],
            ),
        )
    }

    /// One round's tries on segment `s` on `copy` (a copy of the state: [`Eval::empty_copy`]),
    /// reading the state: what they wrote and the segment's bookkeeping.
    fn refine_on_copy(
        &self,
        copy: &mut Eval,
        trial: &mut Trial,
        s: usize,
        round: Round,
    ) -> Refined {
        let (nc, nj) = (self.eval.layout.comps.len(), self.eval.nj);
        let own = s * nc..(s + 1) * nc;
        let mut b = self.blocked[own.clone()].to_vec();
        let mut p = self.probes[own].to_vec();
        let mut w = self.worst[s * nj..(s + 1) * nj].to_vec();
        let kept = refine_segment(
            copy,
            Some(self.eval),
            trial,
            s,
            round,
            (&mut b, &mut p, &mut w),
        );
        (s, kept.then(|| copy.segment_state(s)), b, p, w)
    }

    /// Writes what refining a segment on a copy gave back; true when it kept a try.
    fn store(&mut self, (s, written, b, p, w): Refined) -> bool {
        let (nc, nj) = (self.eval.layout.comps.len(), self.eval.nj);
        let own = s * nc..(s + 1) * nc;
        self.blocked[own.clone()].copy_from_slice(&b);
        self.probes[own].copy_from_slice(&p);
        self.worst[s * nj..(s + 1) * nj].copy_from_slice(&w);
        match written {
            Some(written) => {
                self.eval.store_segment(&written);
                true
            }
            None => false,
        }
    }
}

/// Spins of a waiting thread before it starts yielding its core.
const SPINS: u32 = 1 << 12;

/// Waits until `ready`: spinning first (a phase of the refinement is tens to hundreds of
/// microseconds, and a thread put to sleep takes about as long to wake), then yielding.
fn wait_until(ready: impl Fn() -> bool) {
    let mut spins = 0u32;
    while !ready() {
        if spins < SPINS {
            spins += 1;
            std::hint::spin_loop();
        } else {
            std::thread::yield_now();
        }
    }
}

/// The phases of a side-by-side refinement: each phase is the segments of one parity at one
/// round's threshold; any thread claims the next segment until none is left.
struct Phases {
    /// The phase's number (high 32 bits) and the next segment to claim (low 32 bits).
    cursor: AtomicU64,
    /// The current phase: its number, segments and threshold.
    plan: RwLock<(u64, Vec<usize>, Round)>,
    /// Per segment of the current phase: what refining it gave, and how many are done.
    results: Mutex<Vec<Option<Refined>>>,
    done: AtomicUsize,
    /// The refinement is over (the helpers return), or a helper panicked.
    over: AtomicBool,
    failed: AtomicBool,
    /// Per segment: how long its last refinement took (nanoseconds): the next phase hands out
    /// the longest first, so that one long segment does not start last. (The order changes no
    /// result: each segment reads only the state, and what they wrote is stored in segment
    /// order.)
    cost: Vec<AtomicU64>,
}

impl Phases {
    /// Claims the next segment of phase `number` (`count` segments), if any is left.
    fn claim(&self, number: u64, count: usize) -> Option<usize> {
        let mut v = self.cursor.load(Ordering::Acquire);
        loop {
            let at = (v & u64::from(u32::MAX)) as usize;
            if v >> 32 != number || at >= count {
                return None;
            }
            match self
                .cursor
                .compare_exchange_weak(v, v + 1, Ordering::AcqRel, Ordering::Acquire)
            {
                Ok(_) => return Some(at),
                Err(now) => v = now,
            }
        }
    }

    /// Refines the segments of phase `number` this thread claims, on its slot.
    fn work(
        &self,
        number: u64,
        segments: &[usize],
        round: Round,
        state: &RwLock<State>,
        slot: &Mutex<(Eval, Trial)>,
    ) {
        while let Some(i) = self.claim(number, segments.len()) {
            let started = std::time::Instant::now();
            let refined = {
                let state = state.read().unwrap_or_else(PoisonError::into_inner);
                let mut slot = slot.lock().unwrap_or_else(PoisonError::into_inner);
                let (copy, trial) = &mut *slot;
                state.refine_on_copy(copy, trial, segments[i], round)
            };
            let took = u64::try_from(started.elapsed().as_nanos()).unwrap_or(u64::MAX);
            self.cost[segments[i]].store(took, Ordering::Relaxed);
            self.results.lock().unwrap_or_else(PoisonError::into_inner)[i] = Some(refined);
            self.done.fetch_add(1, Ordering::Release);
        }
    }
}

/// Marks the refinement failed if the thread holding it unwinds (the others stop waiting).
struct FailOnUnwind<'p>(&'p AtomicBool);

impl Drop for FailOnUnwind<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.store(true, Ordering::Release);
        }
    }
}

/// [`descend`] with each parity's segments refined on copies of the state by `threads` threads
/// at once (the calling thread and helpers that stay with the refinement to its end, so that no
/// phase waits for a thread to be woken), what they wrote copied back in segment order. The
/// calling thread never waits for a helper to start: it claims segments too, and does them all
/// if no helper comes, so a pool busy elsewhere only makes it slower.
fn side_by_side(state: State, threads: usize, thresholds: &[f32], climbs: bool) {
    let segs = state.eval.layout.seg_count;
    let slots: Vec<Mutex<(Eval, Trial)>> = (0..threads)
        .map(|_| Mutex::new((state.eval.empty_copy(), Trial::default())))
        .collect();
    let state = RwLock::new(state);
    let phases = Phases {
        cursor: AtomicU64::new(0),
        plan: RwLock::new((
            0,
            Vec::new(),
            Round {
                limit: 1.0,
                climb: false,
            },
        )),
        results: Mutex::new(Vec::new()),
        done: AtomicUsize::new(0),
        over: AtomicBool::new(false),
        failed: AtomicBool::new(false),
        cost: (0..segs).map(|_| AtomicU64::new(0)).collect(),
    };
    let helper = |slot: &Mutex<(Eval, Trial)>| {
        let _fail = FailOnUnwind(&phases.failed);
        let mut seen = 0u64;
        loop {
            wait_until(|| {
                phases.over.load(Ordering::Acquire)
                    || phases.cursor.load(Ordering::Acquire) >> 32 != seen
            });
            if phases.over.load(Ordering::Acquire) {
                return;
            }
            let (number, segments, round) = phases
                .plan
                .read()
                .unwrap_or_else(PoisonError::into_inner)
                .clone();
            seen = number;
            phases.work(number, &segments, round, &state, slot);
        }
    };
    rayon::scope(|scope| {
        for slot in &slots[1..] {
            let helper = &helper;
            scope.spawn(move |_| helper(slot));
        }
        let _over = OverOnDrop(&phases.over);
        let mut number = 0u64;
        each_round(thresholds, climbs, |parity, round| {
            let mut segments: Vec<usize> = (parity..segs).step_by(2).collect();
            segments.sort_by_key(|&s| std::cmp::Reverse(phases.cost[s].load(Ordering::Relaxed)));
            let count = segments.len();
            number += 1;
            *phases
                .results
                .lock()
                .unwrap_or_else(PoisonError::into_inner) = (0..count).map(|_| None).collect();
            phases.done.store(0, Ordering::Release);
            *phases.plan.write().unwrap_or_else(PoisonError::into_inner) =
                (number, segments.clone(), round);
            phases.cursor.store(number << 32, Ordering::Release);
            phases.work(number, &segments, round, &state, &slots[0]);
            wait_until(|| {
                phases.done.load(Ordering::Acquire) == count
                    || phases.failed.load(Ordering::Acquire)
            });
            assert!(
                !phases.failed.load(Ordering::Acquire),
                "a refinement helper panicked"
            );
            let mut results: Vec<Refined> = std::mem::take(
                &mut *phases
                    .results
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner),
            )
            .into_iter()
            .flatten()
            .collect();
            results.sort_by_key(|r| r.0);
            let mut state = state.write().unwrap_or_else(PoisonError::into_inner);
            let mut changed = false;
            for refined in results {
                changed |= state.store(refined);
            }
            changed
        });
    });
}

/// Tells the helpers the refinement is over when the calling thread leaves it (normally or not).
struct OverOnDrop<'p>(&'p AtomicBool);

impl Drop for OverOnDrop<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Release);
    }
}

/// One round's tries on segment `s`, component by component (`blocked`, `probes` and `worst`: the
/// segment's entries); true when one was kept. With `from`, `eval` is a copy of that state
/// ([`Eval::empty_copy`]): the tries read `from` until one is kept, which first loads the
/// segment's neighbourhood into the copy ([`Eval::load_segment`]), and the rest read and write the
/// copy; a segment where nothing is kept copies nothing back. With `climb` the segment first
/// climbs ([`climb`], on the copy loaded first).
fn refine_segment(
    eval: &mut Eval,
    from: Option<&Eval>,
    trial: &mut Trial,
    s: usize,
    Round {
        limit,
        climb: climbs,
    }: Round,
    (blocked, probes, worst): (&mut [bool], &mut [usize], &mut [(f32, usize)]),
) -> bool {
    let nc = eval.layout.comps.len();
    let mut kept = false;
    // The copy holds the segment's neighbourhood (the tries read it instead of `from`).
    let mut loaded = from.is_none();
    if climbs {
        if let Some(state) = from {
            eval.load_segment(state, s);
            loaded = true;
        }
        if let Some(w) = climb(eval, s, worst) {
            kept = true;
            worst.copy_from_slice(&w);
        }
    }
    for (c, (blocked, probe)) in blocked.iter_mut().zip(probes.iter_mut()).enumerate() {
        let i = s * nc + c;
        let current: &Eval = match from {
            Some(state) if !loaded => state,
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
            if let Some(state) = from.filter(|_| !loaded) {
                eval.load_segment(state, s);
                loaded = true;
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

/// `v` without its repeated entries, the first of each kept in place.
fn dedup_keep_order(v: &mut Vec<usize>) {
    let mut seen = Vec::with_capacity(v.len());
    v.retain(|x| {
        let new = !seen.contains(x);
        if new {
            seen.push(*x);
        }
        new
    });
}
