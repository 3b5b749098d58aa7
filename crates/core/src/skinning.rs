//! Local-to-model transforms, the skinning palette, and linear blend skinning.
//!
//! These are the functions the runtime, the baker and the verifier all call, so that a bake checked
//! against the runtime is a bit-for-bit comparison. Every function has a fixed order of floating-point
//! operations: no reassociation, no FMA, no threading inside. The copies chosen at run time (AVX, see
//! `crate::cpu`; [`skin`]'s two-vertices-per-register kernel) perform the same operations in the same
//! order, so the same inputs give the same bits on every call and every x86_64 CPU.
//!
//! Inputs are validated up front (lengths, parent order, joint indices); a bad input is a
//! [`SkinError`], never a panic. On a joint-index error [`skin`] has already written the vertices before
//! the offending one; all other errors are reported before anything is written.

use crate::cpu::multiversion;
use crate::skeleton::JointIndex;
use crate::skin_avx::Normals;
use crate::soa::Splats;
use crate::{soa, Lod, Transform, MAX_INFLUENCES};
use glam::{Mat4, Vec3, Vec3A, Vec3Swizzles, Vec4};

/// Why a skinning step was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SkinError {
    /// Two buffers that must be parallel differ in length.
    #[error("{what} has {got} elements; expected {expected}")]
    Length {
        /// Which buffer.
        what: &'static str,
        /// Elements expected.
        expected: usize,
        /// Elements given.
        got: usize,
    },
    /// A joint's parent does not come before it.
    #[error("joint {joint} has parent {parent}, which does not come before it")]
    ParentOrder {
        /// The child.
        joint: usize,
        /// Its parent index.
        parent: usize,
    },
    /// A vertex names a joint outside the palette.
    #[error("vertex {vertex} uses joint {joint}, but the palette has {palette} matrices")]
    JointIndex {
        /// The vertex.
        vertex: usize,
        /// The joint index it names.
        joint: u16,
        /// Matrices in the palette.
        palette: usize,
    },
}

fn same_len(what: &'static str, expected: usize, got: usize) -> Result<(), SkinError> {
    if expected == got {
        Ok(())
    } else {
        Err(SkinError::Length {
            what,
            expected,
            got,
        })
    }
}

/// Model-space matrices from local transforms: `models[i] = models[parent(i)] * locals[i].to_mat4()`,
/// or `locals[i].to_mat4()` for a root. Parents must come before their children (as in a
/// [`Skeleton`](crate::Skeleton)).
///
/// Joints are taken four at a time: their local matrices `T * R * S` are built together, one joint per
/// SIMD lane, then each joint's model matrix is its parent's times its local
/// matrix, as the affine (3x4) product: it skips the terms that multiply the local matrix's zero bottom
/// row, so for affine matrices the result is the full product's up to rounding. Same bits as
/// [`local_to_model_and_palette`]'s `models`.
pub fn local_to_model(
    parents: &[Option<JointIndex>],
    locals: &[Transform],
    models: &mut [Mat4],
) -> Result<(), SkinError> {
    let n = parents.len();
    same_len("locals", n, locals.len())?;
    same_len("models", n, models.len())?;
    check_parents(parents)?;
    for (b, four) in locals.chunks(4).enumerate() {
        let local = local_matrices(&soa::block_of(four));
        for lane in 0..four.len() {
            let i = b * 4 + lane;
            models[i] = model_of(parents, models, i, &local, lane);
        }
    }
    Ok(())
}

multiversion! {
    /// [`local_to_model`] and [`skinning_palette`] in one pass over the joints (the model matrix is still
    /// in registers when the palette entry is made). The results are bit-identical to calling the two
    /// functions one after the other.
    pub fn local_to_model_and_palette(
        parents: &[Option<JointIndex>],
        locals: &[Transform],
        inverse_bind: &[Mat4],
        models: &mut [Mat4],
        palette: &mut [Mat4],
    ) -> Result<(), SkinError> => local_to_model_and_palette_generic;
}

#[inline(always)]
fn local_to_model_and_palette_generic(
    parents: &[Option<JointIndex>],
    locals: &[Transform],
    inverse_bind: &[Mat4],
    models: &mut [Mat4],
    palette: &mut [Mat4],
) -> Result<(), SkinError> {
    let n = parents.len();
    same_len("locals", n, locals.len())?;
    same_len("models", n, models.len())?;
    same_len("inverse bind matrices", n, inverse_bind.len())?;
    same_len("palette", n, palette.len())?;
    check_parents(parents)?;
    for (b, four) in locals.chunks(4).enumerate() {
        let local = local_matrices(&soa::block_of(four));
        for lane in 0..four.len() {
            let i = b * 4 + lane;
            let m = model_of(parents, models, i, &local, lane);
            models[i] = m;
            palette[i] = mul_affine(&m, &inverse_bind[i]);
        }
    }
    Ok(())
}

