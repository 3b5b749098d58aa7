//! Structure-of-arrays poses: four joints per block, one SIMD lane per joint.
//!
//! The per-frame path of the [`crate::Animator`] keeps poses as *blocks*: block `b` holds joints
//! `4b .. 4b + 4` of the skeleton, one lane each, as ten four-lane vectors (translation x y z, rotation
//! x y z w, scale x y z). Sampling, blending and resolving then work on four joints per instruction,
//! with no per-joint branching, and local-to-model reads each joint's values straight from its lane.
//!
//! Every operation here does, lane by lane, exactly the IEEE operations of the per-joint code it
//! stands in for ([`crate::Sampler::sample`], [`crate::BlendBuffers`], glam's `Quat` arithmetic), in
//! the same order, so the two paths give the same bits; tests compare them. Dot products of
//! quaternions are summed as glam sums them: `(x0*x1 + z0*z1) + (y0*y1 + w0*w1)`.

use crate::Transform;
use glam::{BVec4A, Mat4, Vec4};

/// Vectors per block.
pub(crate) const COMPONENTS: usize = 10;
/// One block: [`COMPONENTS`] vectors.
pub(crate) type Block = [Vec4; COMPONENTS];
/// First translation component in a block (x, y, z follow).
pub(crate) const T: usize = 0;
/// First rotation component in a block (x, y, z, w follow).
pub(crate) const R: usize = 3;
/// First scale component in a block (x, y, z follow).
pub(crate) const S: usize = 7;

/// Blocks needed for `joints` joints.
pub(crate) fn block_count(joints: usize) -> usize {
    joints.div_ceil(4)
}

/// `v`'s lanes where `mask` is set, `fallback`'s elsewhere.
#[inline(always)]
pub(crate) fn select(mask: BVec4A, v: Vec4, fallback: Vec4) -> Vec4 {
    Vec4::select(mask, v, fallback)
}

/// Lane masks for every four-bit pattern.
const LANES: [BVec4A; 16] = {
    let mut out = [BVec4A::new(false, false, false, false); 16];
    let mut bits = 0;
    while bits < 16 {
        out[bits] = BVec4A::new(bits & 1 != 0, bits & 2 != 0, bits & 4 != 0, bits & 8 != 0);
        bits += 1;
    }
    out
};

/// A lane mask from the low four bits of `bits` (bit `l` = lane `l`).
#[inline(always)]
pub(crate) fn lanes(bits: u8) -> BVec4A {
    LANES[(bits & 15) as usize]
}

/// Square root per lane (compiles to one `sqrtps` on x86_64).
#[inline(always)]
pub(crate) fn sqrt4(v: Vec4) -> Vec4 {
    Vec4::new(v.x.sqrt(), v.y.sqrt(), v.z.sqrt(), v.w.sqrt())
}

/// Quaternion dot product per lane, summed in glam's order.
#[inline(always)]
pub(crate) fn dot_q(a: &[Vec4; 4], b: &[Vec4; 4]) -> Vec4 {
    (a[0] * b[0] + a[2] * b[2]) + (a[1] * b[1] + a[3] * b[3])
}

/// `q * (1 / |q|)` per lane: the runtime's normalisation
/// ([`normalize_rotation`](crate::rotation::normalize_rotation) for one quaternion).
/// One division per four quaternions instead of four: the divider, not the adders, is what limits
/// sampling and blending, and the result is within an ulp of `q / |q|`.
#[inline(always)]
pub(crate) fn normalize_q(q: [Vec4; 4]) -> [Vec4; 4] {
    let inv = Vec4::ONE / sqrt4(dot_q(&q, &q));
    q.map(|c| c * inv)
}

/// `q` negated (multiplied by -1, as glam's `-q`) in the lanes where `d < 0`.
#[inline(always)]
pub(crate) fn negate_where_negative(q: [Vec4; 4], d: Vec4) -> [Vec4; 4] {
    let sign = select(d.cmplt(Vec4::ZERO), Vec4::NEG_ONE, Vec4::ONE);
    q.map(|c| c * sign)
}

/// The rotation components of a block.
#[inline(always)]
pub(crate) fn rotation(block: &Block) -> [Vec4; 4] {
    [block[R], block[R + 1], block[R + 2], block[R + 3]]
}

