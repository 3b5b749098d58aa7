//! Unit tests of the search on a clip's frames ([`super::frames::frames`] and the search that
//! starts from them).

#![allow(clippy::unwrap_used)]
use super::eval::Sampled;
use super::frames::*;
use super::metric::*;
use super::options::*;
use super::reduce::Work;
use super::search::*;
use super::tests::{chain, densified_swing, on_threads};
use sinew_core::glam::{Quat, Vec3};
use sinew_core::{Clip, Curve, Skeleton, TrackCurves};

/// Every `extra + 1`-th index of a densified clip of `keys` keys.
fn frame_indices(keys: usize, extra: usize) -> Vec<usize> {
    (0..keys).map(|k| k * (extra + 1)).collect()
}

/// `clip` compressed at 0.001 @ 0.1, checked within the tolerance at every one of its times by
/// [`measure`] (which the report's max error is).
fn compressed_within(
    clip: &Clip,
    skeleton: &Skeleton,
) -> (CompressOptions, Clip, ClipCompressionReport) {
    let options = CompressOptions {
        tolerance: Some(0.001),
        error_distance: Some(0.1),
        ..CompressOptions::default()
    };
    let (c, r) = compress_clip(clip, Some(skeleton), &options);
    assert!(c.is_compressed());
    let worst = measure(clip, &c, Some(skeleton), 0.1)
        .into_iter()
        .fold(0.0f32, f32::max);
    assert!(worst <= 0.001, "error {worst}");
    assert_eq!(r.max_error, worst);
    (options, c, r)
}

/// The search on every time of `clip` at `tol` (compensated, bind values allowed), as `search`
/// runs it on the frames and, when nothing searched first holds, on the whole source.
fn search_on(
    clip: &Clip,
    sampled: Option<&Sampled>,
    rig: &Rig,
    tol: f32,
    options: &CompressOptions,
) -> Option<Found> {
    compress_work(
        &mut Work::from_plain(clip),
        clip,
        sampled,
        rig,
        tol,
        true,
        options,
        true,
        false,
    )
}

/// [`frames_first`] on `clip` at 0.001 with the search `search` runs ([`search_on`]), shown the
/// frames, tolerance and search number first (`look`); with the number of times each search
/// searched.
fn searched_on_frames(
    clip: &Clip,
    skeleton: &Skeleton,
    options: &CompressOptions,
    look: impl Fn(&Clip, f32, usize),
) -> (Option<Found>, Vec<usize>) {
    let (rig, src, origins) = rig_points(clip, skeleton);
    let seen = std::cell::RefCell::new(Vec::new());
    let found = frames_first(clip, &rig, &src, &origins, 0.001, |frames, sampled, tol| {
        let round = seen.borrow().len();
        look(frames, tol, round);
        seen.borrow_mut().push(frames.times().len());
        search_on(frames, Some(sampled), &rig, tol, options)
    });
    (found, seen.into_inner())
}

/// [`search_on`] every time of `clip` at 0.001.
fn whole_search(clip: &Clip, rig: &Rig, options: &CompressOptions) -> Found {
    search_on(clip, None, rig, 0.001, options).unwrap()
}

/// `clip`'s rig at 0.1 and its error points and origins at its own times.
fn rig_points(clip: &Clip, skeleton: &Skeleton) -> (Rig, Vec<Vec<[Vec3; 3]>>, Vec<Vec3>) {
    let rig = Rig::new(clip, Some(skeleton), 0.1).unwrap();
    let poses = rig.poses(clip, clip.times());
    let (src, origins) = rig.source_points(&poses);
    (rig, src, origins)
}

/// One joint turning about Y by its time in radians, keyed at `times`, at sample rate `rate`.
fn turning_at(times: &[f32], rate: f32) -> Clip {
    let tracks = vec![TrackCurves {
        joint: "j0".into(),
        rotation: Curve::new(
            times.to_vec(),
            times.iter().map(|&t| Quat::from_rotation_y(t)).collect(),
        ),
        ..Default::default()
    }];
    let last = *times.last().unwrap();
    Clip::from_curves("turning", last, rate, false, false, tracks)
        .unwrap()
        .to_plain()
}

