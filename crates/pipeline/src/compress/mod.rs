//! Error-bounded keyframe compression of clips (the encoder of [`sinew_core::compressed`]) and the
//! error metric it is bounded by.
//!
//! # The error metric
//!
//! For every joint and every key time of the source clip, three points are attached rigidly to the
//! joint, one along each of its local axes, `error_distance` model units away from it in the bind pose.
//! Each point is carried to model space through the whole chain of parents, once with the source
//! clip and once with the compressed clip; the error of that joint at that time is the largest of the
//! three distances. Joints a clip does not drive take their bind values (so they move with their
//! parents). Without a skeleton every track is a root of its own.
//!
//! Both are measured about the source's *anchor* of each root at that time: the root, or, down the
//! chain of single children from it while the joint is not animated, the first that is or that
//! branches (a capture's `Hips` under a static `Root`). The anchor's model transform has the
//! source's anchor position at that time taken off its translation, in both computations, so its
//! subtree is carried through the chain near the origin. In exact arithmetic the distances are the
//! same as in model space; in f32 they are without the rounding of coordinates far from the origin,
//! which is not the encoding's (a capture in centimetres 6.7 m out: one f32 step of a coordinate is
//! 6e-5 there, and eight of them were half of a 0.001 tolerance). The anchor's own translation is
//! compared exactly: the runtime's decoded value less the source's. The encoder still allows each
//! joint the tolerance less 8 f32 steps of its error points' largest coordinate (now about the
//! anchor), so that another f32 computation of the same measure stays within it
//! (docs/performance.md, session 29).
//!
//! # What the encoder does, in order
//!
//! 1. Channels that one value (their middle value, or the bind value when a skeleton is given and the
//!    clip is not additive; the identity difference for additive clips) reproduces within a quarter of
//!    the tolerance are stored as constants or not at all; a channel the source already holds
//!    constant becomes a bind channel when the bind value reproduces it likewise.
//! 2. Keys that linear interpolation between their neighbours reproduces are dropped (whole keys, so
//!    the runtime still reads one record per key: time-major), once for each key budget of
//!    `KEY_BUDGETS` (fractions of the tolerance; the rest is left to quantization).
//! 3. Every remaining animated channel is quantized: rotations as three components plus the 2-bit
//!    index of the dropped one (the same index from key to key while that component stays large, so
//!    the stored components do not jump), translations and scales as three components; each
//!    component is range-reduced over the clip and over segments of keys. Rotations are quantized
//!    with *chain compensation*: parents first, each joint storing the local rotation that, under its
//!    parent's quantized rotation, gives its source model-space rotation, so orientation errors do not
//!    accumulate down the chain (when every scale of the source poses is positive and uniform, so that
//!    model-space rotations are products of local ones; otherwise, or if nothing meets the limits
//!    with it, without compensation).
//! 4. Bit widths, per component and segment: first the largest uniform error budget whose a-priori
//!    widths measure within the limits (on a ladder of factors 2^(1/4), from half the tolerance for
//!    the first set of kept keys and from the budget the one before reached for the next), then
//!    one bit at a time off each component of each segment
//!    for as long as the measured error (kept up to date incrementally) stays within the limits.
//!    On the whole source (not on its frames or thinned copy, whose result is checked at times
//!    the search does not measure), each segment first climbs a ladder of its own: its budget
//!    raised by 2^(1/4) at a time, its components' a-priori widths lowered together while the
//!    segment holds within the limits; where a rung does not, the components of the joint where
//!    it failed and of its ancestors stay, and the rung is tried again without them (the clip's
//!    ladder stops at its hardest segment and joint; the rest climb further), so that the first
//!    round's tries start nearer their result (docs/performance.md, session 34). `Fast` skips
//!    this step on a clip of more than `FAST_REFINED_VOLUME` source times x joints: its work grows
//!    with the times measured, and long captures keep the first widths (session 36); there the
//!    layout step 5 chooses, when the ladder measured another, is quantized at the ladder's
//!    budget and checked by the runtime's sampler alone (its own ladder from that budget only
//!    where that check fails).
//! 5. Step 3 runs for every set of kept keys from step 2 on one segment length (16); its budget
//!    gives every other segment length (32, and for short clips 64 and lengths that split the clip
//!    into 1 to 4 equal segments) its a-priori widths and so its size, without measuring; the
//!    smallest is measured from that budget and gets step 4's refinement, and the result (or, if
//!    the runtime sampler does not measure it within the limits, the unrefined one) is kept.
//!
//! Steps 1 to 5 first run on the source's *frames*: its key times on the grid of its sample rate,
//! when those are at most half of its times (a glTF file keyed at a rate: the file's own keys,
//! the importer's added times between them left out), less the frames that linear interpolation
//! between the others reproduces within 1% of the tolerance when that is a fifth of them or more
//! (then at 99% of the tolerance, as the thinned source below). Not when the frames themselves,
//! interpolated as the runtime interpolates them, leave some joint's limit at a time between them
//! (then nothing keyed on frames alone holds). The search gets 99% of the tolerance (`FRAME_SHARE`)
//! and its result is measured at every source time; if it does not hold and the source does not
//! thin (below: then the thinned source is searched instead), steps 1 to 5 run with the frames
//! as the only candidate keys and every source time measured, whose result holds wherever one is
//! found (for `Max`, each is one of its candidates); so too where the frames are more than half
//! of the times but at most four fifths (no search on the frames alone then). Rounds on the
//! frames and the times where the last one failed (sessions 30-34) moved the failures to other
//! times between frames and, on some captures, failed four times over before the whole source
//! was searched at twice the bytes (docs/performance.md, session 35). A search on every imported
//! time spends part of the
//! tolerance on key reduction at the added times, where the runtime's nlerp between frames parts
//! from the file's slerp, and keeps keys between frames and more bits; on motion captures exported
//! to glTF the result on the frames, checked at the added times, is 0.54-1.02x as large, 9-14%
//! smaller in all (docs/performance.md, session 30).
//!
//! Otherwise steps 1 to 5 run on a *thinned* source when that leaves out at least a fifth of its key
//! times: the source without the times where it is within 1% of the tolerance of linear
//! interpolation between the times kept (key reduction of the source itself; importers add key
//! times where a file's own interpolation needs them far more finely than any compression
//! tolerance: a glTF slerp to 2e-6 rad), with 99% of the tolerance. The result is kept only if it
//! holds at every time of the whole source (measured as the final check of step 5 measures it);
//! otherwise the search runs again on the whole source. So the tolerance holds at every source key
//! time whichever way was taken, and the search measures fewer times where the source has more
//! than it needs.
//!
//! `CompressOptions::effort` ([`Effort`]) sets how hard steps 2 and 5 search: `Fast` reduces keys
//! at one budget of the three and refines its candidate without the refinement's graded first
//! rounds, `Default` with all three and those rounds, `Max` also every
//! layout measured, more key budgets and segment lengths, and the whole source as well as the
//! thinned one, with the default's result among its candidates (so never a larger result).
//!
//! # Speed, and the same bytes at any thread count
//!
//! - The error is kept up to date incrementally (`eval.rs`): a tentative width change (`trial.rs`)
//!   requantizes only its segment's keys of the joint's subtree, and re-measures only the source
//!   times that read the segment, time by time as its keys are requantized, stopping at the first
//!   time over the round's threshold (a failed try costs a fraction of a full one; the decision is
//!   the one a whole pass would make); the time where a component's try last failed in a segment
//!   is measured first next time, then the times where the joints it can move have their largest
//!   errors in the segment (per segment and joint, kept up to date by the kept tries), up to four
//!   times first in all. First-width checks likewise quantize keys as the times reach
//!   them, and check first up to eight recent times where checks failed or passing ones had
//!   their largest error (in this ladder or the previous layouts').
//! - Independent work runs on rayon: the clips of a scene, the key reductions of a clip, its
//!   layouts, the next two rungs of a first-width ladder, and `Max`'s refinements of several
//!   candidates; a long clip's state (from 16,384 joint-times) is built a block of source times at
//!   a time (256, doubling after each passing block), the block's keys and then its times in
//!   chunks side by side, each chunk of keys writing its own range of the state. The default's
//!   single refinement spreads its own work: tries on segments two or more apart read and write
//!   disjoint keys and times, so each round refines the even segments side by side, each on a
//!   copy of the state that holds what it reads, then the odd ones, and copies back what each
//!   wrote, in segment order. The calling thread and helpers that stay for the whole refinement
//!   claim the segments of each phase, longest first by their last refinement's time (a pool
//!   thread woken per phase could take milliseconds to start). Every result is collected in a
//!   fixed order and the choices are the sequential ones, so the output does not depend on the
//!   thread count (tests compare 1, 2 and 3 threads, and the side-by-side schedule against one try
//!   at a time).
//! - What one step computes is not computed again by the next: the channel simplification tries a
//!   constant by replacing that channel in the poses it holds (the runtime sampler's, bit for bit)
//!   and starts from the source's poses the search sampled; the key reductions of every budget
//!   start from the poses it leaves.
//!
//! The limits are per joint: the tolerance less a margin for f32 noise (a few ulps of the joint's
//! model-space coordinates), so that an independent measurement against the source data also stays
//! within the tolerance on models far from the origin.
//!
//! Key times are kept as the source has them (no resampling), so every source key is honoured in time.

#[cfg(test)]
mod anchor_tests;
#[cfg(test)]
mod climb_tests;
mod eval;
#[cfg(test)]
mod fast_tests;
mod frames;
#[cfg(test)]
mod frames_tests;
mod metric;
mod options;
mod quantize;
mod reduce;
#[cfg(test)]
mod reduce_tests;
mod refine;
#[cfg(test)]
mod report_tests;
mod search;
mod segment;
#[cfg(test)]
mod state_tests;
#[cfg(test)]
mod tests;
mod trial;

pub use metric::{measure, skeleton_extent};
pub use options::{
    ClipCompressionReport, CompressOptions, Effort, KeptPlain, DEFAULT_RELATIVE_DISTANCE,
    DEFAULT_RELATIVE_TOLERANCE, PARALLEL_VOLUME,
};
pub use search::compress_clip;
