//! The search on a source's *frames* (a file's own keys on the grid of its sample rate, the
//! importer's added times left out): the frames found, the search on them alone, and the search
//! with them as the only candidate keys (the module docs of [`super`], step 5's paragraphs on
//! frames).

use super::eval::Sampled;
use super::metric::{errors_against, holds_against, joint_limits, within_limits, Rig};
use super::reduce::reduce_keys;
use super::reduce::Work;
use sinew_core::glam::Vec3;
use sinew_core::{Clip, Transform};

/// The fraction of the tolerance the search on the source's frames gets ([`frames_first`]): the
/// rest is margin for the times between frames, which it does not measure.
pub(super) const FRAME_SHARE: f32 = 0.99;

/// The indices of `source`'s *frames*: its key times on the grid of its sample rate (from its
/// first time), the first and last time always among them; `None` when they are more than half
/// of its times. Importers add times between a file's own keys where its interpolation
/// needs them (a glTF slerp to within 2e-6 rad), and a file keyed at a rate has its own keys on
/// that grid, the added ones off it: a time is on the grid within a thousandth of a frame (the
/// importers add at most 256 times to a frame; exporters write frame times a few f32 steps from
/// the nearest float, 8 on Bandai Namco's captures through sinew's own export) or 16 f32 steps of
/// the time, whichever is larger. Either way of missing (a frame left off, an added time taken as
/// one) costs only work: every result is measured at every time.
///
/// Why at most half: where a file's own interpolation needs few added times, the search on every
/// time spends little on them, and a round on the frames costs most of a whole search
/// (Boxing_Toes exported to glTF, 3,069 frames of 4,862 times: three rounds of 350 ms where the
/// whole search takes 530, for 9% fewer bytes). On the 70 captures measured in session 30, at most
/// four fifths (as for the thinned source) gave 10.3% fewer bytes in 1.01x the time, at most half
/// 8.3% fewer in 0.91x (docs/performance.md).
pub(super) fn frames(source: &Clip) -> Option<Vec<usize>> {
    frames_within(source, (1, 2))
}

/// [`frames`] when they are at most `num / den` of the times (`None` otherwise).
pub(super) fn frames_within(source: &Clip, (num, den): (usize, usize)) -> Option<Vec<usize>> {
    let times = source.times();
    let mut rate = f64::from(source.sample_rate());
    let (&first, &last) = (times.first()?, times.last()?);
    if !(rate.is_finite() && rate > 0.0) {
        return None;
    }
    // The grid's own rate: the median step of the times within a twentieth and then a hundredth
    // of a frame of the grid (each time's step from the first time over its frame number). A
    // file's rate is rounded to the nominal one when within 1%, and a BVH's frame time of
    // 0.0083333 s puts the last frames of a 23 s capture a hundredth of a frame off the 120 Hz
    // grid, where only 253 of cmu_01_01's 2,752 frames were found on it (docs/performance.md,
    // session 35); the importer's added times (halves to sixteenths of a frame) fall outside.
    let nominal = rate;
    for within in [0.05, 0.01] {
        let mut steps: Vec<f64> = times
            .iter()
            .filter_map(|&t| {
                let dt = f64::from(t) - f64::from(first);
                let x = dt * rate;
                let k = x.round();
                (k >= 1.0 && (x - k).abs() <= within).then_some(dt / k)
            })
            .collect();
        if steps.is_empty() {
            break;
        }
        steps.sort_by(f64::total_cmp);
        let step = steps[steps.len() / 2];
        if step > 0.0 && (1.0 / step / nominal - 1.0).abs() < 0.01 {
            rate = 1.0 / step;
        }
    }
    let on_grid = |t: f32| {
        let x = (f64::from(t) - f64::from(first)) * rate;
        let off = (x - x.round()).abs() / rate;
        off <= (1e-3 / rate).max(16.0 * f64::from(f32::EPSILON) * f64::from(t.abs()))
    };
    let kept: Vec<usize> = times
        .iter()
        .enumerate()
        .filter(|&(_, &t)| t == first || t == last || on_grid(t))
        .map(|(i, _)| i)
        .collect();
    (kept.len() * den <= times.len() * num).then_some(kept)
}

