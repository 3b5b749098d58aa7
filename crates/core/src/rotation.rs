//! Rotation arithmetic the whole runtime shares: the one normalisation and the one nlerp.

use glam::Quat;

/// The runtime's normalisation of a rotation: `q * (1 / |q|)`, the length summed as glam's `dot` sums
/// (`(x*x + z*z) + (y*y + w*w)`). Sampling and blending normalise this way, four joints at a time
/// with the same per-lane operations (one division per four rotations instead of four); the result is
/// within an ulp of `q / |q|`.
#[inline]
pub fn normalize_rotation(q: Quat) -> Quat {
    q * q.length_recip()
}

/// Normalised lerp along the shortest path: `b` is negated when `a · b < 0`, then
/// `a * (1 - alpha) + b * alpha` is normalised with [`normalize_rotation`]. The sampler does exactly
/// this, four joints at a time.
#[inline]
pub fn nlerp(a: Quat, b: Quat, alpha: f32) -> Quat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    normalize_rotation(a * (1.0 - alpha) + b * alpha)
}