/// [`local_to_model_and_palette`] for `skeleton`, reading the local pose from blocks of four joints
/// (see [`crate::soa`]; joint `i` is lane `i % 4` of block `i / 4`). Same arithmetic, same bits.
///
/// All local matrices are built first (into `scratch`), then the joints are visited in the
/// skeleton's [`level_order`], which puts a joint's dependants a whole level later, so the CPU can
/// overlap independent joints instead of waiting on each parent.
pub(crate) fn local_to_model_and_palette_blocks(
    skeleton: &crate::Skeleton,
    blocks: &[Vec4],
    scratch: &mut Vec<f32>,
    models: &mut [Mat4],
    palette: &mut [Mat4],
) -> Result<(), SkinError> {
    let n = skeleton.len();
    same_len(
        "local blocks",
        soa::block_count(n) * soa::COMPONENTS,
        blocks.len(),
    )?;
    same_len("models", n, models.len())?;
    same_len("palette", n, palette.len())?;
    scratch.resize(soa::block_count(n) * LOCAL, 0.0);
    fill_local_matrices(blocks, scratch);
    models_and_palette_in_order(
        skeleton.parents(),
        skeleton.level_order(),
        skeleton.inverse_bind_splats(),
        scratch,
        models,
        palette,
    );
    Ok(())
}

multiversion! {
    /// [`local_matrices`] of every block of `blocks` into `scratch` (sized by the caller).
    fn fill_local_matrices(blocks: &[Vec4], scratch: &mut [f32]) -> () => fill_local_matrices_generic;
}

#[inline(always)]
fn fill_local_matrices_generic(blocks: &[Vec4], scratch: &mut [f32]) {
    for (block, local) in blocks
        .chunks_exact(soa::COMPONENTS)
        .zip(scratch.chunks_exact_mut(LOCAL))
    {
        if let (Ok(block), Ok(local)) = (
            <&soa::Block>::try_from(block),
            <&mut [f32; LOCAL]>::try_from(local),
        ) {
            *local = local_matrices(block);
        }
    }
}

multiversion! {
    /// Model matrices and palette entries of the joints in `order` (every joint once, after its
    /// parent), from the local matrices in `scratch`.
    fn models_and_palette_in_order(
        parents: &[Option<JointIndex>],
        order: &[JointIndex],
        inverse_bind: &[Splats],
        scratch: &[f32],
        models: &mut [Mat4],
        palette: &mut [Mat4],
    ) -> () => models_and_palette_in_order_generic;
}

#[inline(always)]
fn models_and_palette_in_order_generic(
    parents: &[Option<JointIndex>],
    order: &[JointIndex],
    inverse_bind: &[Splats],
    scratch: &[f32],
    models: &mut [Mat4],
    palette: &mut [Mat4],
) {
    let n = parents
        .len()
        .min(models.len())
        .min(palette.len())
        .min(inverse_bind.len());
    for &i in order {
        let i = i as usize;
        let Some(Ok(local)) = scratch
            .get((i / 4) * LOCAL..(i / 4 + 1) * LOCAL)
            .map(<&[f32; LOCAL]>::try_from)
        else {
            continue;
        };
        if i >= n {
            continue;
        }
        let m = model_of(parents, models, i, local, i % 4);
        models[i] = m;
        palette[i] = mul_affine_splats(&m, &inverse_bind[i]);
    }
}

/// Floats of [`local_matrices`] per block of four joints.
const LOCAL: usize = 48;

fn check_parents(parents: &[Option<JointIndex>]) -> Result<(), SkinError> {
    for (i, p) in parents.iter().enumerate() {
        if let Some(p) = *p {
            if p as usize >= i {
                return Err(SkinError::ParentOrder {
                    joint: i,
                    parent: p as usize,
                });
            }
        }
    }
    Ok(())
}

/// The local matrices `T * R * S` of four joints (one per lane), as twelve component vectors: entry
/// `3 * c + r` is row `r` of column `c` (columns 0-2: the rotation's columns times the scale, column
/// 3: the translation). The rotation uses glam's `Mat3A::from_quat` formulas; column `c` is multiplied
/// by scale component `c`.
#[inline(always)]
fn local_matrices(block: &soa::Block) -> [f32; LOCAL] {
    let [x, y, z, w] = soa::rotation(block);
    let (x2, y2, z2) = (x + x, y + y, z + z);
    let (xx, xy, xz) = (x * x2, x * y2, x * z2);
    let (yy, yz, zz) = (y * y2, y * z2, z * z2);
    let (wx, wy, wz) = (w * x2, w * y2, w * z2);
    let (sx, sy, sz) = (block[soa::S], block[soa::S + 1], block[soa::S + 2]);
    let one = Vec4::ONE;
    let entries = [
        (one - (yy + zz)) * sx,
        (xy + wz) * sx,
        (xz - wy) * sx,
        (xy - wz) * sy,
        (one - (xx + zz)) * sy,
        (yz + wx) * sy,
        (xz + wy) * sz,
        (yz - wx) * sz,
        (one - (xx + yy)) * sz,
        block[soa::T],
        block[soa::T + 1],
        block[soa::T + 2],
    ];
    let mut out = [0.0; LOCAL];
    for (e, v) in entries.iter().enumerate() {
        out[e * 4..e * 4 + 4].copy_from_slice(&v.to_array());
    }
    out
}

