//! Turning glTF animation samplers (LINEAR, STEP, CUBICSPLINE) into sinew's linear-key curves.
//!
//! The runtime interpolates translation and scale linearly and rotation by normalised lerp. Every glTF key
//! becomes a key with the glTF value bit for bit; keys are added between glTF keys where the runtime's
//! interpolation would otherwise leave the glTF curve by more than the tolerances below.

use glam::{Quat, Vec3};
use sinew_core::Curve;

/// Largest angle (radians) by which a converted rotation curve may differ from glTF's between keys.
pub const ROTATION_TOLERANCE: f32 = 2e-6;
/// Largest distance between a converted translation or scale curve and glTF's cubic spline between keys,
/// relative to `max(1, largest absolute key value of the channel)`.
pub const VECTOR_TOLERANCE: f32 = 1e-4;
/// Most keys inserted into one glTF key interval.
pub const MAX_SUBDIVISIONS: usize = 256;

/// glTF interpolation of one sampler.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interp {
    /// Linear (slerp for rotations).
    Linear,
    /// Hold the previous key until the next.
    Step,
    /// Cubic Hermite spline with in/out tangents.
    Cubic,
}

/// The float just below `x` (for `x > 0`).
pub fn prev_float(x: f32) -> f32 {
    if x > 0.0 && x.is_finite() {
        f32::from_bits(x.to_bits() - 1)
    } else {
        x
    }
}

/// glTF spherical linear interpolation along the shortest path.
pub fn slerp(a: Quat, b: Quat, s: f32) -> Quat {
    Slerp::new(a, b).at(s)
}

/// [`slerp`] between two fixed rotations with the angle between them worked out once: the same
/// operations in the same order, so the same bits, for a fraction of the cost per parameter.
struct Slerp {
    a: Quat,
    /// `b` on `a`'s side of the sphere.
    b: Quat,
    /// Nearly the same rotation: normalised lerp.
    near: bool,
    angle: f32,
    sin_angle: f32,
}

impl Slerp {
    fn new(a: Quat, b: Quat) -> Slerp {
        let mut d = a.dot(b);
        let b = if d < 0.0 {
            d = -d;
            -b
        } else {
            b
        };
        let near = d > 0.9999995;
        let angle = if near { 0.0 } else { d.min(1.0).acos() };
        Slerp {
            a,
            b,
            near,
            angle,
            sin_angle: angle.sin(),
        }
    }

    /// What [`RotationSpan::nlerp_error`] measures over `pieces` equal pieces, worked out without
    /// rounding: every piece spans the same angle of the great circle, and normalised lerp between
    /// its ends lies `u a - atan2(u sin a, 1 - u + u cos a)` from slerp at `u` (`a` the piece's
    /// angle); of the five points measured, `u` = 1/6 and 2/6 (4/6 and 5/6 mirror them, 3/6 is 0).
    /// Below a piece's angle of 0.1, the larger of the two is `a^3` times 0.015432 to 0.015438
    /// (rising with `a`): the upper one is used, 1e-9 rad above near the tolerance.
    fn sampled_deviation(&self, pieces: usize) -> f64 {
        let a = f64::from(self.angle) / pieces as f64;
        if a <= 0.1 {
            return 0.015438 * a * a * a;
        }
        let (sin, cos) = a.sin_cos();
        [1.0 / 6.0, 2.0 / 6.0]
            .iter()
            .map(|&u| (u * a - (u * sin).atan2(1.0 - u + u * cos)).abs())
            .fold(0.0, f64::max)
    }

    fn at(&self, s: f32) -> Quat {
        let (a, b, ang, sn) = (self.a, self.b, self.angle, self.sin_angle);
        if self.near {
            return (a * (1.0 - s) + b * s).normalize();
        }
        (a * (((1.0 - s) * ang).sin() / sn) + b * ((s * ang).sin() / sn)).normalize()
    }
}