/// One block holding up to four transforms (lanes past the end are the identity).
#[inline(always)]
pub(crate) fn block_of(four: &[Transform]) -> Block {
    let t = |l: usize| four.get(l).copied().unwrap_or(Transform::IDENTITY);
    let (a, b, c, d) = (t(0), t(1), t(2), t(3));
    let v3 = |v: glam::Vec3| v.extend(0.0);
    let tr = glam::Mat4::from_cols(
        v3(a.translation),
        v3(b.translation),
        v3(c.translation),
        v3(d.translation),
    )
    .transpose();
    let r = glam::Mat4::from_cols(
        a.rotation.into(),
        b.rotation.into(),
        c.rotation.into(),
        d.rotation.into(),
    )
    .transpose();
    let s = glam::Mat4::from_cols(v3(a.scale), v3(b.scale), v3(c.scale), v3(d.scale)).transpose();
    [
        tr.x_axis, tr.y_axis, tr.z_axis, r.x_axis, r.y_axis, r.z_axis, r.w_axis, s.x_axis,
        s.y_axis, s.z_axis,
    ]
}

/// Blocks holding `transforms` (lanes past the end are the identity).
pub(crate) fn from_transforms(transforms: &[Transform]) -> Vec<Vec4> {
    let mut out = vec![Vec4::ZERO; block_count(transforms.len()) * COMPONENTS];
    for (b, chunk) in transforms.chunks(4).enumerate() {
        let block = &mut out[b * COMPONENTS..(b + 1) * COMPONENTS];
        for (l, t) in chunk
            .iter()
            .copied()
            .chain(std::iter::repeat(Transform::IDENTITY))
            .take(4)
            .enumerate()
        {
            let values = [
                t.translation.x,
                t.translation.y,
                t.translation.z,
                t.rotation.x,
                t.rotation.y,
                t.rotation.z,
                t.rotation.w,
                t.scale.x,
                t.scale.y,
                t.scale.z,
            ];
            for (c, v) in values.into_iter().enumerate() {
                block[c][l] = v;
            }
        }
    }
    out
}

/// Writes the lanes of `block` selected by `lanes` (bit `l` = lane `l`) to `out[l]` (lanes past the end
/// of `out` are skipped).
#[inline]
pub(crate) fn write_transforms(block: &[Vec4], lanes: u8, out: &mut [Transform]) {
    let Some(block) = block.get(..COMPONENTS) else {
        return;
    };
    // Transposing turns the component vectors into one column per joint.
    let t = glam::Mat4::from_cols(block[T], block[T + 1], block[T + 2], Vec4::ZERO).transpose();
    let r = glam::Mat4::from_cols(block[R], block[R + 1], block[R + 2], block[R + 3]).transpose();
    let s = glam::Mat4::from_cols(block[S], block[S + 1], block[S + 2], Vec4::ZERO).transpose();
    for (l, o) in out.iter_mut().enumerate().take(4) {
        if lanes & (1 << l) != 0 {
            o.store(t.col(l), r.col(l), s.col(l));
        }
    }
}

/// Where a sampled block comes from, per channel kind: nothing animated, every driven lane animated, or
/// a mix (animated lanes interpolated, the others copied from the fixed values).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Source {
    Fixed,
    Animated,
    Mixed,
}

/// One block of four skeleton joints that a [`crate::ClipBinding`] samples.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PlanBlock {
    /// Skeleton block: joints `4 * block .. 4 * block + 4`.
    pub(crate) block: usize,
    /// Lanes whose joint the clip drives (bit `l` = lane `l`).
    pub(crate) driven: u8,
    /// Per kind (translation, rotation, scale): lanes holding an animated channel.
    pub(crate) animated: [u8; 3],
    /// Per kind, how the driven lanes are produced.
    pub(crate) source: [Source; 3],
    /// The values of lanes that are not animated: constants, bind values (the identity difference in
    /// an additive clip), and the identity transform in lanes of joints the clip does not drive.
    pub(crate) fixed: [Vec4; COMPONENTS],
}

impl PlanBlock {
    /// Classifies each kind from the lane masks.
    pub(crate) fn set_sources(&mut self) {
        for k in 0..3 {
            let anim = self.animated[k] & self.driven;
            self.source[k] = if anim == 0 {
                Source::Fixed
            } else if anim == self.driven {
                Source::Animated
            } else {
                Source::Mixed
            };
        }
    }
}

/// How a sampled block's rotations come out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Rotations {
    /// Normalised: [`crate::clip::nlerp`] between keys, a key normalised when the slots hold raw
    /// (decoded compressed) rotations. What [`crate::Sampler::sample`] returns.
    Normalized,
    /// As interpolated: the shortest-path weighted sum of the two keys, not normalised (a key as
    /// stored). What a blend takes: it normalises the sum of its layers once (see [`crate::blend`]).
    Interpolated,
}

