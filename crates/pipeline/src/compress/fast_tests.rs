//! Unit tests of `Effort::Fast`'s rule for long clips: widths of the first-width ladder, not
//! refined, above [`FAST_REFINED_VOLUME`] source times x joints.

#![allow(clippy::unwrap_used)]
use super::measure;
use super::options::*;
use super::search::compress_clip;
use super::tests::{chain, on_threads, swing_moving};

fn fast() -> CompressOptions {
    CompressOptions {
        effort: Effort::Fast,
        ..CompressOptions::peers()
    }
}

#[test]
fn fast_refines_a_clip_up_to_the_volume_and_not_one_key_past_it() {
    // Two clips of the same motion, one key apart, on either side of the volume: the one past it
    // keeps its ladder's widths, so it is clearly larger (refined, one more key would change the
    // size by a few bytes); both hold the tolerance, measured independently at every source time.
    let skeleton = chain(8, 0.3);
    let keys = FAST_REFINED_VOLUME / skeleton.len();
    assert_eq!(keys * skeleton.len(), FAST_REFINED_VOLUME);
    let mut sizes = Vec::new();
    for keys in [keys, keys + 1] {
        let clip = swing_moving(&skeleton, keys, true);
        let (c, r) = compress_clip(&clip, Some(&skeleton), &fast());
        assert!(c.is_compressed(), "{keys} keys");
        let worst = measure(&clip, &c, Some(&skeleton), 0.1)
            .into_iter()
            .fold(0.0f32, f32::max);
        assert!(worst <= 0.001, "{keys} keys: error {worst}");
        assert_eq!(r.max_error, worst, "{keys} keys");
        sizes.push(r.compressed_bytes);
    }
    assert!(
        sizes[1] * 100 > sizes[0] * 105,
        "refined {} bytes, unrefined {} bytes",
        sizes[0],
        sizes[1]
    );
    // The default effort refines the longer clip too.
    let clip = swing_moving(&skeleton, keys + 1, true);
    let default = compress_clip(&clip, Some(&skeleton), &CompressOptions::peers()).1;
    assert!(
        default.compressed_bytes * 100 < sizes[1] * 95,
        "default {} bytes, fast {} bytes",
        default.compressed_bytes,
        sizes[1]
    );
}

#[test]
fn fast_on_a_long_clip_gives_the_same_bytes_at_any_thread_count() {
    // The ladder's rungs are measured in pairs on two threads, one at a time on one.
    let skeleton = chain(16, 0.2);
    let keys = FAST_REFINED_VOLUME / skeleton.len() + 100;
    let clip = swing_moving(&skeleton, keys, true);
    let runs: Vec<_> = [1, 2, 3]
        .into_iter()
        .map(|threads| on_threads(threads, || compress_clip(&clip, Some(&skeleton), &fast())))
        .collect();
    assert!(runs[0].0.is_compressed());
    assert!(runs[0].1.max_error <= 0.001, "{:?}", runs[0].1);
    for r in &runs[1..] {
        assert_eq!(r.0, runs[0].0);
        assert_eq!(r.1, runs[0].1);
    }
}