/// The glTF curve between two rotation keys, as a function of the interval's parameter in [0, 1].
enum RotationSpan {
    Linear(Slerp),
    /// Hermite spline through the raw key values `r0`, `r1` with tangents `b0`, `a1`, normalised;
    /// the unit keys `q0`, `q1` themselves at the ends.
    Cubic {
        q0: Quat,
        q1: Quat,
        r0: Quat,
        b0: Quat,
        r1: Quat,
        a1: Quat,
        td: f32,
    },
}

/// The most by which [`RotationSpan::nlerp_error`]'s single-precision measurement of a slerp span
/// differs from [`Slerp::sampled_deviation`]: at most 2.5e-7 rad over 20,000 random spans at
/// every number of pieces (the test below); twice that is the margin.
const ROUNDING_MARGIN: f64 = 5e-7;

impl RotationSpan {
    /// The fewest pieces (1, 2, 4 ... [`MAX_SUBDIVISIONS`]) whose measured error is not certainly
    /// above [`ROTATION_TOLERANCE`], and, when that error is certainly within it, a bound on
    /// it. Certainly: a slerp span's [`Slerp::sampled_deviation`] farther than
    /// [`ROUNDING_MARGIN`] from the tolerance, so the measurement (which only rounding sets
    /// apart from it) would decide the same. A cubic span: one piece, no bound.
    fn first_pieces(&self) -> (usize, Option<f32>) {
        let RotationSpan::Linear(slerp) = self else {
            return (1, None);
        };
        let tolerance = f64::from(ROTATION_TOLERANCE);
        let mut pieces = 1;
        loop {
            let d = slerp.sampled_deviation(pieces);
            if !d.is_finite() {
                return (1, None);
            }
            if d - ROUNDING_MARGIN > tolerance && pieces < MAX_SUBDIVISIONS {
                pieces *= 2;
                continue;
            }
            let bound = (d + ROUNDING_MARGIN <= tolerance).then_some((d + ROUNDING_MARGIN) as f32);
            return (pieces, bound);
        }
    }

    fn at(&self, s: f32) -> Quat {
        match self {
            RotationSpan::Linear(slerp) => slerp.at(s),
            RotationSpan::Cubic {
                q0,
                q1,
                r0,
                b0,
                r1,
                a1,
                td,
            } => {
                let q = hermite(*r0, *b0, *r1, *a1, *td, s);
                if s <= 0.0 {
                    *q0
                } else if s >= 1.0 {
                    *q1
                } else {
                    q.normalize()
                }
            }
        }
    }

    /// The largest angle between the span and normalised lerp over `pieces` equal pieces, at five
    /// points inside each piece; `ends[p]` is the span at `p / pieces`. With `above`, it may stop
    /// at the first point certainly farther than `above` and return that point's angle (the
    /// caller then only needs to know that the pieces are too few).
    ///
    /// The angle is `2 atan2(|a - b|, |a + b|)`, which grows with the ratio `|a - b| / |a + b|`:
    /// the ratios of every point are worked out first, and the arctangent only where it can be the
    /// largest (within 1e-4 of the largest ratio, or a ratio above 0.01, where the arctangent
    /// flattens), so the result is the largest angle bit for bit at a fraction of the cost.
    fn nlerp_error(
        &self,
        pieces: usize,
        ends: &[Quat],
        above: Option<f32>,
        ratios: &mut Vec<(f32, f32, f32)>,
    ) -> f32 {
        // 1e-3 above the ratio of `above`: far beyond the rounding of atan2 and of the division.
        let stop = above.map(|a| (0.5 * a).tan() * 1.001);
        ratios.clear();
        let mut largest = 0.0f32;
        for p in 0..pieces {
            let (s0, s1) = (p as f32 / pieces as f32, (p + 1) as f32 / pieces as f32);
            let (y0, y1) = (ends[p], ends[p + 1]);
            for q in 1..6 {
                let u = q as f32 / 6.0;
                let (y, x) = angle_parts(nlerp(y0, y1, u), self.at(s0 + (s1 - s0) * u));
                let r = y / x;
                if stop.is_some_and(|stop| r > stop) {
                    return 2.0 * y.atan2(x);
                }
                largest = largest.max(r);
                ratios.push((r, y, x));
            }
        }
        let near = largest * (1.0 - 1e-4);
        ratios
            .iter()
            .filter(|&&(r, _, _)| r >= near || r > 0.01 || r.is_nan())
            .fold(0.0f32, |e, &(_, y, x)| e.max(2.0 * y.atan2(x)))
    }
}