/// Joint `i`'s model matrix: its parent's (already in `models`, checked to come before `i`; the
/// identity for a root) times its local matrix, lane `lane` of `local` (see [`local_matrices`]).
#[inline(always)]
fn model_of(
    parents: &[Option<JointIndex>],
    models: &[Mat4],
    i: usize,
    local: &[f32; LOCAL],
    lane: usize,
) -> Mat4 {
    let parent = match parents[i] {
        Some(p) => models.get(p as usize).unwrap_or(&Mat4::IDENTITY),
        None => &Mat4::IDENTITY,
    };
    let (px, py, pz, pw) = (parent.x_axis, parent.y_axis, parent.z_axis, parent.w_axis);
    let e = |k: usize| local[k * 4 + (lane & 3)];
    let column = |c: usize| px * e(3 * c) + py * e(3 * c + 1) + pz * e(3 * c + 2);
    Mat4::from_cols(column(0), column(1), column(2), column(3) + pw)
}

/// The skinning palette: `palette[i] = models[i] * inverse_bind[i]`, which moves a bind-pose
/// model-space point to where joint `i` carries it now. Matrices are taken as affine: the inverse bind
/// matrices' bottom row is not read (it is `0 0 0 1` for any rigid, scaled or sheared bind).
pub fn skinning_palette(
    models: &[Mat4],
    inverse_bind: &[Mat4],
    palette: &mut [Mat4],
) -> Result<(), SkinError> {
    same_len("inverse bind matrices", models.len(), inverse_bind.len())?;
    same_len("palette", models.len(), palette.len())?;
    for ((m, ib), out) in models.iter().zip(inverse_bind).zip(palette.iter_mut()) {
        *out = mul_affine(m, ib);
    }
    Ok(())
}

/// [`mul_affine`] with `b` as [`Splats`]: the same products and sums, the same bits.
#[inline(always)]
fn mul_affine_splats(a: &Mat4, b: &Splats) -> Mat4 {
    let (ax, ay, az, aw) = (a.x_axis, a.y_axis, a.z_axis, a.w_axis);
    let col = |c: usize| ax * b[3 * c] + ay * b[3 * c + 1] + az * b[3 * c + 2];
    Mat4::from_cols(col(0), col(1), col(2), col(3) + aw)
}

/// `a * b` for affine matrices: `b`'s bottom row is taken as `0 0 0 1` (its stored bottom row is not
/// read). For affine inputs this equals the full product, up to the sign of zero components.
#[inline(always)]
fn mul_affine(a: &Mat4, b: &Mat4) -> Mat4 {
    let (ax, ay, az, aw) = (a.x_axis, a.y_axis, a.z_axis, a.w_axis);
    let col = |c: Vec4| ax * c.x + ay * c.y + az * c.z;
    Mat4::from_cols(
        col(b.x_axis),
        col(b.y_axis),
        col(b.z_axis),
        col(b.w_axis) + aw,
    )
}

/// Linear blend skinning of positions and normals with four influences per vertex.
///
/// For vertex `v` with joints `j` and weights `w`, the blended matrix is, column by column and in this
/// order, `((P[j0]*w0 + P[j1]*w1) + P[j2]*w2) + P[j3]*w3` (only the upper 3x4 part is used; the palette's
/// bottom row is assumed to be `0 0 0 1`).
///
/// - **Positions**: `M * (x, y, z, 1)`.
/// - **Normals**: transformed by the *cofactor* matrix of `M`'s 3x3 part `A` (columns `a0 a1 a2`):
///   `n' = n.x*(a1×a2) + n.y*(a2×a0) + n.z*(a0×a1)`, negated when `det A < 0`, then normalised. That is
///   the inverse-transpose up to a positive factor, which renormalisation removes, so normals stay
///   perpendicular to the surface under non-uniform scale and mirroring, without a matrix inverse. A
///   normal that ends up zero-length (degenerate matrix or zero input) is written as zero.
/// - **Zero weights are included**: all four influences are always blended (a weight of 0 adds
///   exactly `0 * P[j]`), so the loop has no data-dependent branch and the operation order never
///   changes. Consequently all four joint indices of every vertex must be valid, even with weight 0.
///   Weights are used as given; they are not renormalised.
///
/// `normals` and `out_normals` may both be empty to skin positions only; otherwise every per-vertex
/// slice must have the same length as `positions`.
///
/// On x86_64 CPUs with AVX this runs two vertices per 256-bit register (`crate::skin_avx`), with the
/// same operations in the same order: the same bits as the portable code, which runs elsewhere.
/// [`skin_with`] offers a cheaper treatment of normals.
pub fn skin(
    palette: &[Mat4],
    positions: &[Vec3],
    normals: &[Vec3],
    joints: &[[u16; MAX_INFLUENCES]],
    weights: &[[f32; MAX_INFLUENCES]],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) -> Result<(), SkinError> {
    skin_with(
        NormalTransform::Cofactor,
        palette,
        positions,
        normals,
        joints,
        weights,
        out_positions,
        out_normals,
    )
}