/// Samples one block from two key slots (`c0`, `c1`: [`COMPONENTS`] vectors each, with the fixed values
/// in the lanes that are not animated) at weight `a` of `c1`, into `out`. `raw_rotations`: the slots
/// hold unnormalised rotations (decoded compressed keys).
///
/// Per lane this is [`crate::Sampler::sample`]'s arithmetic: `Vec3::lerp` for translation and scale,
/// [`crate::clip::nlerp`] for rotation (or its weighted sum alone, see [`Rotations`]), a copy at
/// `a == 0` and for values that are not animated.
#[inline(always)]
pub(crate) fn sample_block(
    plan: &PlanBlock,
    c0: &Block,
    c1: &Block,
    a: f32,
    raw_rotations: bool,
    rotations: Rotations,
    out: &mut Block,
) {
    let fixed = &plan.fixed;
    let (ta, tb) = (Vec4::splat(1.0 - a), Vec4::splat(a));
    for (kind, first) in [(0, T), (2, S)] {
        for c in first..first + 3 {
            out[c] = match plan.source[kind] {
                Source::Fixed => fixed[c],
                _ if a == 0.0 => c0[c],
                Source::Animated => c0[c] * ta + c1[c] * tb,
                Source::Mixed => select(
                    lanes(plan.animated[kind]),
                    c0[c] * ta + c1[c] * tb,
                    fixed[c],
                ),
            };
        }
    }
    let normalize = rotations == Rotations::Normalized;
    // A copy of key 0 (at `a == 0`, unless it must be normalised) already holds the fixed values in
    // the lanes that are not animated; computed values take those lanes from `fixed`.
    let copy = a == 0.0 && !(raw_rotations && normalize);
    let q = match plan.source[1] {
        Source::Fixed => [fixed[R], fixed[R + 1], fixed[R + 2], fixed[R + 3]],
        _ if copy => rotation(c0),
        _ if a == 0.0 => normalize_q(rotation(c0)),
        _ => {
            let (q0, q1) = (rotation(c0), rotation(c1));
            let q1 = negate_where_negative(q1, dot_q(&q0, &q1));
            let q = [
                q0[0] * ta + q1[0] * tb,
                q0[1] * ta + q1[1] * tb,
                q0[2] * ta + q1[2] * tb,
                q0[3] * ta + q1[3] * tb,
            ];
            if normalize {
                normalize_q(q)
            } else {
                q
            }
        }
    };
    if plan.source[1] == Source::Mixed && !copy {
        let m = lanes(plan.animated[1]);
        for (i, v) in q.into_iter().enumerate() {
            out[R + i] = select(m, v, fixed[R + i]);
        }
    } else {
        out[R..R + 4].copy_from_slice(&q);
    }
}

/// Vectors per accumulator block: translation 3, rotation 4, scale 3, total weight 1.
pub(crate) const ACCUM: usize = 11;
/// The total weight's vector in an accumulator block.
pub(crate) const W: usize = 10;

/// Adds one sampled block `p` of a normal layer (plan block `pb`) to the accumulators (see
/// [`crate::blend`] for the arithmetic, which this follows lane for lane). `mask` holds one vector of
/// per-joint factors per skeleton block.
#[inline(always)]
pub(crate) fn accumulate_block(
    accum: &mut [Vec4],
    pb: &PlanBlock,
    p: &Block,
    weight: f32,
    mask: Option<&[Vec4]>,
) {
    let b = pb.block;
    let Some(Ok(a)) = accum
        .get_mut(b * ACCUM..(b + 1) * ACCUM)
        .map(<&mut [Vec4; ACCUM]>::try_from)
    else {
        return;
    };
    let w = match mask {
        Some(m) => Vec4::splat(weight) * m.get(b).copied().unwrap_or(Vec4::ZERO),
        None => Vec4::splat(weight),
    };
    // Lanes that contribute: driven, with a weight above zero (NaN excluded). The others add
    // `value * 0`, which leaves a sum that never holds -0 unchanged (values are finite).
    let w = select(lanes(pb.driven) & w.cmpgt(Vec4::ZERO), w, Vec4::ZERO);
    let acc_r = [a[R], a[R + 1], a[R + 2], a[R + 3]];
    let q = negate_where_negative(rotation(p), dot_q(&acc_r, &rotation(p)));
    for c in 0..3 {
        a[T + c] += p[T + c] * w;
        a[S + c] += p[S + c] * w;
    }
    for (c, v) in q.into_iter().enumerate() {
        a[R + c] += v * w;
    }
    a[W] += w;
}

