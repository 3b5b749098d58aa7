//! Fitting one channel of the runtime's playback with the fewest glTF `LINEAR` keys that reproduce it
//! at any time: the runtime's values at its knots (every key time of the clip), checked between the
//! knots at test points, a knot dropped where interpolating its neighbours gives the same curve, and
//! keys added inside an interval where a viewer's interpolation (slerp) leaves the runtime's (nlerp).
//!
//! Interpolation a viewer applies between two exported keys at fraction `f`:
//! - translation and scale: `a + (b - a) * f` (glTF `LINEAR`, and the runtime's);
//! - rotation: glTF `LINEAR` is spherical (three.js, Babylon, the glTF sample viewer), Blender
//!   interpolates the four components and normalises (the runtime's nlerp); a rotation segment is kept
//!   only when *both* stay within tolerance of the runtime, so every viewer plays the same.

use sinew_core::glam::{DQuat, DVec3, Quat, Vec3};

/// Fractions of a knot interval at which the runtime is compared with a candidate segment (on top of
/// the knots themselves). 0.21 and 0.79 are where slerp and nlerp of two keys differ most.
pub const TEST_FRACTIONS: [f32; 7] = [0.1, 0.21, 0.35, 0.5, 0.65, 0.79, 0.9];

/// Most pieces one knot interval is cut into when a viewer's interpolation between its ends leaves the
/// runtime's; beyond that the interval is kept as finely cut as this allows. Slerp moves at a steady
/// rate and nlerp does not, so a piece of angle `2 * phi` at fraction `f` leaves it by about
/// `df^2 / 4 * sin(phi) * (1 - cos(phi))` rad: a 120-degree turn between two keys needs 512 pieces
/// for 1e-6 rad, a 10-degree one 16.
pub const MAX_PIECES: usize = 1024;

/// One exported channel: strictly increasing times and a value per time.
#[derive(Debug, Clone, PartialEq)]
pub struct Keys<V> {
    /// Key times, seconds.
    pub times: Vec<f32>,
    /// One value per time.
    pub values: Vec<V>,
}

/// How far a viewer's interpolation may be from the runtime: translation in model units, rotation in
/// radians, scale as a factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// Largest translation difference, model units.
    pub translation: f64,
    /// Largest rotation difference, radians.
    pub rotation: f64,
    /// Largest scale difference (per component).
    pub scale: f64,
}

/// A value a channel holds: how a viewer interpolates it and whether that is close enough to a
/// runtime value.
pub trait Value: Copy {
    /// True when a viewer interpolates between two neighbouring knots exactly as the runtime does
    /// (linear values), so a knot interval never needs cutting; a difference there is f32 rounding.
    const LINEAR: bool;
    /// True when every viewer's interpolation from `a` to `b` at fraction `f` is within `tol` of
    /// `runtime`.
    fn close(a: Self, b: Self, f: f32, runtime: Self, tol: &Tolerance) -> bool;
}

/// A translation (a [`Vec3`] compared with `tol.translation`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Translation(pub Vec3);
/// A scale (a [`Vec3`] compared with `tol.scale`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scale(pub Vec3);
/// A rotation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rotation(pub Quat);

fn lerp3(a: Vec3, b: Vec3, f: f32) -> DVec3 {
    let (a, b) = (a.as_dvec3(), b.as_dvec3());
    a + (b - a) * f64::from(f)
}

/// Four f32 rounding steps of the largest magnitude involved: what the runtime's own f32 arithmetic
/// may differ by, added to the tolerance so that a value far from the origin is not held to more
/// precision than f32 has.
fn rounding(a: Vec3, b: Vec3, r: Vec3) -> f64 {
    let m = a.abs().max(b.abs()).max(r.abs()).max_element();
    4.0 * f64::from(m) * f64::from(f32::EPSILON) * 0.5
}

impl Value for Translation {
    const LINEAR: bool = true;
    fn close(a: Self, b: Self, f: f32, runtime: Self, tol: &Tolerance) -> bool {
        lerp3(a.0, b.0, f).distance(runtime.0.as_dvec3())
            <= tol.translation + rounding(a.0, b.0, runtime.0)
    }
}