/// How [`skin_with`] transforms normals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NormalTransform {
    /// Through the cofactor of the blended 3x3, sign-corrected and normalised: what [`skin`] does.
    /// Correct under non-uniform scale, shear and mirroring; unit-length output.
    #[default]
    Cofactor,
    /// Through the blended matrix's 3x3 part itself, `((a0*n.x + a1*n.y) + a2*n.z)`, not normalised:
    /// what ozz-animation's `SkinningJob` does when it is given no inverse-transpose matrices. Exact
    /// (up to length) when every joint's palette matrix is a rotation times a uniform scale; under
    /// non-uniform scale or shear the normal leans off the surface, and the caller normalises (often
    /// in the vertex shader) if it needs unit normals. About a third cheaper than the cofactor.
    BlendedMatrix,
}

/// [`skin`] with a choice of how normals are transformed ([`NormalTransform`]); positions are the
/// same bits whichever is chosen, and with [`NormalTransform::Cofactor`] this is [`skin`].
#[allow(clippy::too_many_arguments)]
pub fn skin_with(
    normal_transform: NormalTransform,
    palette: &[Mat4],
    positions: &[Vec3],
    normals: &[Vec3],
    joints: &[[u16; MAX_INFLUENCES]],
    weights: &[[f32; MAX_INFLUENCES]],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) -> Result<(), SkinError> {
    let n = positions.len();
    same_len("joints", n, joints.len())?;
    same_len("weights", n, weights.len())?;
    same_len("output positions", n, out_positions.len())?;
    let with_normals = !(normals.is_empty() && out_normals.is_empty());
    if with_normals {
        same_len("normals", n, normals.len())?;
        same_len("output normals", n, out_normals.len())?;
    }
    let mode = match (with_normals, normal_transform) {
        (false, _) => Normals::None,
        (true, NormalTransform::Cofactor) => Normals::Cofactor,
        (true, NormalTransform::BlendedMatrix) => Normals::Matrix,
    };
    #[allow(unused_mut)]
    let mut done = 0;
    #[cfg(target_arch = "x86_64")]
    if crate::cpu::use_avx() {
        // SAFETY: `use_avx` is true only when the running CPU has AVX, which is all that
        // `skin_pairs` requires; it reads and writes through checked slices only.
        #[allow(unsafe_code)]
        {
            done = unsafe {
                crate::skin_avx::skin_pairs(
                    palette,
                    positions,
                    normals,
                    joints,
                    weights,
                    out_positions,
                    out_normals,
                    mode,
                )
            };
        }
    }
    // The portable code finishes: an odd last vertex, the pair with a bad joint index (which it
    // reports), or everything on a CPU without AVX.
    fn rest<T>(v: &[T], done: usize) -> &[T] {
        v.get(done..).unwrap_or(&[])
    }
    skin_generic(
        mode,
        done,
        palette,
        rest(positions, done),
        if with_normals {
            rest(normals, done)
        } else {
            &[]
        },
        rest(joints, done),
        rest(weights, done),
        out_positions.get_mut(done..).unwrap_or(&mut []),
        if with_normals {
            out_normals.get_mut(done..).unwrap_or(&mut [])
        } else {
            &mut []
        },
    )
}

