//! [`super::union_of_times`] against the sort and dedup it replaces.

use super::union_of_times;

/// What the union replaces: the concatenation sorted by `total_cmp`, then `dedup`.
fn sorted_then_deduped(lists: &[&[f32]]) -> Vec<f32> {
    let mut times = lists.concat();
    times.sort_by(f32::total_cmp);
    times.dedup();
    times
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|t| t.to_bits()).collect()
}

#[test]
fn the_union_of_sorted_lists_is_their_sorted_distinct_times() {
    let a = [0.0, 0.5, 1.0, 2.0];
    let b = [0.25, 0.5, 3.0];
    let c = [0.0, 2.0];
    assert_eq!(
        union_of_times(&[&a, &b, &c]),
        vec![0.0, 0.25, 0.5, 1.0, 2.0, 3.0]
    );
    assert_eq!(union_of_times(&[]), Vec::<f32>::new());
    assert_eq!(union_of_times(&[&[], &b]), vec![0.25, 0.5, 3.0]);
}

#[test]
fn signed_zeros_keep_the_first_in_total_order_from_either_list() {
    // -0.0 == 0.0: dedup keeps -0.0, which total_cmp puts first, wherever it came from.
    for lists in [[&[0.0f32, 1.0][..], &[-0.0]], [&[-0.0f32, 1.0][..], &[0.0]]] {
        let got = union_of_times(&lists);
        assert_eq!(bits(&got), bits(&[-0.0, 1.0]));
        assert_eq!(bits(&got), bits(&sorted_then_deduped(&lists)));
    }
}

#[test]
fn unsorted_lists_and_nans_give_what_the_sort_gives() {
    let nan = f32::from_bits(0x7fc0_0001);
    let cases: [&[&[f32]]; 5] = [
        &[&[1.0, 0.5], &[0.25]],
        &[&[0.0, nan], &[nan, 2.0]],
        &[&[1.0, 1.0, 2.0], &[1.0]],
        &[&[f32::NEG_INFINITY, 0.0], &[-1.0, f32::INFINITY]],
        // Sorted lists sharing a NaN (the same bits): the sort keeps both (NaN != NaN).
        &[&[0.0, 1.0, nan], &[1.0, nan]],
    ];
    assert_eq!(union_of_times(cases[4]).len(), 4);
    for lists in cases {
        assert_eq!(
            bits(&union_of_times(lists)),
            bits(&sorted_then_deduped(lists))
        );
    }
}

/// Many lists of pseudo-random sorted times from a small grid (so that they share times), some
/// with signed zeros: bit for bit the sort's result.
#[test]
fn random_sorted_lists_match_the_sort_bit_for_bit() {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for _ in 0..200 {
        let count = (next() % 40) as usize;
        let lists: Vec<Vec<f32>> = (0..count)
            .map(|_| {
                let len = (next() % 30) as usize;
                let mut l: Vec<f32> = (0..len)
                    .map(|_| match next() % 50 {
                        0 => -0.0,
                        k => (k as f32 - 1.0) / 8.0,
                    })
                    .collect();
                l.sort_by(f32::total_cmp);
                l
            })
            .collect();
        let refs: Vec<&[f32]> = lists.iter().map(Vec::as_slice).collect();
        assert_eq!(
            bits(&union_of_times(&refs)),
            bits(&sorted_then_deduped(&refs))
        );
    }
}