/// Normalised lerp along the shortest path, as the runtime does it.
pub fn nlerp(a: Quat, b: Quat, s: f32) -> Quat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    (a * (1.0 - s) + b * s).normalize()
}

/// Angle in radians between two rotations.
pub fn rotation_angle(a: Quat, b: Quat) -> f32 {
    let (y, x) = angle_parts(a, b);
    2.0 * y.atan2(x)
}

/// `|a - b|` and `|a + b|` with `b` on `a`'s side of the sphere: the angle between the rotations
/// is `2 atan2` of them.
fn angle_parts(a: Quat, b: Quat) -> (f32, f32) {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    ((a - b).length(), (a + b).length())
}

/// glTF cubic Hermite basis: value at `s` in [0,1] between (v0, out-tangent b0) and (v1, in-tangent a1).
fn hermite<T>(v0: T, b0: T, v1: T, a1: T, td: f32, s: f32) -> T
where
    T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let s2 = s * s;
    let s3 = s2 * s;
    v0 * (2.0 * s3 - 3.0 * s2 + 1.0)
        + b0 * (td * (s3 - 2.0 * s2 + s))
        + v1 * (-2.0 * s3 + 3.0 * s2)
        + a1 * (td * (s3 - s2))
}

/// Key times inserted between `t0` and `t1` for `n` equal pieces (strictly inside, increasing).
fn inner_times(t0: f32, t1: f32, n: usize) -> Vec<(f32, f32)> {
    let mut out = Vec::new();
    let mut last = t0;
    for k in 1..n {
        let s = k as f32 / n as f32;
        let t = t0 + (t1 - t0) * s;
        if t > last && t < t1 {
            // The parameter actually used for the value is the one the stored time implies.
            out.push((t, (t - t0) / (t1 - t0)));
            last = t;
        }
    }
    out
}

/// Converts a vector channel (translation or scale). `values` holds one Vec3 per key (three per key for
/// CUBICSPLINE: in-tangent, value, out-tangent). Returns the curve and the largest deviation measured.
pub fn vector_curve(times: &[f32], values: &[Vec3], interp: Interp) -> (Curve<Vec3>, f32) {
    let n = times.len();
    let key = |k: usize| match interp {
        Interp::Cubic => values[3 * k + 1],
        _ => values[k],
    };
    let mut out_t = Vec::with_capacity(n);
    let mut out_v = Vec::with_capacity(n);
    let mut worst = 0.0f32;
    let scale = (0..n).fold(1.0f32, |m, k| m.max(key(k).abs().max_element()));
    let tol = VECTOR_TOLERANCE * scale;
    for k in 0..n {
        if k > 0 {
            let (t0, t1) = (times[k - 1], times[k]);
            match interp {
                Interp::Linear => {}
                Interp::Step => {
                    let tb = prev_float(t1);
                    if tb > t0 {
                        out_t.push(tb);
                        out_v.push(key(k - 1));
                    }
                }
                Interp::Cubic => {
                    let td = t1 - t0;
                    let (v0, b0, v1, a1) =
                        (key(k - 1), values[3 * (k - 1) + 2], key(k), values[3 * k]);
                    let f = |s: f32| hermite(v0, b0, v1, a1, td, s);
                    let err_at = |pieces: usize| -> f32 {
                        let mut e = 0.0f32;
                        for p in 0..pieces {
                            let (s0, s1) =
                                (p as f32 / pieces as f32, (p + 1) as f32 / pieces as f32);
                            let (y0, y1) = (f(s0), f(s1));
                            for q in 1..6 {
                                let u = q as f32 / 6.0;
                                let lin = y0.lerp(y1, u);
                                e = e.max((lin - f(s0 + (s1 - s0) * u)).length());
                            }
                        }
                        e
                    };
                    let mut pieces = 1;
                    let mut e = err_at(1);
                    while e > tol && pieces < MAX_SUBDIVISIONS {
                        pieces *= 2;
                        e = err_at(pieces);
                    }
                    worst = worst.max(e);
                    for (t, s) in inner_times(t0, t1, pieces) {
                        out_t.push(t);
                        out_v.push(f(s));
                    }
                }
            }
        }
        out_t.push(times[k]);
        out_v.push(key(k));
    }
    (Curve::new(out_t, out_v), worst)
}