#[test]
fn the_frames_are_the_key_times_on_the_sample_rate_grid() {
    let skeleton = chain(6, 0.3);
    let dense = densified_swing(&skeleton, 31, 7).to_plain();
    assert_eq!(dense.times().len(), 241);
    assert_eq!(frames(&dense), Some(frame_indices(31, 7)));
    // A clip keyed at its rate only: nothing to leave out.
    let plain = densified_swing(&skeleton, 31, 0).to_plain();
    assert_eq!(plain.times().len(), 31);
    assert_eq!(frames(&plain), None);
    // Frame times a few f32 steps from k / 30 (as exporters write them) are frames still.
    let times: Vec<f32> = (0..31)
        .flat_map(|k| {
            let t = k as f32 / 30.0;
            let off = f32::from_bits(t.to_bits() + 8);
            let between = |q: f32| t + q / 30.0;
            [
                if k == 0 { t } else { off },
                between(0.25),
                between(0.5),
                between(0.75),
            ]
        })
        .take(121)
        .collect();
    let clip = turning_at(&times, 30.0);
    let found = frames(&clip).unwrap();
    assert_eq!(found, (0..31).map(|k| 4 * k).collect::<Vec<_>>());
    // Frames that are more than half of the times are not searched first; at most four fifths,
    // they are the candidate keys of `frame_keys`.
    let half = densified_swing(&skeleton, 31, 1).to_plain();
    assert_eq!(half.times().len(), 61);
    assert_eq!(frames(&half), None);
    assert_eq!(frames_within(&half, (4, 5)), Some(frame_indices(31, 1)));
    assert_eq!(frames_within(&half, (1, 2)), None);
    assert_eq!(frames_within(&plain, (4, 5)), None);
}

#[test]
fn frames_are_found_on_a_grid_a_little_off_the_nominal_rate() {
    // A BVH's frame time of 0.0083333 s read as 120 Hz: frame 2,400 is 0.008 frames off the
    // 120 Hz grid (beyond a thousandth of a frame). An added time halfway between every second
    // pair of frames, as the importer adds them.
    let mut times = Vec::new();
    let mut frame_at = Vec::new();
    for k in 0..2401u32 {
        frame_at.push(times.len());
        times.push(k as f32 * 0.0083333);
        if k % 2 == 0 && k < 2400 {
            times.push((k as f32 + 0.5) * 0.0083333);
        }
    }
    let clip = turning_at(&times, 120.0);
    assert_eq!(clip.sample_rate(), 120.0);
    assert_eq!(clip.times().len(), 3601);
    assert_eq!(frames_within(&clip, (4, 5)), Some(frame_at));
}

#[test]
fn frames_as_keys_hold_where_they_are_more_than_half_of_the_times() {
    let skeleton = chain(6, 0.3);
    // 31 frames of 61 times: no search on the frames alone, but the frames as candidate keys.
    let clip = densified_swing(&skeleton, 31, 1).to_plain();
    let (rig, src, _) = rig_points(&clip, &skeleton);
    let whole = Sampled::new(&rig, &clip, clip.times());
    let options = CompressOptions::peers();
    let (_, c, errors) = frame_keys((&clip, &whole), &rig, 0.001, |w| {
        compensated_first(w, (&clip, Some(&whole), &rig, 0.001), true, &options, true)
    })
    .unwrap();
    let frame_times: Vec<f32> = frame_indices(31, 1)
        .into_iter()
        .map(|i| clip.times()[i])
        .collect();
    assert!(c.times().iter().all(|t| frame_times.contains(t)));
    let limits = joint_limits(&src, skeleton.len(), 0.001);
    assert_eq!(errors.len(), 61 * skeleton.len());
    assert!(within_limits(&errors, &limits));
    // `compress_clip` ends there too (the source does not thin at this tolerance).
    let (compressed, r) = compress_clip(&clip, Some(&skeleton), &options);
    assert_eq!(compressed.times(), c.times());
    assert!(r.max_error <= 0.001, "{}", r.max_error);
}