impl Value for Scale {
    const LINEAR: bool = true;
    fn close(a: Self, b: Self, f: f32, runtime: Self, tol: &Tolerance) -> bool {
        let d = (lerp3(a.0, b.0, f) - runtime.0.as_dvec3()).abs();
        d.max_element() <= tol.scale + rounding(a.0, b.0, runtime.0)
    }
}

/// The rotation angle between two unit quaternions (either sign), robust for small angles.
pub fn angle(a: DQuat, b: DQuat) -> f64 {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    let diff = (DQuat::from_xyzw(a.x - b.x, a.y - b.y, a.z - b.z, a.w - b.w)).length();
    let sum = (DQuat::from_xyzw(a.x + b.x, a.y + b.y, a.z + b.z, a.w + b.w)).length();
    4.0 * diff.atan2(sum)
}

/// Spherical interpolation along the shorter arc, in f64.
pub fn slerp(a: DQuat, b: DQuat, f: f64) -> DQuat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    let theta = 0.5 * angle(a, b);
    if theta < 1e-12 {
        return a;
    }
    let (sa, sb) = (((1.0 - f) * theta).sin(), (f * theta).sin());
    let s = theta.sin();
    let q = a * (sa / s) + b * (sb / s);
    q.normalize()
}

/// Normalised linear interpolation along the shorter arc (the runtime's rule), in f64.
pub fn nlerp(a: DQuat, b: DQuat, f: f64) -> DQuat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    (a * (1.0 - f) + b * f).normalize()
}

impl Value for Rotation {
    const LINEAR: bool = false;
    fn close(a: Self, b: Self, f: f32, runtime: Self, tol: &Tolerance) -> bool {
        let (a, b, r) = (
            a.0.as_dquat().normalize(),
            b.0.as_dquat().normalize(),
            runtime.0.as_dquat().normalize(),
        );
        let f = f64::from(f);
        angle(slerp(a, b, f), r) <= tol.rotation && angle(nlerp(a, b, f), r) <= tol.rotation
    }
}

/// The runtime's playback of one channel, as the fitter sees it.
pub struct Runtime<'a, V> {
    /// Knot times: strictly increasing; the first is 0 and the last the clip's duration.
    pub knots: &'a [f32],
    /// The runtime's value at each knot.
    pub values: &'a [V],
    /// Per knot interval `k` (between knots `k` and `k + 1`), the runtime's value at each of
    /// [`TEST_FRACTIONS`]: `tests[k * TEST_FRACTIONS.len() + i]`.
    pub tests: &'a [V],
}

/// The time at fraction `f` of `[a, b]` (as f32, the way keys and test times are computed).
pub fn at(a: f32, b: f32, f: f32) -> f32 {
    (f64::from(a) + (f64::from(b) - f64::from(a)) * f64::from(f)) as f32
}

/// The fraction a viewer computes for time `t` between keys at `a` and `b`.
fn fraction(a: f32, b: f32, t: f32) -> f32 {
    (t - a) / (b - a)
}

/// True when the segment from knot `i` to knot `j` (a viewer interpolating their values) reproduces
/// the runtime at every knot and test point between them.
fn segment_ok<V: Value>(rt: &Runtime<'_, V>, i: usize, j: usize, tol: &Tolerance) -> bool {
    let (ta, tb) = (rt.knots[i], rt.knots[j]);
    let (va, vb) = (rt.values[i], rt.values[j]);
    let n = TEST_FRACTIONS.len();
    for k in i..j {
        if k > i && !V::close(va, vb, fraction(ta, tb, rt.knots[k]), rt.values[k], tol) {
            return false;
        }
        for (x, &f) in TEST_FRACTIONS.iter().enumerate() {
            let t = at(rt.knots[k], rt.knots[k + 1], f);
            if !V::close(va, vb, fraction(ta, tb, t), rt.tests[k * n + x], tol) {
                return false;
            }
        }
    }
    true
}