/// The unit key `k` of a rotation channel (the value, not a tangent, of a cubic one).
fn rotation_key(values: &[Quat], interp: Interp, k: usize) -> Quat {
    unit(match interp {
        Interp::Cubic => values[3 * k + 1],
        _ => values[k],
    })
}

/// The glTF curve of a rotation channel between keys `k - 1` and `k` (`None` for STEP).
fn rotation_span(times: &[f32], values: &[Quat], interp: Interp, k: usize) -> Option<RotationSpan> {
    let (q0, q1) = (
        rotation_key(values, interp, k - 1),
        rotation_key(values, interp, k),
    );
    match interp {
        Interp::Step => None,
        Interp::Linear => Some(RotationSpan::Linear(Slerp::new(q0, q1))),
        Interp::Cubic => Some(RotationSpan::Cubic {
            q0,
            q1,
            r0: values[3 * (k - 1) + 1],
            b0: values[3 * (k - 1) + 2],
            r1: values[3 * k + 1],
            a1: values[3 * k],
            td: times[k] - times[k - 1],
        }),
    }
}

/// Below the most pieces, only whether the error is above the tolerance matters until it is not
/// ([`RotationSpan::nlerp_error`]'s `above`).
fn above(pieces: usize) -> Option<f32> {
    (pieces < MAX_SUBDIVISIONS).then_some(ROTATION_TOLERANCE)
}

/// The span at the ends of `pieces` equal pieces, worked out at once: the parameter 2p / 2n is
/// p / n bit for bit, so these are the ends a halving from one piece keeps.
fn piece_ends(span: &RotationSpan, pieces: usize) -> Vec<Quat> {
    (0..=pieces)
        .map(|p| span.at(p as f32 / pieces as f32))
        .collect()
}

/// Converts a rotation channel. Values are normalised copies of the glTF quaternions (bit-exact when the
/// glTF value is already unit length to within 1e-6). Returns the curve and the largest deviation (radians).
pub fn rotation_curve(times: &[f32], values: &[Quat], interp: Interp) -> (Curve<Quat>, f32) {
    rotation_curve_known(times, values, interp, 0.0)
}

