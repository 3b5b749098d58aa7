//! Unit tests of the per-clip report's figures.

use super::search::percentile;

#[test]
fn percentile_is_the_value_at_its_rank_in_sorted_order() {
    // A scrambled sequence with repeats: the selection gives what sorting gives.
    let values: Vec<f32> = (0..1000u32)
        .map(|i| ((i * 7919) % 613) as f32 * 0.25)
        .collect();
    let mut sorted = values.clone();
    sorted.sort_by(f32::total_cmp);
    for p in [0.0f32, 0.01, 0.5, 0.99, 0.999, 1.0] {
        let rank = (1000.0 * p).ceil() as usize;
        let expected = sorted[rank.clamp(1, 1000) - 1];
        assert_eq!(percentile(&mut values.clone(), p), expected, "p {p}");
    }
    assert_eq!(percentile(&mut [], 0.99), 0.0);
    assert_eq!(percentile(&mut [3.0], 0.99), 3.0);
}