/// Cuts knot interval `k` into equal pieces until a viewer reproduces the runtime inside every
/// piece (at most [`MAX_PIECES`]); `eval` is the runtime's value at any time. Returns the inner cut
/// times and values (the interval's ends not included).
fn cut<V: Value>(
    rt: &Runtime<'_, V>,
    k: usize,
    tol: &Tolerance,
    eval: &mut impl FnMut(f32) -> V,
) -> Vec<(f32, V)> {
    let (ta, tb) = (rt.knots[k], rt.knots[k + 1]);
    let mut pieces = 2;
    loop {
        let mut cuts: Vec<(f32, V)> = Vec::with_capacity(pieces - 1);
        for p in 1..pieces {
            let t = at(ta, tb, p as f32 / pieces as f32);
            if t > cuts.last().map_or(ta, |c| c.0) && t < tb {
                cuts.push((t, eval(t)));
            }
        }
        let mut ends = vec![(ta, rt.values[k])];
        ends.extend(cuts.iter().copied());
        ends.push((tb, rt.values[k + 1]));
        let ok = ends.windows(2).all(|w| {
            let ((a, va), (b, vb)) = (w[0], w[1]);
            TEST_FRACTIONS.iter().all(|&f| {
                let t = at(a, b, f);
                V::close(va, vb, fraction(a, b, t), eval(t), tol)
            })
        });
        if ok || pieces >= MAX_PIECES {
            return cuts;
        }
        pieces *= 2;
    }
}