/// [`rotation_curve`] given `known`, an error measured already on an interval of the same import
/// as this function measures it ([`certain_interval_error`]; 0 for none): an interval whose first
/// pieces certainly suffice and whose error cannot be above the larger of `known` and the largest
/// measured here so far is not measured. The curve is the same; the error returned is the largest
/// measured here, and the larger of it and `known` is the largest [`rotation_curve`] would
/// report over both channels (the same bits).
pub fn rotation_curve_known(
    times: &[f32],
    values: &[Quat],
    interp: Interp,
    known: f32,
) -> (Curve<Quat>, f32) {
    let n = times.len();
    let key = |k: usize| rotation_key(values, interp, k);
    let mut out_t = Vec::with_capacity(n);
    let mut out_v = Vec::with_capacity(n);
    let mut worst = 0.0f32;
    let mut ratios = Vec::new();
    for k in 0..n {
        if k > 0 {
            let (t0, t1) = (times[k - 1], times[k]);
            if interp == Interp::Step {
                let tb = prev_float(t1);
                if tb > t0 {
                    out_t.push(tb);
                    out_v.push(key(k - 1));
                }
            }
            if let Some(span) = rotation_span(times, values, interp, k) {
                // Fewer pieces than the first that is not certainly too few would be measured
                // too few: they are not measured. And where that many are certainly enough and
                // their error cannot be the largest so far, it is not measured either: the curve
                // and the largest error are those of measuring every level from one piece.
                let (mut pieces, enough) = span.first_pieces();
                if enough.is_some_and(|bound| bound <= worst.max(known)) {
                    for (t, s) in inner_times(t0, t1, pieces) {
                        out_t.push(t);
                        out_v.push(span.at(s));
                    }
                    out_t.push(times[k]);
                    out_v.push(key(k));
                    continue;
                }
                let mut ends = piece_ends(&span, pieces);
                let mut e = span.nlerp_error(pieces, &ends, above(pieces), &mut ratios);
                while e > ROTATION_TOLERANCE && pieces < MAX_SUBDIVISIONS {
                    pieces *= 2;
                    ends = (0..=pieces)
                        .map(|p| {
                            if p % 2 == 0 {
                                ends[p / 2]
                            } else {
                                span.at(p as f32 / pieces as f32)
                            }
                        })
                        .collect();
                    e = span.nlerp_error(pieces, &ends, above(pieces), &mut ratios);
                }
                worst = worst.max(e);
                for (t, s) in inner_times(t0, t1, pieces) {
                    out_t.push(t);
                    out_v.push(span.at(s));
                }
            }
        }
        out_t.push(times[k]);
        out_v.push(key(k));
    }
    (Curve::new(out_t, out_v), worst)
}

/// Of a rotation channel's intervals whose first pieces certainly suffice
/// ([`RotationSpan::first_pieces`]), the one with the largest bound on its error: (the bound, the
/// key it ends at). Without measuring: what an import measures first ([`certain_interval_error`])
/// so that [`rotation_curve_known`] can leave out the intervals that cannot exceed it.
pub fn largest_certain(times: &[f32], values: &[Quat], interp: Interp) -> Option<(f32, usize)> {
    if interp != Interp::Linear {
        return None;
    }
    (1..times.len())
        .filter_map(|k| {
            let span = rotation_span(times, values, interp, k)?;
            span.first_pieces().1.map(|bound| (bound, k))
        })
        .fold(None, |best: Option<(f32, usize)>, (bound, k)| match best {
            Some((b, _)) if b >= bound => best,
            _ => Some((bound, k)),
        })
}

/// The error [`rotation_curve`] measures on the interval ending at key `k` when its first pieces
/// certainly suffice, as it measures it (`None` otherwise, or if the measurement is above the
/// tolerance after all).
pub fn certain_interval_error(
    times: &[f32],
    values: &[Quat],
    interp: Interp,
    k: usize,
) -> Option<f32> {
    if k == 0 || k >= times.len() {
        return None;
    }
    let span = rotation_span(times, values, interp, k)?;
    let (pieces, enough) = span.first_pieces();
    enough?;
    let e = span.nlerp_error(
        pieces,
        &piece_ends(&span, pieces),
        above(pieces),
        &mut Vec::new(),
    );
    (e <= ROTATION_TOLERANCE).then_some(e)
}