/// The search on the source's [`frames`] alone at [`FRAME_SHARE`] of the tolerance, kept only where
/// its result holds at every source time. `None` at once when [`frames`] finds none to search, or
/// when the frames themselves, interpolated as the runtime does, leave some joint's limit at a
/// time between them (nothing keyed on the frames alone can then hold there); `None` when the
/// result does not hold ([`frame_keys`] or the thinned source is searched next).
///
/// Why: a search on every imported time spends part of the tolerance on key reduction at the
/// added times, where nlerp between frames parts from the file's slerp, and so keeps keys between
/// frames and more bits; measured on motion captures exported to glTF, the result on the frames,
/// checked at the added times, is 0.54-1.02x as large (14% smaller in all), in 0.17-0.5x the time
/// (docs/performance.md, session 30). The guarantee is the same: within the tolerance at every
/// imported key time.
///
/// Frames that linear interpolation between the frames kept reproduces within [`THINNING`] x the
/// tolerance are left out first, as [`thinned`] leaves out times (when that is at least a fifth of
/// them), and the fraction is then of the rest of the tolerance: a file keyed on every step of a
/// fine grid (sinew's own export of ninja.ms3d: 8,627 frames on a 1,600 Hz grid of 17,459
/// imported times, 3,998 after this) was searched on all of them, 2x the time of the thinned
/// search before the frames (docs/performance.md, session 31).
/// `search_at`: the search on a plain clip, sampled, at a tolerance.
pub(super) fn frames_first(
    source: &Clip,
    rig: &Rig,
    src: &[Vec<[Vec3; 3]>],
    origins: &[Vec3],
    tolerance: f32,
    search_at: impl Fn(&Clip, &Sampled, f32) -> Option<Found>,
) -> Option<Found> {
    let times = source.times();
    let limits = joint_limits(src, rig.skeleton.len(), tolerance);
    let (_, mut clip) = holding(source, &frames(source)?, (rig, src, origins), &limits)?;
    let mut sampled = Sampled::new(rig, &clip, clip.times());
    // Frames that linear interpolation between their neighbours reproduces (an export that keys
    // a curve densely on a fine grid) are left out as [`thinned`] leaves out times, for the same
    // share of the tolerance.
    let mut share = 1.0;
    let thin_frames = thinned(
        &clip,
        rig,
        &sampled.points,
        &sampled.origins,
        Some(&sampled.poses),
        tolerance,
    );
    if let Some((_, thin_clip)) = thin_frames {
        clip = thin_clip;
        sampled = Sampled::new(rig, &clip, clip.times());
        share = 1.0 - THINNING;
    }
    let (size, c, _) = search_at(&clip, &sampled, tolerance * FRAME_SHARE * share)?;
    let errors = errors_against(rig, src, origins, &c, times);
    within_limits(&errors, &limits).then_some((size, c, errors))
}