#[test]
fn a_clip_searched_on_its_frames_holds_at_every_time_and_is_smaller() {
    let skeleton = chain(6, 0.3);
    let clip = densified_swing(&skeleton, 31, 7).to_plain();
    // Within the tolerance at every time of the source, the 210 between the frames included.
    let (options, c, r) = compressed_within(&clip, &skeleton);
    // Searched on the frames: every key it kept is one.
    let frame_times: Vec<f32> = frame_indices(31, 7)
        .into_iter()
        .map(|i| clip.times()[i])
        .collect();
    assert!(
        c.times().iter().all(|t| frame_times.contains(t)),
        "{:?}",
        c.times()
    );
    // It came from the search on the frames, which holds in its first round here.
    let (on_frames, rounds) = searched_on_frames(&clip, &skeleton, &options, |frames, tol, _| {
        assert_eq!(frames.times(), &frame_times[..]);
        assert!((tol - 0.001 * FRAME_SHARE).abs() < 1e-9);
    });
    let on_frames = on_frames.unwrap();
    assert_eq!(rounds.len(), 1);
    assert_eq!(on_frames.0, r.compressed_bytes);
    assert_eq!(on_frames.2.len(), clip.times().len() * skeleton.len());
    let (rig, _, _) = rig_points(&clip, &skeleton);
    // The search on every time of the source keeps keys between the frames and is larger.
    let whole = whole_search(&clip, &rig, &options);
    assert!(
        r.compressed_bytes < whole.0,
        "{} vs {}",
        r.compressed_bytes,
        whole.0
    );
    assert!(whole.1.times().iter().any(|t| !frame_times.contains(t)));
}

/// A chain turning by up to `amplitude` rad between keys 0.25 s apart, with `extra` slerped keys
/// between every two (as the glTF importer adds them), its sample rate 4.
fn fast_turns(joints: usize, keys: usize, extra: usize, amplitude: f32) -> Clip {
    turns_held_after(joints, keys, keys, extra, amplitude)
}

/// [`fast_turns`] whose keys from `moving` on hold the value of the key before.
fn turns_held_after(
    joints: usize,
    keys: usize,
    moving: usize,
    extra: usize,
    amplitude: f32,
) -> Clip {
    let skeleton = chain(joints, 0.3);
    let coarse: Vec<Vec<Quat>> = (0..joints)
        .map(|j| {
            let axis = Vec3::new(1.0, j as f32 * 0.37, 0.5).normalize();
            (0..keys)
                .map(|k| {
                    let k = k.min(moving.max(1) - 1);
                    Quat::from_axis_angle(axis, amplitude * ((k + j) as f32 * 1.3).sin())
                })
                .collect()
        })
        .collect();
    let mut times = Vec::new();
    let mut values: Vec<Vec<Quat>> = vec![Vec::new(); joints];
    for k in 0..keys {
        let steps = if k + 1 < keys { extra + 1 } else { 1 };
        for i in 0..steps {
            let u = i as f32 / (extra + 1) as f32;
            times.push((k as f32 + u) * 0.25);
            for (j, v) in values.iter_mut().enumerate() {
                let b = coarse[j].get(k + 1).copied().unwrap_or(coarse[j][k]);
                v.push(coarse[j][k].slerp(b, u));
            }
        }
    }
    let tracks = skeleton
        .names()
        .iter()
        .zip(values)
        .map(|(name, rotation)| TrackCurves {
            joint: name.clone(),
            rotation: Curve::new(times.clone(), rotation),
            ..Default::default()
        })
        .collect();
    Clip::from_curves("turns", *times.last().unwrap(), 4.0, false, false, tracks).unwrap()
}