/// The portable loop of [`skin_with`] on slices of equal length (checked by the caller), whose first
/// vertex is vertex `first` of the mesh (for error reports).
#[allow(clippy::too_many_arguments)]
fn skin_generic(
    mode: Normals,
    first: usize,
    palette: &[Mat4],
    positions: &[Vec3],
    normals: &[Vec3],
    joints: &[[u16; MAX_INFLUENCES]],
    weights: &[[f32; MAX_INFLUENCES]],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) -> Result<(), SkinError> {
    // Every per-vertex slice has the same length (checked by the caller), so the zips visit every
    // vertex.
    match mode {
        Normals::Cofactor => {
            // Two passes per chunk of vertices: the first blends, writes the position and keeps the
            // unnormalised normal and the determinant's three products; the second sums the
            // determinant, corrects the sign and normalises. Separating the long
            // square-root-and-divide latency from the blend lets the CPU overlap many vertices. The
            // operations on each vertex are the same as in one pass.
            let mut pending = [(Vec3A::ZERO, Vec3A::ZERO); CHUNK];
            let chunks = positions
                .chunks(CHUNK)
                .zip(normals.chunks(CHUNK))
                .zip(joints.chunks(CHUNK))
                .zip(weights.chunks(CHUNK))
                .zip(out_positions.chunks_mut(CHUNK))
                .zip(out_normals.chunks_mut(CHUNK));
            for (c, (((((ps, ns), js), ws), ops), ons)) in chunks.enumerate() {
                let mut done = 0;
                let mut error = None;
                let vertices = ps.iter().zip(ns).zip(js).zip(ws).zip(ops.iter_mut());
                for (((((p, n), j), w), op), r) in vertices.zip(pending.iter_mut()) {
                    match blend(palette, j, w, first + c * CHUNK + done) {
                        Ok(m) => {
                            *op = transform_point(&m, *p);
                            *r = cofactor_normal(&m, *n);
                            done += 1;
                        }
                        Err(e) => {
                            error = Some(e);
                            break;
                        }
                    }
                }
                for (&(r, d), on) in pending[..done].iter().zip(ons.iter_mut()) {
                    *on = normalize_yzx(r, d);
                }
                if let Some(e) = error {
                    return Err(e);
                }
            }
        }
        Normals::Matrix => {
            let inputs = positions.iter().zip(normals).zip(joints).zip(weights);
            let outputs = out_positions.iter_mut().zip(out_normals.iter_mut());
            for (v, ((((p, n), j), w), (op, on))) in inputs.zip(outputs).enumerate() {
                let m = blend(palette, j, w, first + v)?;
                *op = transform_point(&m, *p);
                *on = (m[0] * n.x + m[1] * n.y + m[2] * n.z).truncate();
            }
        }
        Normals::None => {
            let inputs = positions.iter().zip(joints).zip(weights).enumerate();
            for ((v, ((p, j), w)), op) in inputs.zip(out_positions.iter_mut()) {
                let m = blend(palette, j, w, first + v)?;
                *op = transform_point(&m, *p);
            }
        }
    }
    Ok(())
}

/// Vertices per chunk in [`skin`]'s two-pass loop (a 1 KiB stack buffer).
const CHUNK: usize = 32;

/// Skins one LOD's positions and normals with [`skin`]. A LOD without normals skins positions only
/// (pass an empty `out_normals`). A static LOD (no joints) is a [`SkinError::Length`] on `joints`.
pub fn skin_lod(
    palette: &[Mat4],
    lod: &Lod,
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) -> Result<(), SkinError> {
    skin(
        palette,
        &lod.positions,
        &lod.normals,
        &lod.joints,
        &lod.weights,
        out_positions,
        out_normals,
    )
}

/// The blended matrix's four columns (x, y, z axes and translation).
#[inline(always)]
fn blend(
    palette: &[Mat4],
    j: &[u16; MAX_INFLUENCES],
    w: &[f32; MAX_INFLUENCES],
    vertex: usize,
) -> Result<[Vec4; 4], SkinError> {
    let bad = |joint: u16| SkinError::JointIndex {
        vertex,
        joint,
        palette: palette.len(),
    };
    let m0 = palette.get(j[0] as usize).ok_or_else(|| bad(j[0]))?;
    let m1 = palette.get(j[1] as usize).ok_or_else(|| bad(j[1]))?;
    let m2 = palette.get(j[2] as usize).ok_or_else(|| bad(j[2]))?;
    let m3 = palette.get(j[3] as usize).ok_or_else(|| bad(j[3]))?;
    let (w0, w1, w2, w3) = (w[0], w[1], w[2], w[3]);
    Ok([
        m0.x_axis * w0 + m1.x_axis * w1 + m2.x_axis * w2 + m3.x_axis * w3,
        m0.y_axis * w0 + m1.y_axis * w1 + m2.y_axis * w2 + m3.y_axis * w3,
        m0.z_axis * w0 + m1.z_axis * w1 + m2.z_axis * w2 + m3.z_axis * w3,
        m0.w_axis * w0 + m1.w_axis * w1 + m2.w_axis * w2 + m3.w_axis * w3,
    ])
}

#[inline(always)]
fn transform_point(m: &[Vec4; 4], p: Vec3) -> Vec3 {
    (m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3]).truncate()
}

