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

/// Normalised lerp along the shortest path, as the runtime does it.
pub fn nlerp(a: Quat, b: Quat, s: f32) -> Quat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    (a * (1.0 - s) + b * s).normalize()
}

/// Angle in radians between two rotations.
pub fn rotation_angle(a: Quat, b: Quat) -> f32 {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    2.0 * (a - b).length().atan2((a + b).length())
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

/// Converts a rotation channel. Values are normalised copies of the glTF quaternions (bit-exact when the
/// glTF value is already unit length to within 1e-6). Returns the curve and the largest deviation (radians).
pub fn rotation_curve(times: &[f32], values: &[Quat], interp: Interp) -> (Curve<Quat>, f32) {
    let n = times.len();
    let key = |k: usize| {
        let q = match interp {
            Interp::Cubic => values[3 * k + 1],
            _ => values[k],
        };
        unit(q)
    };
    let mut out_t = Vec::with_capacity(n);
    let mut out_v = Vec::with_capacity(n);
    let mut worst = 0.0f32;
    for k in 0..n {
        if k > 0 {
            let (t0, t1) = (times[k - 1], times[k]);
            let (q0, q1) = (key(k - 1), key(k));
            let exact: Box<dyn Fn(f32) -> Quat> = match interp {
                Interp::Step => {
                    let tb = prev_float(t1);
                    if tb > t0 {
                        out_t.push(tb);
                        out_v.push(q0);
                    }
                    Box::new(|_| q0)
                }
                Interp::Linear => Box::new(move |s| slerp(q0, q1, s)),
                Interp::Cubic => {
                    let td = t1 - t0;
                    let (b0, a1) = (values[3 * (k - 1) + 2], values[3 * k]);
                    let (r0, r1) = (values[3 * (k - 1) + 1], values[3 * k + 1]);
                    Box::new(move |s| {
                        let q = hermite(r0, b0, r1, a1, td, s);
                        if s <= 0.0 {
                            q0
                        } else if s >= 1.0 {
                            q1
                        } else {
                            q.normalize()
                        }
                    })
                }
            };
            if interp != Interp::Step {
                let err_at = |pieces: usize| -> f32 {
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
        }
        out_t.push(times[k]);
        out_v.push(key(k));
    }
    (Curve::new(out_t, out_v), worst)
}

/// The quaternion itself when it is unit length to within 1e-6, else normalised.
pub fn unit(q: Quat) -> Quat {
    if (q.length_squared() - 1.0).abs() <= 2e-6 {
        q
    } else {
        q.normalize()
    }
}