#[test]
fn frames_that_interpolation_reproduces_are_left_out_of_the_search() {
    let skeleton = chain(4, 0.3);
    // 41 frames, 3 slerped times between each two; the turns stop at the 9th frame and the
    // rest hold (an export that keys a curve on every frame of a fine grid).
    let clip = turns_held_after(4, 41, 9, 3, 0.2).to_plain();
    assert_eq!(clip.times().len(), 161);
    let all_frames = frame_indices(41, 3);
    assert_eq!(frames(&clip), Some(all_frames.clone()));
    let frame_times: Vec<f32> = all_frames.iter().map(|&i| clip.times()[i]).collect();
    let (options, c, r) = compressed_within(&clip, &skeleton);
    // The search saw the frames that linear interpolation does not reproduce: those of the
    // turns, and the ends of the hold.
    let (on_frames, seen) = searched_on_frames(&clip, &skeleton, &options, |frames, tol, round| {
        assert!(frames.times().iter().all(|t| frame_times.contains(t)));
        assert!(frames.times().contains(&clip.times()[160]));
        assert_eq!(round, 0);
        let share = FRAME_SHARE * (1.0 - THINNING);
        assert!((tol - 0.001 * share).abs() < 1e-9, "{tol}");
    });
    let on_frames = on_frames.unwrap();
    assert!(!seen.is_empty() && seen[0] <= 12, "{seen:?}");
    assert_eq!(on_frames.0, r.compressed_bytes);
    // Every key the encoder kept is a frame, within the tolerance at all 161 times
    // (`compressed_within`).
    assert!(c.times().iter().all(|t| frame_times.contains(t)));
}

#[test]
fn frames_whose_interpolation_leaves_the_tolerance_are_not_searched_alone() {
    let skeleton = chain(4, 0.3);
    // Turns of up to 1.2 rad a key: nlerp between the frames is far from their slerp.
    let clip = fast_turns(4, 9, 15, 1.2).to_plain();
    assert_eq!(frames(&clip), Some(frame_indices(9, 15)));
    let (_, c, _) = compressed_within(&clip, &skeleton);
    // The frames alone, nlerped, are past the limits between them: not searched at all.
    let (rig, src, origins) = rig_points(&clip, &skeleton);
    let none = frames_first(&clip, &rig, &src, &origins, 0.001, |_, _, _| {
        panic!("searched frames that cannot hold")
    });
    assert!(none.is_none());
    // Nor with the frames as candidate keys.
    let whole = Sampled::new(&rig, &clip, clip.times());
    let options = CompressOptions::peers();
    assert!(frame_keys((&clip, &whole), &rig, 0.001, |w| {
        compensated_first(w, (&clip, Some(&whole), &rig, 0.001), true, &options, true)
    })
    .is_none());
    // It needs keys between the frames, which the search on the frames alone cannot keep.
    let frame_times: Vec<f32> = frame_indices(9, 15)
        .into_iter()
        .map(|i| clip.times()[i])
        .collect();
    assert!(c.times().iter().any(|t| !frame_times.contains(t)));
}

#[test]
fn simple_skin_is_searched_on_its_file_keys_and_holds_between_them() {
    let Some(path) = sinew_testdata::corpus_file("gltf/SimpleSkin.gltf") else {
        return;
    };
    let scene = sinew_import::import_path(&path, &Default::default()).unwrap();
    let asset = crate::compile::compile(&scene).unwrap();
    let (clip, skeleton) = (&asset.clips[0], asset.skeleton.as_ref().unwrap());
    // The file's one sampler keys 0, 0.5, ..., 5.5 s (its input accessor), LINEAR rotations of up
    // to 90 degrees apart: the importer adds times between them for its slerp.
    let file_keys: Vec<f32> = (0..12).map(|k| k as f32 * 0.5).collect();
    let indices: Vec<usize> = file_keys
        .iter()
        .map(|k| clip.times().iter().position(|t| t == k).unwrap())
        .collect();
    assert!(clip.times().len() > 5 * 12 / 4, "{}", clip.times().len());
    assert_eq!(frames(clip), Some(indices));
    let options = CompressOptions::peers();
    let (c, r) = compress_clip(clip, Some(skeleton), &options);
    assert!(c.is_compressed());
    // Within the tolerance at every imported time, the added ones included.
    let errors = measure(clip, &c, Some(skeleton), 0.1);
    assert_eq!(errors.len(), clip.times().len() * skeleton.len());
    let worst = errors.into_iter().fold(0.0f32, f32::max);
    assert!(worst <= 0.001, "error {worst}");
    // Searched on the frames alone, it does not hold at some added time; its source thins (the
    // added times are within 1% of the tolerance of linear interpolation between others), so the
    // thinned source is searched next (144 bytes; 140 after three rounds on the frames, session
    // 30), not the frames as keys.
    let (rig, src, origins) = rig_points(clip, skeleton);
    let rounds = std::cell::Cell::new(0);
    let on_frames = frames_first(clip, &rig, &src, &origins, 0.001, |frames, sampled, tol| {
        rounds.set(rounds.get() + 1);
        search_on(frames, Some(sampled), &rig, tol, &options)
    });
    assert!(on_frames.is_none());
    assert_eq!(rounds.get(), 1);
    let poses = rig.poses(clip, clip.times());
    let (_, thin) = thinned(clip, &rig, &src, &origins, Some(&poses), 0.001).unwrap();
    let on_thin = search_on(&thin, None, &rig, 0.001 * (1.0 - THINNING), &options).unwrap();
    assert_eq!(r.compressed_bytes, on_thin.0);
}