/// `n` through the cofactor of `m`'s 3x3 part, not yet normalised, in `yzx` lane order, and the
/// three products whose sum is the determinant of the 3x3 part (see [`normalize_yzx`]).
///
/// The three cross products share their shuffles: with `s_k = a_k.zxy()`, `s_a*b - a*s_b` is
/// `(a × b).yzx()` (the same per-lane products and differences as `a.cross(b)`), so the sum is formed
/// in `yzx` lane order and shuffled back once, after normalising.
#[inline(always)]
fn cofactor_normal(m: &[Vec4; 4], n: Vec3) -> (Vec3A, Vec3A) {
    let a0 = Vec3A::from_vec4(m[0]);
    let a1 = Vec3A::from_vec4(m[1]);
    let a2 = Vec3A::from_vec4(m[2]);
    let (s0, s1, s2) = (a0.zxy(), a1.zxy(), a2.zxy());
    let c0 = s1 * a2 - a1 * s2; // (a1 × a2).yzx
    let c1 = s2 * a0 - a2 * s0; // (a2 × a0).yzx
    let c2 = s0 * a1 - a0 * s1; // (a0 × a1).yzx
    let r = c0 * n.x + c1 * n.y + c2 * n.z; // (cofactor * n).yzx
    (r, a0.yzx() * c0)
}