/// The search with the source's frames (as [`frames`] finds them, when they are at most four
/// fifths of its times) as its only candidate keys, measured at every source time: its result
/// holds wherever it is found, and keeps no key between frames (the file's own keys, where the
/// search on every time spends tolerance on times the importer added). `None` without frames, or
/// when the frames, interpolated as the runtime does, leave some joint's limit at a time between
/// them (then nothing keyed on frames holds), or when nothing meets the limits.
///
/// Four fifths, not half as for [`frames_first`]: this search measures every time whatever the
/// frames' share (the half bounds what a search on the frames alone costs), and where more than
/// four fifths of the times are frames it differs little from the search on every time (the
/// share [`thinned`] asks of the times it leaves out). Boxing_Toes.bvh exported to glTF (3,069
/// frames of 4,862 times) 339,356 -> 305,176 bytes at 0.001 @ 0.1 in 0.71x the time
/// (docs/performance.md, session 35).
///
/// Why: after the search on the frames alone does not hold (the times between frames it does not
/// measure), searching it again with the times where it failed moves the failures to other times
/// between frames (a key dropped or requantized changes the runtime's interpolation across a
/// whole interval); on captures at 0.001 @ 0.1 the rounds of sessions 30-34 failed four times
/// over on some and the whole source was searched, at 1.5-2.5x the bytes of this search, which
/// costs about what the whole source's does (docs/performance.md, session 35).
/// `whole`: the source sampled at its times.
/// `search_keys`: the search on every time of `source` with a set of candidate keys.
pub(super) fn frame_keys(
    (source, whole): (&Clip, &Sampled),
    rig: &Rig,
    tolerance: f32,
    search_keys: impl FnOnce(&Work) -> Option<Found>,
) -> Option<Found> {
    let (src, origins) = (&*whole.points, whole.origins.as_slice());
    let limits = joint_limits(src, rig.skeleton.len(), tolerance);
    let kept = frames_within(source, (4, 5))?;
    let (work, _) = holding(source, &kept, (rig, src, origins), &limits)?;
    search_keys(&work)
}

/// `source` keyed at its times `kept` alone, as a work and as a plain clip, when that clip,
/// interpolated as the runtime does, is within `limits` at every source time (`src`, `origins`:
/// the source's error points and their origins); `None` otherwise (nothing keyed on those times
/// alone can hold then).
fn holding(
    source: &Clip,
    kept: &[usize],
    (rig, src, origins): (&Rig, &[Vec<[Vec3; 3]>], &[Vec3]),
    limits: &[f32],
) -> Option<(Work, Clip)> {
    let mut work = Work::from_plain(source);
    work.keep(kept);
    let clip = work.plain(source)?;
    holds_against(rig, src, origins, &clip, source.times(), limits).then_some((work, clip))
}

/// A result of the search (`super::search`): its record size, the clip, and its errors at every
/// time of the source it was searched on (time-major, one per joint).
pub(super) type Found = (usize, Clip, Vec<f32>);

/// Fraction of the tolerance within which the thinned source of [`thinned`] follows the source
/// (the search on it gets the rest). At 1% the corpus's clips change by +0.02% in total at
/// 0.001 @ 0.1 and -0.3% at the default tolerance; at 5% some thinned results did not hold at the
/// times left out, and at 2% one clip grew by 12% (docs/performance.md).
pub(super) const THINNING: f32 = 0.01;

/// The source without the key times where it is within [`THINNING`] x the tolerance of linear
/// interpolation between the times kept (key reduction of the source itself, whole keys), when that
/// leaves out at least a fifth of its times, with the indices of the times kept; else `None`.
/// Importers add times where a file's own interpolation needs them to a precision far finer than a
/// compression tolerance (a glTF slerp to within 2e-6 rad: Fox's Walk has 157 key times for 18
/// glTF keys), and the search's cost grows with the times it measures. A result of the search on
/// the thinned source is kept only if it holds at every time of the whole source.
/// `src`, `origins`: the source's error points at its times and their origins
/// ([`Rig::source_points`]); `poses`: its poses at its times, when known.
pub(super) fn thinned(
    source: &Clip,
    rig: &Rig,
    src: &[Vec<[Vec3; 3]>],
    origins: &[Vec3],
    poses: Option<&[Vec<Transform>]>,
    tolerance: f32,
) -> Option<(Vec<usize>, Clip)> {
    let mut work = Work::from_plain(source);
    let kept = reduce_keys(
        &work,
        source,
        rig,
        src,
        origins,
        poses,
        tolerance * THINNING,
    );
    if kept.len() * 5 > source.times().len() * 4 {
        return None;
    }
    work.keep(&kept);
    Some((kept, work.plain(source)?))
}