#[test]
fn a_search_on_the_frames_that_does_not_hold_is_not_kept_and_the_frames_as_keys_hold() {
    let skeleton = chain(6, 0.3);
    let clip = densified_swing(&skeleton, 31, 7).to_plain();
    let (rig, src, origins) = rig_points(&clip, &skeleton);
    let options = CompressOptions::peers();
    // The search on the frames at 30 times the tolerance: measured at every time, it does not
    // hold, and nothing is returned (one search, no rounds after it).
    let searches = std::cell::Cell::new(0);
    let found = frames_first(
        &clip,
        &rig,
        &src,
        &origins,
        0.001,
        |frames, sampled, tol| {
            searches.set(searches.get() + 1);
            search_on(frames, Some(sampled), &rig, tol * 30.0, &options)
        },
    );
    assert!(found.is_none());
    assert_eq!(searches.get(), 1);
    // The frames as the only candidate keys, every time measured: every key kept is a frame,
    // and the errors it reports are those at every time, each within its joint's limit (and
    // `measure`, computed apart from the search, agrees that the tolerance holds).
    let frame_times: Vec<f32> = frame_indices(31, 7)
        .into_iter()
        .map(|i| clip.times()[i])
        .collect();
    let whole = Sampled::new(&rig, &clip, clip.times());
    let (size, c, errors) = frame_keys((&clip, &whole), &rig, 0.001, |w| {
        compensated_first(w, (&clip, Some(&whole), &rig, 0.001), true, &options, true)
    })
    .unwrap();
    assert!(c.times().iter().all(|t| frame_times.contains(t)));
    assert_eq!(errors.len(), clip.times().len() * skeleton.len());
    let limits = joint_limits(&src, skeleton.len(), 0.001);
    assert!(within_limits(&errors, &limits));
    let worst = measure(&clip, &c, Some(&skeleton), 0.1)
        .into_iter()
        .fold(0.0f32, f32::max);
    assert!(worst <= 0.001, "{worst}");
    // Smaller than the search on every time, which keeps keys between the frames.
    let every = whole_search(&clip, &rig, &options);
    assert!(size < every.0, "{size} vs {}", every.0);
}

#[test]
fn holds_against_agrees_with_the_errors_at_every_time() {
    // 4 joints x 129 times: one pass; 8 x 625: chunks side by side, at 1 to 3 threads.
    for (joints, keys) in [(4, 9), (8, 40)] {
        let skeleton = chain(joints, 0.3);
        let clip = fast_turns(joints, keys, 15, 1.2).to_plain();
        let (rig, src, origins) = rig_points(&clip, &skeleton);
        assert_eq!(
            rig.side_by_side(clip.times().len()),
            joints == 8,
            "{} times",
            clip.times().len()
        );
        let limits = joint_limits(&src, skeleton.len(), 0.001);
        let mut work = Work::from_plain(&clip);
        work.keep(&frames(&clip).unwrap());
        let on_frames = work.plain(&clip).unwrap();
        for (candidate, expected) in [(&clip, true), (&on_frames, false)] {
            let errors = errors_against(&rig, &src, &origins, candidate, clip.times());
            assert_eq!(within_limits(&errors, &limits), expected);
            for threads in [1, 2, 3] {
                let holds = on_threads(threads, || {
                    holds_against(&rig, &src, &origins, candidate, clip.times(), &limits)
                });
                assert_eq!(holds, expected, "{joints} joints, {threads} threads");
            }
        }
    }
}