/// `r / |r|`, negated when the determinant (the sum of `d`'s lanes) is negative, shuffled from `yzx`
/// back to `xyz` lane order; zero when `|r|` is zero or not finite. Divides by the signed length (no
/// reciprocal).
#[inline(always)]
fn normalize_yzx(r: Vec3A, d: Vec3A) -> Vec3 {
    let len = r.dot(r).sqrt();
    if len > 0.0 && len < f32::INFINITY {
        let det = d.element_sum();
        let len = if det < 0.0 { -len } else { len };
        Vec3::from((r / len).zxy())
    } else {
        Vec3::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::level_order;
    use glam::Quat;

    /// xorshift32 in [-1, 1).
    struct Rng(u32);
    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 17;
            self.0 ^= self.0 << 5;
            (self.0 >> 8) as f32 / (1u32 << 23) as f32 - 1.0
        }
        fn vec3(&mut self) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next())
        }
    }

    fn bits(m: &[Mat4]) -> Vec<u32> {
        m.iter()
            .flat_map(|m| m.to_cols_array())
            .map(f32::to_bits)
            .collect()
    }

    /// A random 23-joint tree (parents before children) with non-uniform scales.
    fn rig(rng: &mut Rng) -> (Vec<Option<JointIndex>>, Vec<Transform>, Vec<Mat4>) {
        let n = 23;
        let parents: Vec<Option<JointIndex>> = (0..n)
            .map(|i| (i > 0).then(|| ((rng.next() + 1.0) * 0.5 * i as f32) as JointIndex))
            .collect();
        let locals: Vec<Transform> = (0..n)
            .map(|_| {
                Transform::new(
                    rng.vec3() * 3.0,
                    Quat::from_xyzw(rng.next(), rng.next(), rng.next(), rng.next()).normalize(),
                    Vec3::ONE + rng.vec3() * 0.5,
                )
            })
            .collect();
        let inverse_bind = (0..n)
            .map(|_| {
                Mat4::from_scale_rotation_translation(
                    Vec3::ONE + rng.vec3() * 0.2,
                    Quat::from_rotation_y(rng.next() * 3.0),
                    rng.vec3() * 10.0,
                )
            })
            .collect();
        (parents, locals, inverse_bind)
    }

    #[test]
    fn every_instruction_set_and_layout_gives_the_same_bits() {
        let mut rng = Rng(0x9e37_79b9);
        for _ in 0..20 {
            let (parents, locals, inverse_bind) = rig(&mut rng);
            let n = parents.len();
            let run = |models: &mut Vec<Mat4>, palette: &mut Vec<Mat4>| {
                local_to_model_and_palette(&parents, &locals, &inverse_bind, models, palette)
                    .unwrap();
            };
            let (mut m1, mut p1) = (vec![Mat4::ZERO; n], vec![Mat4::ZERO; n]);
            let (mut m2, mut p2) = (vec![Mat4::ZERO; n], vec![Mat4::ZERO; n]);
            run(&mut m1, &mut p1);
            crate::cpu::baseline(|| run(&mut m2, &mut p2));
            assert_eq!(bits(&m1), bits(&m2));
            assert_eq!(bits(&p1), bits(&p2));
            // The block path, in level order, with and without AVX (pairs of joints per register).
            let blocks = soa::from_transforms(&locals);
            let skeleton = crate::Skeleton::new(
                (0..n).map(|i| format!("j{i}")).collect(),
                parents.clone(),
                locals.clone(),
                inverse_bind.clone(),
            )
            .unwrap();
            for baseline in [false, true] {
                let (mut m3, mut p3) = (vec![Mat4::ZERO; n], vec![Mat4::ZERO; n]);
                let mut scratch = Vec::new();
                let mut go = || {
                    local_to_model_and_palette_blocks(
                        &skeleton,
                        &blocks,
                        &mut scratch,
                        &mut m3,
                        &mut p3,
                    )
                    .unwrap()
                };
                if baseline {
                    crate::cpu::baseline(go);
                } else {
                    go();
                }
                assert_eq!(bits(&m1), bits(&m3));
                assert_eq!(bits(&p1), bits(&p3));
            }
            // Skinning with random influences, positions and normals.
            let vertices = 301;
            let positions: Vec<Vec3> = (0..vertices).map(|_| rng.vec3() * 50.0).collect();
            let normals: Vec<Vec3> = (0..vertices)
                .map(|_| rng.vec3().normalize_or(Vec3::Y))
                .collect();
            let joints: Vec<[u16; 4]> = (0..vertices)
                .map(|_| [0; 4].map(|_| ((rng.next() + 1.0) * 0.5 * n as f32) as u16 % n as u16))
                .collect();
            let weights: Vec<[f32; 4]> = (0..vertices)
                .map(|_| [0; 4].map(|_| (rng.next() + 1.0) * 0.25))
                .collect();
            let skin_with = |out_p: &mut Vec<Vec3>, out_n: &mut Vec<Vec3>| {
                skin(&p1, &positions, &normals, &joints, &weights, out_p, out_n).unwrap();
            };
            let (mut a_p, mut a_n) = (vec![Vec3::ZERO; vertices], vec![Vec3::ZERO; vertices]);
            let (mut b_p, mut b_n) = (vec![Vec3::ZERO; vertices], vec![Vec3::ZERO; vertices]);
            skin_with(&mut a_p, &mut a_n);
            crate::cpu::baseline(|| skin_with(&mut b_p, &mut b_n));
            let vbits = |v: &[Vec3]| -> Vec<u32> {
                v.iter()
                    .flat_map(|v| v.to_array())
                    .map(f32::to_bits)
                    .collect()
            };
            assert_eq!(vbits(&a_p), vbits(&b_p));
            assert_eq!(vbits(&a_n), vbits(&b_n));
        }
    }

    #[test]
    fn level_order_visits_every_joint_after_its_parent() {
        let mut rng = Rng(7);
        let (parents, _, _) = rig(&mut rng);
        let order = level_order(&parents);
        let mut seen = vec![false; parents.len()];
        for &j in &order {
            if let Some(p) = parents[j as usize] {
                assert!(seen[p as usize], "{j} before its parent {p}");
            }
            assert!(!seen[j as usize]);
            seen[j as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
        // Level by level: a biped-like chain and two branches.
        let parents = [None, Some(0), Some(1), Some(1), Some(2), Some(3), Some(0)];
        assert_eq!(level_order(&parents), [0, 1, 6, 2, 3, 4, 5]);
    }

    #[test]
    fn normals_under_non_uniform_scale_stay_perpendicular() {
        // Scale x by 2: the plane x + y = 0 has normal (1,1,0)/√2; after scaling x the plane is
        // x/2 + y = 0, normal (1,2,0)/√5 (up to length).
        let palette = [Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0))];
        let mut p = [Vec3::ZERO];
        let mut n = [Vec3::ZERO];
        let s = std::f32::consts::FRAC_1_SQRT_2;
        skin(
            &palette,
            &[Vec3::new(1.0, -1.0, 0.0)],
            &[Vec3::new(s, s, 0.0)],
            &[[0; 4]],
            &[[1.0, 0.0, 0.0, 0.0]],
            &mut p,
            &mut n,
        )
        .unwrap();
        assert_eq!(p[0], Vec3::new(2.0, -1.0, 0.0));
        let e = Vec3::new(1.0, 2.0, 0.0) / 5f32.sqrt();
        assert!((n[0] - e).length() < 1e-6, "{}", n[0]);
        // Mirroring keeps the normal outward-facing relative to the mirrored surface.
        let palette = [Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0))];
        skin(
            &palette,
            &[Vec3::X],
            &[Vec3::X],
            &[[0; 4]],
            &[[1.0, 0.0, 0.0, 0.0]],
            &mut p,
            &mut n,
        )
        .unwrap();
        assert_eq!(n[0], Vec3::new(-1.0, 0.0, 0.0));
    }

    #[test]
    fn local_to_model_matches_the_plain_matrix_product() {
        let parents = [None, Some(0), Some(1), Some(0)];
        let locals = [
            Transform::new(
                Vec3::new(1.0, 2.0, 3.0),
                Quat::from_rotation_y(0.7),
                Vec3::ONE,
            ),
            Transform::new(
                Vec3::new(0.5, -1.0, 0.0),
                Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.2, 2.0),
                Vec3::new(1.0, 2.0, 0.5),
            ),
            Transform::new(Vec3::Z, Quat::from_rotation_x(-0.4), Vec3::splat(3.0)),
            Transform::from_translation(Vec3::NEG_X),
        ];
        let mut models = [Mat4::IDENTITY; 4];
        local_to_model(&parents, &locals, &mut models).unwrap();
        let mut expected = [Mat4::IDENTITY; 4];
        for i in 0..4 {
            expected[i] = match parents[i] {
                Some(p) => expected[p as usize] * locals[i].to_mat4(),
                None => locals[i].to_mat4(),
            };
            assert!(models[i].abs_diff_eq(expected[i], 1e-5), "{i}");
        }
        let inverse: Vec<Mat4> = expected.iter().map(|m| m.inverse()).collect();
        let mut palette = [Mat4::ZERO; 4];
        skinning_palette(&models, &inverse, &mut palette).unwrap();
        for p in palette {
            assert!(p.abs_diff_eq(Mat4::IDENTITY, 1e-5), "{p}");
        }
    }

    #[test]
    fn fused_palette_is_bit_identical_to_the_two_steps() {
        let parents = [None, Some(0), Some(1), Some(1), Some(3)];
        let locals: Vec<Transform> = (0..5)
            .map(|i| {
                let f = i as f32;
                Transform::new(
                    Vec3::new(f, 1.0 - f, 0.5 * f),
                    Quat::from_euler(glam::EulerRot::XYZ, 0.3 * f, -0.7 + f, 1.1 * f).normalize(),
                    Vec3::new(1.0 + 0.1 * f, 1.0, 2.0 - 0.3 * f),
                )
            })
            .collect();
        let inverse_bind: Vec<Mat4> = (0..5)
            .map(|i| {
                Mat4::from_rotation_z(i as f32) * Mat4::from_translation(Vec3::splat(i as f32))
            })
            .collect();
        let (mut m1, mut p1) = ([Mat4::ZERO; 5], [Mat4::ZERO; 5]);
        local_to_model(&parents, &locals, &mut m1).unwrap();
        skinning_palette(&m1, &inverse_bind, &mut p1).unwrap();
        let (mut m2, mut p2) = ([Mat4::ZERO; 5], [Mat4::ZERO; 5]);
        local_to_model_and_palette(&parents, &locals, &inverse_bind, &mut m2, &mut p2).unwrap();
        let bits = |m: &[Mat4]| -> Vec<u32> {
            m.iter()
                .flat_map(|m| m.to_cols_array())
                .map(f32::to_bits)
                .collect()
        };
        assert_eq!(bits(&m1), bits(&m2));
        assert_eq!(bits(&p1), bits(&p2));
        // And a root's model matrix is its local matrix.
        assert!(m1[0].abs_diff_eq(locals[0].to_mat4(), 1e-6));
    }

    #[test]
    fn normals_match_the_inverse_transpose() {
        // Rotations, non-uniform scales, shears and mirrors; expected is normalize((A^-1)^T n),
        // computed with glam's general inverse (independent of the cofactor code).
        let mats = [
            Mat4::from_scale_rotation_translation(
                Vec3::new(2.0, 0.5, 1.5),
                Quat::from_euler(glam::EulerRot::XYZ, 0.4, -1.3, 2.2),
                Vec3::new(1.0, -2.0, 3.0),
            ),
            Mat4::from_scale(Vec3::new(-1.0, 3.0, 0.25)),
            Mat4::from_cols_array(&[
                1.0, 0.2, -0.3, 0.0, 0.5, 1.5, 0.1, 0.0, -0.4, 0.3, 0.8, 0.0, 4.0, 5.0, 6.0, 1.0,
            ]),
        ];
        let normals = [
            Vec3::X,
            Vec3::new(0.3, -0.9, 0.2).normalize(),
            Vec3::new(-0.5, 0.5, 0.7).normalize(),
        ];
        for (k, m) in mats.iter().enumerate() {
            for n in normals {
                let mut out_n = [Vec3::ZERO];
                let mut out_p = [Vec3::ZERO];
                skin(
                    &[*m],
                    &[Vec3::ONE],
                    &[n],
                    &[[0; 4]],
                    &[[1.0, 0.0, 0.0, 0.0]],
                    &mut out_p,
                    &mut out_n,
                )
                .unwrap();
                let a = glam::Mat3::from_mat4(*m);
                let e = (a.inverse().transpose() * n).normalize();
                assert!((out_n[0] - e).length() < 1e-6, "{k}: {} vs {e}", out_n[0]);
                assert!((out_p[0] - m.transform_point3(Vec3::ONE)).length() < 1e-5);
            }
        }
        // A zero normal stays zero.
        let mut out_n = [Vec3::ONE];
        let mut out_p = [Vec3::ZERO];
        skin(
            &mats[..1],
            &[Vec3::ONE],
            &[Vec3::ZERO],
            &[[0; 4]],
            &[[1.0, 0.0, 0.0, 0.0]],
            &mut out_p,
            &mut out_n,
        )
        .unwrap();
        assert_eq!(out_n[0], Vec3::ZERO);
    }

    #[test]
    fn rejects_parents_after_children() {
        let mut m = [Mat4::IDENTITY; 2];
        let e = local_to_model(&[Some(1), None], &[Transform::IDENTITY; 2], &mut m);
        assert_eq!(
            e,
            Err(SkinError::ParentOrder {
                joint: 0,
                parent: 1
            })
        );
    }
}
