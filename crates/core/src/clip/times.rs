//! The union of several key-time lists: what a clip's frame times are (every animated channel's
//! times, once each).

use std::cmp::Ordering;

/// The distinct times of `lists`, in [`f32::total_cmp`] order: the same values as concatenating
/// them, sorting by `total_cmp` and removing consecutive `==` repeats (`Vec::dedup`), which is
/// what it falls back to when a list is not in `total_cmp` order.
///
/// Why: a clip's channels are each sorted already (a curve's times strictly increase), so merging
/// them in pairs costs the times times the logarithm of the lists instead of a sort of every key;
/// on a 23 s motion capture at 120 Hz exported to glTF (31 rotation curves of up to 3,442 keys
/// each, their times differing where the importer added some) the sort was a quarter of a
/// `--no-compress` convert's instructions (docs/performance.md, session 37).
pub fn union_of_times(lists: &[&[f32]]) -> Vec<f32> {
    let sorted = |l: &&[f32]| {
        l.windows(2)
            .all(|w| w[0].total_cmp(&w[1]) != Ordering::Greater)
    };
    if !lists.iter().all(sorted) {
        let mut times = lists.concat();
        times.sort_by(f32::total_cmp);
        times.dedup();
        return times;
    }
    union_sorted(lists)
}

/// [`union_of_times`] of lists each in `total_cmp` order: halves merged, recursively.
fn union_sorted(lists: &[&[f32]]) -> Vec<f32> {
    match lists {
        [] => Vec::new(),
        [one] => {
            let mut times = one.to_vec();
            times.dedup();
            times
        }
        _ => {
            let (a, b) = lists.split_at(lists.len() / 2);
            merge(&union_sorted(a), &union_sorted(b))
        }
    }
}

/// Two lists in `total_cmp` order merged in that order, each time pushed unless it is `==` to the
/// last one kept (as `Vec::dedup` keeps the first of a run: within a run of `==` times, such as
/// -0.0 then 0.0, `total_cmp` order puts the same one first whichever list it came from).
fn merge(a: &[f32], b: &[f32]) -> Vec<f32> {
    let mut out: Vec<f32> = Vec::with_capacity(a.len().max(b.len()));
    let mut push = |t: f32| {
        if out.last() != Some(&t) {
            out.push(t);
        }
    };
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        // The same time in both lists, as channels sampled alike mostly are: kept once, both
        // passed (the second push would be dropped as `==` anyway; not a NaN, which `==` keeps).
        if a[i] == b[j] && a[i].to_bits() == b[j].to_bits() {
            push(a[i]);
            i += 1;
            j += 1;
        } else if b[j].total_cmp(&a[i]) == Ordering::Less {
            push(b[j]);
            j += 1;
        } else {
            push(a[i]);
            i += 1;
        }
    }
    a[i..].iter().chain(&b[j..]).for_each(|&t| push(t));
    out
}