/// Writes the blend of the accumulated layers into `out` (one block per skeleton block), filling with
/// the bind pose (`bind`, blocks) where the total weight is below 1: [`crate::BlendBuffers::resolve`]
/// lane for lane.
#[inline(always)]
pub(crate) fn resolve(accum: &[Vec4], bind: &[Vec4], out: &mut [Vec4]) {
    let blocks = accum
        .chunks_exact(ACCUM)
        .zip(bind.chunks_exact(COMPONENTS))
        .zip(out.chunks_exact_mut(COMPONENTS));
    for ((a, b), o) in blocks {
        let (Ok(a), Ok(b), Ok(o)) = (
            <&[Vec4; ACCUM]>::try_from(a),
            <&Block>::try_from(b),
            <&mut Block>::try_from(o),
        ) else {
            continue;
        };
        let w = a[W];
        let r = [a[R], a[R + 1], a[R + 2], a[R + 3]];
        if w.cmpeq(Vec4::ONE).all() {
            // Every lane has weight exactly 1: the sums are the result (no division).
            o[T..T + 3].copy_from_slice(&a[T..T + 3]);
            o[S..S + 3].copy_from_slice(&a[S..S + 3]);
            for (i, v) in normalize_q(r).into_iter().enumerate() {
                o[R + i] = v;
            }
            continue;
        }
        // Weights of 1 or more are divided out (x / 1 == x exactly); between 0 and 1 the bind pose
        // fills the rest; anything else is the bind pose exactly.
        let full = w.cmpge(Vec4::ONE);
        let fill = w.cmpgt(Vec4::ZERO) & w.cmplt(Vec4::ONE);
        let blended = full | fill;
        let rest = Vec4::ONE - w;
        let br = negate_where_negative(rotation(b), dot_q(&r, &rotation(b)));
        for c in (T..T + 3).chain(S..S + 3) {
            let v = select(full, a[c] / w, a[c] + b[c] * rest);
            o[c] = select(blended, v, b[c]);
        }
        let r = [0, 1, 2, 3].map(|i| select(fill, r[i] + br[i] * rest, r[i]));
        for (i, v) in normalize_q(r).into_iter().enumerate() {
            o[R + i] = select(blended, v, b[R + i]);
        }
    }
}

/// A matrix's upper 3x4 entries, each broadcast to four lanes: entry `3 * c + r` is row `r` of column
/// `c`. Multiplying by a broadcast kept in memory saves the broadcast instruction of every use.
pub(crate) type Splats = [Vec4; 12];

/// `m`'s [`Splats`].
pub(crate) fn splats(m: &Mat4) -> Splats {
    let mut out = [Vec4::ZERO; 12];
    for c in 0..4 {
        for r in 0..3 {
            out[3 * c + r] = Vec4::splat(m.col(c)[r]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rotation::normalize_rotation;
    use glam::{Quat, Vec3};

    #[test]
    fn blocks_round_trip_transforms() {
        let ts: Vec<Transform> = (0..6)
            .map(|i| {
                let f = i as f32;
                Transform::new(
                    Vec3::new(f, -f, 2.0 * f),
                    Quat::from_rotation_y(0.1 * f),
                    Vec3::new(1.0 + f, 2.0, 3.0),
                )
            })
            .collect();
        let blocks = from_transforms(&ts);
        assert_eq!(blocks.len(), 2 * COMPONENTS);
        let mut back = vec![Transform::from_translation(Vec3::splat(9.0)); 8];
        for (b, block) in blocks.chunks_exact(COMPONENTS).enumerate() {
            write_transforms(block, 0b1111, &mut back[b * 4..]);
        }
        assert_eq!(back[..6], ts[..]);
        // Lanes past the end are the identity.
        assert_eq!(back[6..], [Transform::IDENTITY; 2]);
        // Only the selected lanes are written.
        let mut some = vec![Transform::IDENTITY; 4];
        write_transforms(&blocks, 0b0100, &mut some);
        assert_eq!(
            some,
            [
                Transform::IDENTITY,
                Transform::IDENTITY,
                ts[2],
                Transform::IDENTITY
            ]
        );
    }

    #[test]
    fn lane_arithmetic_is_glams() {
        let q0 = [
            Quat::from_rotation_x(0.3),
            Quat::from_xyzw(0.1, -0.7, 0.2, 0.5).normalize(),
            -Quat::from_rotation_z(2.0),
            Quat::from_xyzw(0.0, 0.0, 0.0, 1.0),
        ];
        let q1 = [
            Quat::from_rotation_y(-1.3),
            Quat::from_xyzw(-0.1, 0.7, -0.2, -0.5).normalize(),
            Quat::from_rotation_z(2.2),
            Quat::from_xyzw(0.0, -0.0, 1.0, 0.0),
        ];
        let soa = |q: &[Quat; 4]| -> [Vec4; 4] {
            [0, 1, 2, 3].map(|c| Vec4::from_array(q.map(|q| q.to_array()[c])))
        };
        let (a, b) = (soa(&q0), soa(&q1));
        let d = dot_q(&a, &b);
        let n = normalize_q(b.map(|v| v * 3.0));
        for l in 0..4 {
            assert_eq!(d[l].to_bits(), q0[l].dot(q1[l]).to_bits());
            let want = normalize_rotation(q1[l] * 3.0);
            for (c, w) in want.to_array().into_iter().enumerate() {
                assert_eq!(n[c][l].to_bits(), w.to_bits());
            }
        }
    }
}