/// Fits the runtime's channel: keys at a subset of the knots (the first and last always), plus cuts
/// inside intervals that need them, such that a viewer's interpolation stays within `tol` of the
/// runtime at every knot and test point. `eval` gives the runtime's value at any time (used only for
/// cuts). Greedy from the first knot: each segment is extended as far as it holds (doubling, then
/// halving back), so a channel that is still or moves at a steady rate takes few keys.
pub fn fit<V: Value>(
    rt: &Runtime<'_, V>,
    tol: &Tolerance,
    mut eval: impl FnMut(f32) -> V,
) -> Keys<V> {
    let n = rt.knots.len();
    let mut out = Keys {
        times: vec![rt.knots[0]],
        values: vec![rt.values[0]],
    };
    let mut i = 0;
    while i + 1 < n {
        if !V::LINEAR && !segment_ok(rt, i, i + 1, tol) {
            for (t, v) in cut(rt, i, tol, &mut eval) {
                out.times.push(t);
                out.values.push(v);
            }
            i += 1;
            out.times.push(rt.knots[i]);
            out.values.push(rt.values[i]);
            continue;
        }
        // `good` holds; find a farther end by doubling the step, then narrow down.
        let mut good = i + 1;
        let mut step = 2;
        let mut bad = None;
        while good < n - 1 {
            let j = (i + step).min(n - 1);
            if segment_ok(rt, i, j, tol) {
                good = j;
                step *= 2;
            } else {
                bad = Some(j);
                break;
            }
        }
        if let Some(mut hi) = bad {
            while hi - good > 1 {
                let mid = good + (hi - good) / 2;
                if segment_ok(rt, i, mid, tol) {
                    good = mid;
                } else {
                    hi = mid;
                }
            }
        }
        i = good;
        out.times.push(rt.knots[i]);
        out.values.push(rt.values[i]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const TOL: Tolerance = Tolerance {
        translation: 1e-6,
        rotation: 1e-6,
        scale: 1e-6,
    };

    /// A runtime made of knots and linear (or nlerp) playback between them, evaluated as the runtime
    /// does; returns the fitted keys.
    fn fit_linear<V: Value>(
        knots: &[f32],
        values: &[V],
        lerp: impl Fn(V, V, f32) -> V + Copy,
    ) -> Keys<V> {
        let eval = move |t: f32| {
            let k = knots.partition_point(|&x| x <= t).clamp(1, knots.len() - 1);
            let f = (t - knots[k - 1]) / (knots[k] - knots[k - 1]);
            lerp(values[k - 1], values[k], f.clamp(0.0, 1.0))
        };
        let mut tests = Vec::new();
        for w in knots.windows(2) {
            for &f in &TEST_FRACTIONS {
                tests.push(eval(at(w[0], w[1], f)));
            }
        }
        let rt = Runtime {
            knots,
            values,
            tests: &tests,
        };
        fit(&rt, &TOL, eval)
    }

    fn lerp_t(a: Translation, b: Translation, f: f32) -> Translation {
        Translation(a.0.lerp(b.0, f))
    }

    #[test]
    fn knots_on_a_straight_line_collapse_to_its_ends() {
        let knots: Vec<f32> = (0..=40).map(|i| i as f32 / 40.0).collect();
        let values: Vec<Translation> = knots
            .iter()
            .map(|&t| Translation(Vec3::new(2.0 * t, 1.0, -t)))
            .collect();
        let k = fit_linear(&knots, &values, lerp_t);
        assert_eq!(k.times, vec![0.0, 1.0]);
        assert_eq!(k.values[1].0, Vec3::new(2.0, 1.0, -1.0));
    }

    #[test]
    fn every_corner_of_a_zigzag_is_kept() {
        let knots: Vec<f32> = (0..=10).map(|i| i as f32 * 0.1).collect();
        let values: Vec<Translation> = (0..=10)
            .map(|i| Translation(Vec3::new(0.0, (i % 2) as f32, 0.0)))
            .collect();
        let k = fit_linear(&knots, &values, lerp_t);
        assert_eq!(k.times, knots);
    }

    #[test]
    fn a_corner_between_two_lines_is_kept_and_the_rest_dropped() {
        let knots: Vec<f32> = (0..=20).map(|i| i as f32 * 0.05).collect();
        // Up until t = 0.5, then flat.
        let values: Vec<Translation> = knots
            .iter()
            .map(|&t| Translation(Vec3::new(0.0, t.min(0.5), 0.0)))
            .collect();
        let k = fit_linear(&knots, &values, lerp_t);
        assert_eq!(k.times, vec![0.0, 0.5, 1.0]);
    }

    #[test]
    fn a_wide_nlerp_interval_is_cut_until_slerp_matches() {
        // One knot interval turning 120 degrees: the runtime's nlerp leaves slerp by about 1.5
        // degrees in between, so the fit adds keys; every added key is the runtime's value.
        let knots = [0.0f32, 1.0];
        let values = [
            Rotation(Quat::IDENTITY),
            Rotation(Quat::from_rotation_y(120f32.to_radians())),
        ];
        let nl = |a: Rotation, b: Rotation, f: f32| Rotation(sinew_core::clip::nlerp(a.0, b.0, f));
        let k = fit_linear(&knots, &values, nl);
        assert!(
            k.times.len() > 8 && k.times.len() <= MAX_PIECES + 1,
            "{}",
            k.times.len()
        );
        for (t, v) in k.times.iter().zip(&k.values) {
            let want = sinew_core::clip::nlerp(values[0].0, values[1].0, *t);
            assert!(angle(v.0.as_dquat(), want.as_dquat()) < 1e-6);
        }
        // Between the keys, slerp stays within tolerance of the runtime's nlerp.
        for w in k.times.windows(2).zip(k.values.windows(2)) {
            let ((a, b), (va, vb)) = ((w.0[0], w.0[1]), (w.1[0], w.1[1]));
            for s in 1..10 {
                let t = a + (b - a) * s as f32 / 10.0;
                let runtime = sinew_core::clip::nlerp(values[0].0, values[1].0, t).as_dquat();
                let viewer = slerp(va.0.as_dquat(), vb.0.as_dquat(), f64::from(s) / 10.0);
                assert!(angle(viewer, runtime) < 2e-6, "{}", angle(viewer, runtime));
            }
        }
    }

    #[test]
    fn a_steady_rotation_keeps_a_few_of_its_knots() {
        let knots: Vec<f32> = (0..=30).map(|i| i as f32 / 30.0).collect();
        let values: Vec<Rotation> = knots
            .iter()
            .map(|&t| Rotation(Quat::from_rotation_z(0.3 * t)))
            .collect();
        let nl = |a: Rotation, b: Rotation, f: f32| Rotation(sinew_core::clip::nlerp(a.0, b.0, f));
        let k = fit_linear(&knots, &values, nl);
        // 0.3 rad over the clip at a steady rate: slerp between far knots matches, but Blender's
        // nlerp between them leaves the runtime by 0.032 * (half angle)^3, so a segment spans at most
        // about 0.06 rad: 6 or so of the 31 knots are kept, never every one.
        assert!((5..=10).contains(&k.times.len()), "{}", k.times.len());
    }

    #[test]
    fn angle_is_exact_for_small_and_opposite_signs() {
        let a = DQuat::IDENTITY;
        let b = DQuat::from_rotation_x(1e-7);
        assert!((angle(a, b) - 1e-7).abs() < 1e-15);
        assert!((angle(a, -b) - 1e-7).abs() < 1e-15);
        assert!((angle(a, DQuat::from_rotation_x(2.0)) - 2.0).abs() < 1e-12);
    }
}
