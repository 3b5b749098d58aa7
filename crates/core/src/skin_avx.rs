//! The AVX kernel behind [`crate::skin`]: two vertices per 256-bit register, one in each 128-bit half.
//!
//! Every lane does exactly the IEEE operations of the portable per-vertex code in
//! [`crate::skinning`], in the same order (the blend `((P0*w0 + P1*w1) + P2*w2) + P3*w3` per column,
//! `((m0*x + m1*y) + m2*z) + m3` for a position, the cofactor normal with its shuffles, the length
//! summed as glam's `dot` sums, one `sqrt` and one division); there is no FMA and no reassociation,
//! so the results are the same bits as the portable code (unit tests compare them). What changes is
//! how many instructions carry them: a 256-bit multiply does two vertices' column at once, the
//! weights and coordinates of two vertices are broadcast by in-lane permutes, and the normal's
//! zero-length and mirror cases are selected with masks instead of branches.
//!
//! The kernel stops before the first pair of vertices that names a joint outside the palette and
//! returns how many vertices it wrote; the caller finishes (and reports the error) with the
//! portable code. It depends on nothing of the crate but the data it is given.

use glam::{Mat4, Vec3, Vec4};
#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

/// What the skinning loops do with normals.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Normals {
    /// No normals: positions only.
    None,
    /// Through the cofactor of the blended 3x3, sign-corrected and normalised.
    Cofactor,
    /// Through the blended 3x3 itself, not normalised.
    Matrix,
}

/// Skins vertices two at a time (see the module docs); returns the number of vertices written, an
/// even number, which is less than `positions.len()` when the vertex count is odd or a pair names a
/// joint outside `palette`. Per-vertex slices are read up to the shortest of them; `normals` and
/// `out_normals` are not touched with [`Normals::None`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[allow(clippy::too_many_arguments)]
pub(crate) fn skin_pairs(
    palette: &[Mat4],
    positions: &[Vec3],
    normals: &[Vec3],
    joints: &[[u16; 4]],
    weights: &[[f32; 4]],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
    mode: Normals,
) -> usize {
    match mode {
        Normals::None => pairs::<0>(
            palette,
            positions,
            positions,
            joints,
            weights,
            out_positions,
            &mut [],
        ),
        Normals::Cofactor => pairs::<1>(
            palette,
            positions,
            normals,
            joints,
            weights,
            out_positions,
            out_normals,
        ),
        Normals::Matrix => pairs::<2>(
            palette,
            positions,
            normals,
            joints,
            weights,
            out_positions,
            out_normals,
        ),
    }
}

/// `lo` in the low 128 bits, `hi` in the high.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
fn pair(lo: Vec4, hi: Vec4) -> __m256 {
    _mm256_set_m128(hi.into(), lo.into())
}

/// The two 128-bit halves of `v`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
fn halves(v: __m256) -> (Vec4, Vec4) {
    (
        Vec4::from(_mm256_castps256_ps128(v)),
        Vec4::from(_mm256_extractf128_ps::<1>(v)),
    )
}

/// Shuffle immediates (lane 0 in the low two bits) of glam's `zxy`, `yzx` and the broadcasts.
#[cfg(target_arch = "x86_64")]
const ZXY: i32 = 0b11_01_00_10;
#[cfg(target_arch = "x86_64")]
const YZX: i32 = 0b11_00_10_01;
#[cfg(target_arch = "x86_64")]
const XXXX: i32 = 0b00_00_00_00;
#[cfg(target_arch = "x86_64")]
const YYYY: i32 = 0b01_01_01_01;
#[cfg(target_arch = "x86_64")]
const ZZZZ: i32 = 0b10_10_10_10;
#[cfg(target_arch = "x86_64")]
const WWWW: i32 = 0b11_11_11_11;