/// The quaternion itself when it is unit length to within 1e-6, else normalised.
pub fn unit(q: Quat) -> Quat {
    if (q.length_squared() - 1.0).abs() <= 2e-6 {
        q
    } else {
        q.normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A xorshift generator of values in [-1, 1] from `seed`.
    fn xorshift(mut s: u32) -> impl FnMut() -> f32 {
        move || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            s as f32 / u32::MAX as f32 * 2.0 - 1.0
        }
    }

    /// The conversion as first written (a fresh slerp per parameter, every piece's ends evaluated
    /// again): the reference the faster `rotation_curve` must match bit for bit.
    fn rotation_curve_reference(
        times: &[f32],
        values: &[Quat],
        interp: Interp,
    ) -> (Vec<f32>, Vec<Quat>, f32) {
        fn slerp_alone(a: Quat, b: Quat, s: f32) -> Quat {
            let mut d = a.dot(b);
            let b = if d < 0.0 {
                d = -d;
                -b
            } else {
                b
            };
            if d > 0.9999995 {
                return (a * (1.0 - s) + b * s).normalize();
            }
            let ang = d.min(1.0).acos();
            let sn = ang.sin();
            (a * (((1.0 - s) * ang).sin() / sn) + b * ((s * ang).sin() / sn)).normalize()
        }
        let key = |k: usize| {
            unit(match interp {
                Interp::Cubic => values[3 * k + 1],
                _ => values[k],
            })
        };
        let (mut out_t, mut out_v, mut worst) = (Vec::new(), Vec::new(), 0.0f32);
        for k in 0..times.len() {
            if k > 0 {
                let (t0, t1) = (times[k - 1], times[k]);
                let (q0, q1) = (key(k - 1), key(k));
                let exact = |s: f32| match interp {
                    Interp::Cubic => {
                        let q = hermite(
                            values[3 * (k - 1) + 1],
                            values[3 * (k - 1) + 2],
                            values[3 * k + 1],
                            values[3 * k],
                            t1 - t0,
                            s,
                        );
                        if s <= 0.0 {
                            q0
                        } else if s >= 1.0 {
                            q1
                        } else {
                            q.normalize()
                        }
                    }
                    _ => slerp_alone(q0, q1, s),
                };
                let err_at = |pieces: usize| {
                    let mut e = 0.0f32;
                    for p in 0..pieces {
                        let (s0, s1) = (p as f32 / pieces as f32, (p + 1) as f32 / pieces as f32);
                        let (y0, y1) = (exact(s0), exact(s1));
                        for q in 1..6 {
                            let u = q as f32 / 6.0;
                            e = e.max(rotation_angle(nlerp(y0, y1, u), exact(s0 + (s1 - s0) * u)));
                        }
                    }
                    e
                };
                let mut pieces = 1;
                let mut e = err_at(1);
                while e > ROTATION_TOLERANCE && pieces < MAX_SUBDIVISIONS {
                    pieces *= 2;
                    e = err_at(pieces);
                }
                worst = worst.max(e);
                for (t, s) in inner_times(t0, t1, pieces) {
                    out_t.push(t);
                    out_v.push(exact(s));
                }
            }
            out_t.push(times[k]);
            out_v.push(key(k));
        }
        (out_t, out_v, worst)
    }

    #[test]
    fn rotation_curves_match_the_reference_bit_for_bit() {
        let mut rnd = xorshift(0x2545_f491);
        let (mut inserted, mut most) = (0, 0);
        for case in 0..400 {
            let n = 2 + case % 7;
            let times: Vec<f32> = (0..n)
                .map(|k| k as f32 * (0.01 + 0.2 * (case % 5) as f32))
                .collect();
            // Steps from tiny to large angles, and a flip to the other hemisphere now and then.
            let step = [0.001f32, 0.05, 0.3, 1.5][case % 4];
            let mut q = Quat::from_xyzw(rnd(), rnd(), rnd(), rnd()).normalize();
            let mut keys = Vec::new();
            for k in 0..n {
                let turn = Quat::from_axis_angle(
                    glam::Vec3::new(rnd(), rnd(), rnd() + 2.0).normalize(),
                    step * (1.0 + rnd() * 0.5),
                );
                q = (turn * q).normalize();
                keys.push(if k % 3 == 2 { -q } else { q });
            }
            for interp in [Interp::Linear, Interp::Cubic] {
                let values: Vec<Quat> = match interp {
                    Interp::Cubic => keys
                        .iter()
                        .flat_map(|&q| {
                            let t = Quat::from_xyzw(rnd(), rnd(), rnd(), rnd()) * step;
                            [t, q, t * -0.5]
                        })
                        .collect(),
                    _ => keys.clone(),
                };
                let (curve, worst) = rotation_curve(&times, &values, interp);
                let (t, v, w) = rotation_curve_reference(&times, &values, interp);
                assert_eq!(curve.times, t, "case {case} {interp:?}");
                let bits = |q: &[Quat]| -> Vec<[u32; 4]> {
                    q.iter().map(|q| q.to_array().map(f32::to_bits)).collect()
                };
                assert_eq!(bits(&curve.values), bits(&v), "case {case} {interp:?}");
                assert_eq!(worst.to_bits(), w.to_bits());
                inserted += t.len() - n;
                most = most.max(t.len() - n);
            }
        }
        // The cases subdivide (the halving and the reuse of the ends are exercised), and some
        // interval reaches the most pieces (where the error is measured in full at every level).
        assert!(inserted > 100, "{inserted}");
        assert!(most >= MAX_SUBDIVISIONS - 1, "{most}");
    }
    #[test]
    fn the_cubic_term_bounds_the_slerp_deviation_below_a_tenth_of_a_radian() {
        // `Slerp::sampled_deviation`'s shortcut against the formula it stands for.
        let exact = |a: f64| -> f64 {
            [1.0 / 6.0, 2.0 / 6.0]
                .iter()
                .map(|&u| (u * a - (u * a.sin()).atan2(1.0 - u + u * a.cos())).abs())
                .fold(0.0, f64::max)
        };
        for k in 1..=1000 {
            let a = 0.1 * f64::from(k) / 1000.0;
            let (cubic, d) = (0.015438 * a * a * a, exact(a));
            assert!(cubic >= d && cubic <= d * 1.0004, "{a} {cubic} {d}");
        }
        // Above it the formula itself is used: the shortcut would no longer bound it.
        assert!(0.015438 * 0.2f64.powi(3) < exact(0.2));
    }

    #[test]
    fn the_measured_slerp_error_is_its_analytic_value_within_half_the_margin() {
        // `ROUNDING_MARGIN` decides levels without measuring them: the single-precision
        // measurement must stay within half of it of the analytic value, at every number of
        // pieces, over spans from 0.001 to 3.75 rad (4D angles up to 1.9); where it is large, the
        // two agree to 0.1% (the same quantity, not merely both small).
        let mut rnd = xorshift(0x2545_f491);
        let (mut worst, mut compared, mut ratios) = (0.0f64, 0, Vec::new());
        for case in 0..3000 {
            let q0 = Quat::from_xyzw(rnd(), rnd(), rnd(), rnd()).normalize();
            let angle = [0.001f32, 0.01, 0.05, 0.3, 1.0, 2.5][case % 6] * (1.0 + rnd() * 0.5);
            let axis = Vec3::new(rnd(), rnd(), rnd() + 2.0).normalize();
            let q1 = (Quat::from_axis_angle(axis, angle) * q0).normalize();
            // Half the cases with keys as long as `unit` keeps them (within 1e-6 of unit length).
            let (q0, q1) = if (case / 6) % 2 == 1 {
                (
                    unit(q0 * (1.0 + 9.9e-7 * rnd())),
                    unit(q1 * (1.0 + 9.9e-7 * rnd())),
                )
            } else {
                (q0, q1)
            };
            let slerp = Slerp::new(q0, q1);
            let span = RotationSpan::Linear(Slerp::new(q0, q1));
            for pieces in [1usize, 2, 4, 8, 16, 32, 64, 128, 256] {
                let ends: Vec<Quat> = (0..=pieces)
                    .map(|p| span.at(p as f32 / pieces as f32))
                    .collect();
                let measured = f64::from(span.nlerp_error(pieces, &ends, None, &mut ratios));
                let analytic = slerp.sampled_deviation(pieces);
                let off = (measured - analytic).abs();
                assert!(
                    off <= ROUNDING_MARGIN / 2.0 + 1e-3 * analytic,
                    "{measured} {analytic}"
                );
                if analytic < 1e-5 {
                    worst = worst.max(off);
                    compared += 1;
                }
            }
        }
        assert!(compared > 10_000, "{compared}");
        assert!(worst <= ROUNDING_MARGIN / 2.0, "{worst:e}");
    }
    #[test]
    fn a_known_error_leaves_the_curves_and_the_largest_error_as_they_are() {
        // What the glTF import does over an animation's channels: the interval with the largest
        // bound among those certainly within the tolerance measured first, then every channel
        // given that error. The same curves bit for bit, and the same largest error over the
        // channels, as each channel converted alone.
        let mut rnd = xorshift(0x1234_5678);
        let mut witnessed = 0;
        for case in 0..40 {
            // Four channels of fine and coarse steps (a capture's small turns and a keyed clip's).
            let channels: Vec<(Vec<f32>, Vec<Quat>)> = (0..4)
                .map(|c| {
                    let n = 20 + (case + c) % 30;
                    let times: Vec<f32> = (0..n).map(|k| k as f32 / 30.0).collect();
                    // Every other case only steps that no interval needs more pieces for (its
                    // largest error is then among the intervals that may be left out).
                    let steps = if case % 2 == 0 {
                        [0.002f32, 0.005, 0.01, 0.02]
                    } else {
                        [0.002, 0.02, 0.08, 0.6]
                    };
                    let step = steps[(case + c) % 4];
                    let mut q = Quat::from_xyzw(rnd(), rnd(), rnd(), rnd()).normalize();
                    let keys = (0..n)
                        .map(|_| {
                            let axis = Vec3::new(rnd(), rnd(), rnd() + 2.0).normalize();
                            q = (Quat::from_axis_angle(axis, step * (1.0 + rnd() * 0.5)) * q)
                                .normalize();
                            q
                        })
                        .collect();
                    (times, keys)
                })
                .collect();
            let alone: Vec<(Curve<Quat>, f32)> = channels
                .iter()
                .map(|(t, v)| rotation_curve(t, v, Interp::Linear))
                .collect();
            let largest = alone.iter().fold(0.0f32, |m, c| m.max(c.1));
            let witness = channels
                .iter()
                .enumerate()
                .filter_map(|(i, (t, v))| {
                    largest_certain(t, v, Interp::Linear).map(|(b, k)| (b, i, k))
                })
                .fold(None, |best: Option<(f32, usize, usize)>, c| match best {
                    Some(b) if b.0 >= c.0 => best,
                    _ => Some(c),
                });
            let known = witness.map_or(0.0, |(_, i, k)| {
                let (t, v) = &channels[i];
                certain_interval_error(t, v, Interp::Linear, k).unwrap_or(0.0)
            });
            witnessed += usize::from(known > 0.0);
            let mut seeded = known;
            for ((t, v), (curve, _)) in channels.iter().zip(&alone) {
                let (c, e) = rotation_curve_known(t, v, Interp::Linear, known);
                assert_eq!(c.times, curve.times, "case {case}");
                let bits = |q: &[Quat]| -> Vec<[u32; 4]> {
                    q.iter().map(|q| q.to_array().map(f32::to_bits)).collect()
                };
                assert_eq!(bits(&c.values), bits(&curve.values), "case {case}");
                seeded = seeded.max(e);
            }
            assert_eq!(seeded.to_bits(), largest.to_bits(), "case {case}");
        }
        assert!(witnessed >= 30, "{witnessed}");
    }
}