/// `MODE`: 0 positions only, 1 cofactor normals, 2 normals through the matrix (see [`Normals`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
#[inline]
fn pairs<const MODE: u8>(
    palette: &[Mat4],
    positions: &[Vec3],
    normals: &[Vec3],
    joints: &[[u16; 4]],
    weights: &[[f32; 4]],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) -> usize {
    let mut n = positions
        .len()
        .min(joints.len())
        .min(weights.len())
        .min(out_positions.len());
    if MODE != 0 {
        n = n.min(normals.len()).min(out_normals.len());
    }
    // Pairs `(v, v + 1)` with `v + 2 < n`: a vertex's coordinates are read as 16 bytes, its three
    // floats and the next vertex's x, which exists for both vertices of such a pair.
    let count = if n >= 3 { (n - 1) / 2 } else { 0 };
    let zero = _mm256_setzero_ps();
    let infinity = _mm256_set1_ps(f32::INFINITY);
    let sign = _mm256_set1_ps(-0.0);
    let (position_floats, normal_floats) = (
        positions.as_ptr().cast::<f32>(),
        normals.as_ptr().cast::<f32>(),
    );
    // Two vertices' coordinates, each as `(x, y, z, next x)` in its half.
    let coordinates = |base: *const f32, v: usize| {
        // SAFETY: `glam::Vec3` is `#[repr(C)]` of three `f32`, so `base` (the slice's start) points
        // at `3 * len` consecutive floats; the loads read floats `3v .. 3v + 8`, and `v + 2 < n`
        // (see `count`) keeps them below `3n`, inside the slice. Unaligned loads need no alignment.
        #[allow(unsafe_code)]
        unsafe {
            _mm256_loadu2_m128(base.add(3 * v + 3), base.add(3 * v))
        }
    };
    let vertices = joints
        .chunks_exact(2)
        .zip(weights.chunks_exact(2))
        .zip(out_positions.chunks_exact_mut(2))
        .take(count)
        .enumerate();
    let mut done = 0;
    for (k, ((j, w), op)) in vertices {
        let v = 2 * k;
        let (ja, jb) = (&j[0], &j[1]);
        let get = |j: u16| palette.get(j as usize);
        let (Some(a0), Some(a1), Some(a2), Some(a3)) =
            (get(ja[0]), get(ja[1]), get(ja[2]), get(ja[3]))
        else {
            break;
        };
        let (Some(b0), Some(b1), Some(b2), Some(b3)) =
            (get(jb[0]), get(jb[1]), get(jb[2]), get(jb[3]))
        else {
            break;
        };
        let w = pair(Vec4::from_array(w[0]), Vec4::from_array(w[1]));
        let (w0, w1, w2, w3) = (
            _mm256_permute_ps::<XXXX>(w),
            _mm256_permute_ps::<YYYY>(w),
            _mm256_permute_ps::<ZZZZ>(w),
            _mm256_permute_ps::<WWWW>(w),
        );
        let column = |c: usize| {
            let s = _mm256_add_ps(
                _mm256_mul_ps(pair(a0.col(c), b0.col(c)), w0),
                _mm256_mul_ps(pair(a1.col(c), b1.col(c)), w1),
            );
            let s = _mm256_add_ps(s, _mm256_mul_ps(pair(a2.col(c), b2.col(c)), w2));
            _mm256_add_ps(s, _mm256_mul_ps(pair(a3.col(c), b3.col(c)), w3))
        };
        let (m0, m1, m2, m3) = (column(0), column(1), column(2), column(3));
        // `((m0 * x + m1 * y) + m2 * z)` with each vertex's coordinates broadcast in its half.
        let through = |p: __m256| {
            let s = _mm256_add_ps(
                _mm256_mul_ps(m0, _mm256_permute_ps::<XXXX>(p)),
                _mm256_mul_ps(m1, _mm256_permute_ps::<YYYY>(p)),
            );
            _mm256_add_ps(s, _mm256_mul_ps(m2, _mm256_permute_ps::<ZZZZ>(p)))
        };
        let (pa, pb) = halves(_mm256_add_ps(through(coordinates(position_floats, v)), m3));
        op[0] = pa.truncate();
        op[1] = pb.truncate();
        if MODE == 0 {
            done = v + 2;
            continue;
        }
        let Some(on) = out_normals.get_mut(v..v + 2) else {
            break;
        };
        let nrm = coordinates(normal_floats, v);
        let out = if MODE == 2 {
            through(nrm)
        } else {
            // The cofactor normal in `yzx` lane order and the determinant's three products, as
            // `skinning::cofactor_normal`.
            let (s0, s1, s2) = (
                _mm256_permute_ps::<ZXY>(m0),
                _mm256_permute_ps::<ZXY>(m1),
                _mm256_permute_ps::<ZXY>(m2),
            );
            let c0 = _mm256_sub_ps(_mm256_mul_ps(s1, m2), _mm256_mul_ps(m1, s2));
            let c1 = _mm256_sub_ps(_mm256_mul_ps(s2, m0), _mm256_mul_ps(m2, s0));
            let c2 = _mm256_sub_ps(_mm256_mul_ps(s0, m1), _mm256_mul_ps(m0, s1));
            let r = _mm256_add_ps(
                _mm256_add_ps(
                    _mm256_mul_ps(c0, _mm256_permute_ps::<XXXX>(nrm)),
                    _mm256_mul_ps(c1, _mm256_permute_ps::<YYYY>(nrm)),
                ),
                _mm256_mul_ps(c2, _mm256_permute_ps::<ZZZZ>(nrm)),
            );
            let d = _mm256_mul_ps(_mm256_permute_ps::<YZX>(m0), c0);
            // `skinning::normalize_yzx`: |r| as `(x*x + y*y) + z*z`, the determinant as
            // `(x + y) + z`, both in lane 0 of each half and broadcast from there.
            let rr = _mm256_mul_ps(r, r);
            let dot = _mm256_add_ps(
                _mm256_add_ps(rr, _mm256_permute_ps::<YYYY>(rr)),
                _mm256_permute_ps::<ZZZZ>(rr),
            );
            let len = _mm256_sqrt_ps(_mm256_permute_ps::<XXXX>(dot));
            let det = _mm256_add_ps(
                _mm256_add_ps(d, _mm256_permute_ps::<YYYY>(d)),
                _mm256_permute_ps::<ZZZZ>(d),
            );
            let det = _mm256_permute_ps::<XXXX>(det);
            let mirrored = _mm256_cmp_ps::<_CMP_LT_OQ>(det, zero);
            // Ordered compares: a NaN length is not "ok", as with `len > 0.0 && len < INFINITY`.
            let ok = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OQ>(len, zero),
                _mm256_cmp_ps::<_CMP_LT_OQ>(len, infinity),
            );
            let len = _mm256_blendv_ps(len, _mm256_xor_ps(len, sign), mirrored);
            let unit = _mm256_permute_ps::<ZXY>(_mm256_div_ps(r, len));
            _mm256_and_ps(unit, ok)
        };
        let (na, nb) = halves(out);
        on[0] = na.truncate();
        on[1] = nb.truncate();
        done = v + 2;
    }
    done
}
