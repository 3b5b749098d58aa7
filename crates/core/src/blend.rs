//! Blending of weighted, masked and additive layers into one local pose.
//!
//! A frame's blend runs in three steps on a [`BlendBuffers`] made once for a skeleton size and reused:
//!
//! 1. [`BlendBuffers::reset`], then [`BlendBuffers::accumulate`] once per *normal* layer. Each layer is a
//!    sampled local pose, the joints its clip drives ([`ClipBinding::driven`](crate::ClipBinding::driven))
//!    and a weight, optionally times a per-joint mask. For every driven joint the effective weight
//!    `w = weight * mask[j]` is added to the joint's total; translation and scale are summed as
//!    `w * value`; the rotation is summed as `w * q`, with `q` first negated when it points away from the
//!    sum so far (`dot < 0`), which blends along the shortest path. Rotations are used as given; they
//!    need not be unit. The [`crate::Animator`] feeds each layer's rotations as interpolated
//!    ([`Sampler::sample_layer`](crate::Sampler::sample_layer): the shortest-path weighted sum of two
//!    keys, not normalised), so a joint's rotation is the weighted sum of every contributing key,
//!    normalised once in step 2. For one layer at full weight that is exactly
//!    [`nlerp`](crate::clip::nlerp) of its two keys, what [`Sampler::sample`](crate::Sampler::sample)
//!    returns.
//! 2. [`BlendBuffers::resolve`] writes the result. For a joint whose total weight `W` is at least 1, the
//!    sums are divided by `W` (the rotation sum is normalised, as `q * (1 / |q|)`, the runtime's
//!    normalisation): weights are normalised. For `W < 1` the
//!    bind pose fills the remainder: `1 - W` of the bind translation, scale and (sign-aligned) rotation are
//!    added before normalising. A joint no layer reached (`W == 0`) is the bind pose exactly.
//! 3. [`apply_additive`] once per *additive* layer, in order, on the resolved pose.
//!
//! Effective weights that are not greater than zero (including NaN) contribute nothing.
//!
//! # Additive layers: the delta convention
//!
//! An additive clip ([`Clip::additive`](crate::Clip::additive)) stores, per joint and time, a difference
//! `D` between a source pose `S` and a reference pose `R` (typically the source clip's first frame, or a
//! separate reference clip), made offline by the pipeline:
//!
//! - translation: `D.t = S.t - R.t`
//! - rotation: `D.r = S.r * R.r⁻¹` (so that `D.r * R.r == S.r`; the delta acts in the parent's space)
//! - scale: `D.s = S.s / R.s`, component-wise
//!
//! Channels the additive clip does not store sample as the identity difference (`t = 0`, `r = identity`,
//! `s = 1`). Applying `D` with effective weight `w` to a base pose `B`:
//!
//! - `B.t += w * D.t`
//! - `B.r = normalize(nlerp(identity, D.r, w) * B.r)`, where `nlerp` takes the shortest path (`D.r` is
//!   negated first when its `w` component is negative) and normalises
//! - `B.s *= 1 + w * (D.s - 1)` (that is `lerp(1, D.s, w)`)
//!
//! With `w == 1` and `B == R` this gives back `S`. Weights above 1 exaggerate the difference.
//!
//! Nothing here allocates: all state lives in the [`BlendBuffers`].

use crate::cpu::multiversion;
use crate::pose_blocks::PoseBlocks;
use crate::skeleton::JointIndex;
use crate::soa;
use crate::Transform;
use glam::{Quat, Vec3, Vec4};

/// Why a blend step was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BlendError {
    /// A buffer has the wrong number of joints.
    #[error("{what} has {got} joints; the blend is set up for {expected}")]
    Length {
        /// Which buffer: "pose", "mask", "bind pose" or "output".
        what: &'static str,
        /// Joints the blend buffers were made for.
        expected: usize,
        /// Joints in the buffer.
        got: usize,
    },
    /// A driven joint index is outside the skeleton.
    #[error("layer drives joint {joint}, but the skeleton has {joints} joints")]
    JointIndex {
        /// The offending index.
        joint: JointIndex,
        /// Joints in the skeleton.
        joints: usize,
    },
}

/// One weighted layer: a sampled local pose and the joints its clip drives.
#[derive(Debug, Clone, Copy)]
pub struct Layer<'a> {
    /// Local pose, one transform per skeleton joint; only the `driven` joints are read.
    pub pose: &'a [Transform],
    /// Joints the layer's clip drives (from [`ClipBinding::driven`](crate::ClipBinding::driven)).
    pub driven: &'a [JointIndex],
    /// Layer weight.
    pub weight: f32,
    /// Optional per-joint weight factor, one per skeleton joint.
    pub mask: Option<&'a [f32]>,
}

impl<'a> Layer<'a> {
    /// A layer with weight 1 and no mask.
    pub fn new(pose: &'a [Transform], driven: &'a [JointIndex]) -> Self {
        Self {
            pose,
            driven,
            weight: 1.0,
            mask: None,
        }
    }
    /// The same layer with another weight.
    pub fn with_weight(self, weight: f32) -> Self {
        Self { weight, ..self }
    }
    /// The same layer with a per-joint mask.
    pub fn with_mask(self, mask: &'a [f32]) -> Self {
        Self {
            mask: Some(mask),
            ..self
        }
    }

    fn check(&self, joints: usize) -> Result<(), BlendError> {
        if self.pose.len() != joints {
            return Err(BlendError::Length {
                what: "pose",
                expected: joints,
                got: self.pose.len(),
            });
        }
        if let Some(m) = self.mask {
            if m.len() != joints {
                return Err(BlendError::Length {
                    what: "mask",
                    expected: joints,
                    got: m.len(),
                });
            }
        }
        Ok(())
    }
}

/// Preallocated accumulators for blending poses of one skeleton size. Make once, reuse every frame.
///
/// The sums are kept four joints per block, one SIMD lane per joint (see `crate::soa`): a layer is
/// added a block at a time (blocks its mask or weight leaves out are skipped), and the resolve
/// normalises four rotations with one square root and one division. Every lane does the per-joint
/// arithmetic of the module docs in the same order, so the results are the same bits as adding and
/// resolving joint by joint (tested against that reference).
#[derive(Debug, Clone)]
pub struct BlendBuffers {
    joints: usize,
    /// [`soa::ACCUM`] vectors per block: translation, rotation, scale sums and the total weight.
    accum: Vec<Vec4>,
    /// Scratch: per block, the lanes the layer being added drives.
    driven: Vec<u8>,
    /// Per block, the lanes of joints that exist (all four but in a last, partial block).
    every: Vec<u8>,
    /// The sums are to be read as zero ([`BlendBuffers::reset`] only sets this; the next layer
    /// writes every block instead of adding to it, which saves a pass over the buffer).
    fresh: bool,
}

impl BlendBuffers {
    /// Buffers for a skeleton of `joints` joints.
    pub fn new(joints: usize) -> Self {
        let blocks = soa::block_count(joints);
        Self {
            joints,
            accum: vec![Vec4::ZERO; blocks * soa::ACCUM],
            driven: vec![0; blocks],
            every: crate::pose_blocks::every_lane(joints),
            fresh: false,
        }
    }

    /// Number of joints the buffers were made for.
    pub fn joint_count(&self) -> usize {
        self.joints
    }

    /// Clears the accumulated weights; call before the first layer of a frame.
    pub fn reset(&mut self) {
        self.fresh = true;
    }

    /// Writes the zeros a [`BlendBuffers::reset`] stands for.
    fn materialize(&mut self) {
        if self.fresh {
            self.accum.fill(Vec4::ZERO);
            self.fresh = false;
        }
    }

    /// Total normal-layer weight accumulated so far on each joint.
    pub fn total_weight(&self, joint: usize) -> Option<f32> {
        if joint >= self.joints {
            return None;
        }
        let w = self.accum.get((joint / 4) * soa::ACCUM + soa::W)?;
        Some(if self.fresh { 0.0 } else { w[joint % 4] })
    }

    /// Adds a normal (non-additive) layer. See the module docs for the arithmetic.
    pub fn accumulate(&mut self, layer: &Layer<'_>) -> Result<(), BlendError> {
        let n = self.joints;
        layer.check(n)?;
        // A layer that drives every joint in order (a whole-body clip) drives every lane.
        if layer.driven.len() == n && n <= 1 << 16 && in_order(layer.driven) {
            let (pose, weight, mask) = (layer.pose, layer.weight, layer.mask);
            accumulate_transforms(&mut self.accum, &self.every, pose, weight, mask, self.fresh);
            self.fresh = false;
            return Ok(());
        }
        // The lanes of each block the layer drives. A joint index outside the skeleton, or one
        // listed twice, sends the layer the per-joint way, which adds the joints in the order
        // listed (twice for a joint listed twice) and stops at a bad index, as documented.
        self.driven.fill(0);
        let mut by_blocks = true;
        // The current block's lanes are kept in a register and stored when the block changes (a
        // sorted list, the usual case, visits each block once).
        let (mut block, mut lanes) = (usize::MAX, 0u8);
        for &j in layer.driven {
            let j = j as usize;
            if j >= n {
                by_blocks = false;
                break;
            }
            if j / 4 != block {
                if let Some(d) = self.driven.get_mut(block) {
                    *d = lanes;
                }
                block = j / 4;
                lanes = self.driven.get(block).copied().unwrap_or(0);
            }
            let bit = 1u8 << (j % 4);
            if lanes & bit != 0 {
                by_blocks = false;
                break;
            }
            lanes |= bit;
        }
        if let Some(d) = self.driven.get_mut(block) {
            *d = lanes;
        }
        if by_blocks {
            let (pose, weight, mask) = (layer.pose, layer.weight, layer.mask);
            accumulate_transforms(
                &mut self.accum,
                &self.driven,
                pose,
                weight,
                mask,
                self.fresh,
            );
            self.fresh = false;
            Ok(())
        } else {
            self.materialize();
            accumulate_joints(&mut self.accum, n, layer)
        }
    }

    /// Writes the blend of the accumulated normal layers to `out`, filling with the bind pose where the
    /// total weight is below 1 and normalising where it is above.
    pub fn resolve(&self, bind: &[Transform], out: &mut [Transform]) -> Result<(), BlendError> {
        let n = self.joints;
        if bind.len() != n {
            return Err(BlendError::Length {
                what: "bind pose",
                expected: n,
                got: bind.len(),
            });
        }
        if out.len() != n {
            return Err(BlendError::Length {
                what: "output",
                expected: n,
                got: out.len(),
            });
        }
        if self.fresh {
            // Nothing accumulated since the reset: every joint is the bind pose.
            out.copy_from_slice(bind);
        } else {
            resolve_blocks(&self.accum, bind, out);
        }
        Ok(())
    }

    /// [`BlendBuffers::accumulate`] for a layer kept as blocks: adds the joints `pose` holds (a
    /// sampled layer: the joints its clip drives), at `weight` times `mask[j]` when a mask (one
    /// factor per joint) is given. The same arithmetic and the same bits as the [`Layer`] of the
    /// same transforms, driven joints, weight and mask, without transposing the pose.
    pub fn accumulate_blocks(
        &mut self,
        pose: &PoseBlocks,
        weight: f32,
        mask: Option<&[f32]>,
    ) -> Result<(), BlendError> {
        let n = self.joints;
        if pose.joint_count() != n {
            return Err(BlendError::Length {
                what: "pose",
                expected: n,
                got: pose.joint_count(),
            });
        }
        if let Some(m) = mask {
            if m.len() != n {
                return Err(BlendError::Length {
                    what: "mask",
                    expected: n,
                    got: m.len(),
                });
            }
        }
        let (accum, fresh) = (&mut self.accum, self.fresh);
        accumulate_pose_blocks(accum, &pose.held, &pose.blocks, weight, mask, fresh);
        self.fresh = false;
        Ok(())
    }

    /// [`BlendBuffers::resolve`] into blocks: `bind` is the bind pose ([`PoseBlocks::from_transforms`]
    /// of [`Skeleton::bind_local`](crate::Skeleton::bind_local), made once), `out` receives every
    /// joint (all held).
    pub fn resolve_blocks(
        &self,
        bind: &PoseBlocks,
        out: &mut PoseBlocks,
    ) -> Result<(), BlendError> {
        let n = self.joints;
        for (what, got) in [
            ("bind pose", bind.joint_count()),
            ("output", out.joint_count()),
        ] {
            if got != n {
                return Err(BlendError::Length {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        if self.fresh {
            out.blocks.copy_from_slice(&bind.blocks);
        } else {
            resolve_pose_blocks(&self.accum, &bind.blocks, &mut out.blocks);
        }
        out.held.copy_from_slice(&self.every);
        Ok(())
    }

    /// Convenience for one frame: reset, accumulate every normal layer, resolve into `out`, then apply
    /// the additive layers in order.
    pub fn blend(
        &mut self,
        bind: &[Transform],
        normal: &[Layer<'_>],
        additive: &[Layer<'_>],
        out: &mut [Transform],
    ) -> Result<(), BlendError> {
        self.reset();
        for l in normal {
            self.accumulate(l)?;
        }
        self.resolve(bind, out)?;
        for l in additive {
            apply_additive(out, l)?;
        }
        Ok(())
    }
}

/// Whether `driven` is `0, 1, 2, ...` (for a list as long as the skeleton: every joint, in order).
/// Eight indices at a time, with no early exit, so that it compiles to a few vector operations.
fn in_order(driven: &[JointIndex]) -> bool {
    let mut want: [JointIndex; 8] = [0, 1, 2, 3, 4, 5, 6, 7];
    let mut differ = [0; 8];
    let eights = driven.chunks_exact(8);
    let rest = eights.remainder();
    for e in eights {
        for k in 0..8 {
            differ[k] |= e[k] ^ want[k];
            want[k] = want[k].wrapping_add(8);
        }
    }
    differ.iter().all(|&d| d == 0) && rest.iter().zip(want).all(|(&j, w)| j == w)
}

/// Where a layer's blocks come from: transforms, transposed four at a time, or a [`PoseBlocks`]
/// read as it is. (A trait rather than an enum: each source gets its own copy of the loop.)
trait BlockSource: Copy {
    /// Block `b` (lanes past the end of the pose are the identity).
    fn block(self, b: usize) -> soa::Block;
}

impl BlockSource for &[Transform] {
    #[inline(always)]
    fn block(self, b: usize) -> soa::Block {
        match self.get(4 * b..4 * b + 4) {
            Some(four) => soa::block_of(four),
            None => soa::block_of(self.get(4 * b..).unwrap_or(&[])),
        }
    }
}

impl BlockSource for &[Vec4] {
    #[inline(always)]
    fn block(self, b: usize) -> soa::Block {
        self.get(b * soa::COMPONENTS..(b + 1) * soa::COMPONENTS)
            .and_then(|v| <&soa::Block>::try_from(v).ok())
            .copied()
            .unwrap_or([Vec4::ZERO; soa::COMPONENTS])
    }
}

multiversion! {
    /// Adds a layer of transforms (`pose` at `weight`, times `mask` per joint) to `accum` a block
    /// at a time; `driven` holds the lanes it drives per block (each joint once, all inside the
    /// skeleton). `fresh`: `accum` is to be read as zeros (every block is written).
    fn accumulate_transforms(
        accum: &mut [Vec4],
        driven: &[u8],
        pose: &[Transform],
        weight: f32,
        mask: Option<&[f32]>,
        fresh: bool,
    ) -> () => accumulate_generic;
}

multiversion! {
    /// [`accumulate_transforms`] for a pose kept as blocks ([`PoseBlocks`]).
    fn accumulate_pose_blocks(
        accum: &mut [Vec4],
        driven: &[u8],
        pose: &[Vec4],
        weight: f32,
        mask: Option<&[f32]>,
        fresh: bool,
    ) -> () => accumulate_generic;
}

#[inline(always)]
fn accumulate_generic<S: BlockSource>(
    accum: &mut [Vec4],
    driven: &[u8],
    source: S,
    weight: f32,
    mask: Option<&[f32]>,
    fresh: bool,
) {
    if fresh {
        add_blocks::<true, S>(accum, driven, source, weight, mask);
    } else {
        add_blocks::<false, S>(accum, driven, source, weight, mask);
    }
}

/// [`accumulate_transforms`] with `FRESH` = `fresh`. Adding to a zero read from memory and adding to a
/// zero in a register are the same operation: a fresh buffer gives the bits a cleared one gives.
#[inline(always)]
fn add_blocks<const FRESH: bool, S: BlockSource>(
    accum: &mut [Vec4],
    driven: &[u8],
    source: S,
    weight: f32,
    mask: Option<&[f32]>,
) {
    let weight = Vec4::splat(weight);
    let blocks = accum.chunks_exact_mut(soa::ACCUM).zip(driven);
    for (b, (a, &d)) in blocks.enumerate() {
        let Ok(a) = <&mut [Vec4; soa::ACCUM]>::try_from(a) else {
            continue;
        };
        if d == 0 {
            if FRESH {
                *a = [Vec4::ZERO; soa::ACCUM];
            }
            continue;
        }
        let first = 4 * b;
        // `layer.weight * mask[j]` per lane, as the per-joint code multiplies them.
        let w = match mask {
            Some(m) => match m.get(first..first + 4) {
                Some(m4) => weight * Vec4::from_slice(m4),
                None => {
                    let m = m.get(first..).unwrap_or(&[]);
                    let lane = |l: usize| m.get(l).copied().unwrap_or(0.0);
                    weight * Vec4::new(lane(0), lane(1), lane(2), lane(3))
                }
            },
            None => weight,
        };
        // Lanes that contribute: driven, with a weight above zero (NaN excluded). The others take
        // zero values at weight zero, adding +0 or -0 to sums that are never -0: no change, and a
        // joint the layer leaves out is never read.
        let on = soa::lanes(d) & w.cmpgt(Vec4::ZERO);
        if !on.any() {
            if FRESH {
                *a = [Vec4::ZERO; soa::ACCUM];
            }
            continue;
        }
        let mut sums = if FRESH { [Vec4::ZERO; soa::ACCUM] } else { *a };
        let w = soa::select(on, w, Vec4::ZERO);
        let block = source.block(b);
        // (Lanes left out are zeroed so that a value the layer does not provide is never read.)
        let p = if on.all() {
            block
        } else {
            block.map(|v| soa::select(on, v, Vec4::ZERO))
        };
        let s = &mut sums;
        let acc_r = [s[soa::R], s[soa::R + 1], s[soa::R + 2], s[soa::R + 3]];
        let q =
            soa::negate_where_negative(soa::rotation(&p), soa::dot_q(&acc_r, &soa::rotation(&p)));
        for c in 0..3 {
            s[soa::T + c] += p[soa::T + c] * w;
            s[soa::S + c] += p[soa::S + c] * w;
        }
        for (c, v) in q.into_iter().enumerate() {
            s[soa::R + c] += v * w;
        }
        s[soa::W] += w;
        *a = sums;
    }
}

/// Adds `layer` joint by joint, in the order it lists them, into lane `j % 4` of block `j / 4`;
/// stops with an error at a joint outside the skeleton (`joints`). Scalar operations, the same as
/// the lanes' in [`accumulate_transforms`].
fn accumulate_joints(
    accum: &mut [Vec4],
    joints: usize,
    layer: &Layer<'_>,
) -> Result<(), BlendError> {
    for &j in layer.driven {
        let ju = j as usize;
        let block = accum.get_mut((ju / 4) * soa::ACCUM..(ju / 4 + 1) * soa::ACCUM);
        let (Some(p), Some(a), true) = (layer.pose.get(ju), block, ju < joints) else {
            return Err(BlendError::JointIndex { joint: j, joints });
        };
        let w = match layer.mask {
            Some(m) => layer.weight * m.get(ju).copied().unwrap_or(0.0),
            None => layer.weight,
        };
        if w.is_nan() || w <= 0.0 {
            continue;
        }
        let l = ju % 4;
        let sum = Quat::from_xyzw(
            a[soa::R][l],
            a[soa::R + 1][l],
            a[soa::R + 2][l],
            a[soa::R + 3][l],
        );
        let q = if sum.dot(p.rotation) < 0.0 {
            -p.rotation
        } else {
            p.rotation
        };
        let (t, r, s) = (p.translation.to_array(), q.to_array(), p.scale.to_array());
        for c in 0..3 {
            a[soa::T + c][l] += t[c] * w;
            a[soa::S + c][l] += s[c] * w;
        }
        for (c, v) in r.into_iter().enumerate() {
            a[soa::R + c][l] += v * w;
        }
        a[soa::W][l] += w;
    }
    Ok(())
}

multiversion! {
    /// Resolves every block of `accum` into `out` (`bind` and `out` hold one transform per joint).
    fn resolve_blocks(accum: &[Vec4], bind: &[Transform], out: &mut [Transform]) -> ()
        => resolve_blocks_generic;
}

#[inline(always)]
fn resolve_blocks_generic(accum: &[Vec4], bind: &[Transform], out: &mut [Transform]) {
    let blocks = accum
        .chunks_exact(soa::ACCUM)
        .zip(bind.chunks(4))
        .zip(out.chunks_mut(4));
    for ((a, b4), o4) in blocks {
        // The bind pose is read only where some lane's total weight is not exactly 1.
        let w = a.get(soa::W).copied().unwrap_or(Vec4::ONE);
        let bind_block = if w.cmpeq(Vec4::ONE).all() {
            [Vec4::ZERO; soa::COMPONENTS]
        } else {
            soa::block_of(b4)
        };
        let mut o = [Vec4::ZERO; soa::COMPONENTS];
        soa::resolve(a, &bind_block, &mut o);
        soa::write_transforms(&o, 0b1111, o4);
    }
}

multiversion! {
    /// Resolves every block of `accum` into `out`, blocks of the bind pose `bind`.
    fn resolve_pose_blocks(accum: &[Vec4], bind: &[Vec4], out: &mut [Vec4]) -> ()
        => resolve_pose_blocks_generic;
}

#[inline(always)]
fn resolve_pose_blocks_generic(accum: &[Vec4], bind: &[Vec4], out: &mut [Vec4]) {
    soa::resolve(accum, bind, out);
}

/// Applies an additive layer (a pose of differences, see the module docs) on top of `base`, in place.
pub fn apply_additive(base: &mut [Transform], layer: &Layer<'_>) -> Result<(), BlendError> {
    let n = base.len();
    layer.check(n)?;
    let pose = layer.pose;
    for &j in layer.driven {
        let ju = j as usize;
        let (Some(d), Some(b)) = (pose.get(ju), base.get_mut(ju)) else {
            return Err(BlendError::JointIndex {
                joint: j,
                joints: n,
            });
        };
        let w = match layer.mask {
            Some(m) => layer.weight * m.get(ju).copied().unwrap_or(0.0),
            None => layer.weight,
        };
        if w.is_nan() || w <= 0.0 {
            continue;
        }
        let dr = if d.rotation.w < 0.0 {
            -d.rotation
        } else {
            d.rotation
        };
        let partial = (Quat::IDENTITY * (1.0 - w) + dr * w).normalize();
        b.translation += d.translation * w;
        b.rotation = (partial * b.rotation).normalize();
        b.scale *= Vec3::ONE + (d.scale - Vec3::ONE) * w;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3A;

    #[derive(Debug, Clone, Copy)]
    struct Accum {
        translation: Vec3A,
        scale: Vec3A,
        rotation: Quat,
        weight: f32,
    }

    /// The per-joint blend as it was before the accumulators were kept four joints per block: the
    /// reference the blend must match bit for bit.
    fn reference_blend(bind: &[Transform], layers: &[Layer<'_>], out: &mut [Transform]) {
        use crate::rotation::normalize_rotation;
        let zero = Accum {
            translation: Vec3A::ZERO,
            scale: Vec3A::ZERO,
            rotation: Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
            weight: 0.0,
        };
        let mut accum = vec![zero; bind.len()];
        for layer in layers {
            for &j in layer.driven {
                let (p, a) = (&layer.pose[j as usize], &mut accum[j as usize]);
                let w = match layer.mask {
                    Some(m) => layer.weight * m[j as usize],
                    None => layer.weight,
                };
                if w.is_nan() || w <= 0.0 {
                    continue;
                }
                let q = if a.rotation.dot(p.rotation) < 0.0 {
                    -p.rotation
                } else {
                    p.rotation
                };
                a.translation += Vec3A::from(p.translation) * w;
                a.scale += Vec3A::from(p.scale) * w;
                a.rotation += q * w;
                a.weight += w;
            }
        }
        for ((a, b), o) in accum.iter().zip(bind).zip(out.iter_mut()) {
            let w = a.weight;
            *o = if w == 1.0 {
                Transform {
                    translation: Vec3::from(a.translation),
                    rotation: normalize_rotation(a.rotation),
                    scale: Vec3::from(a.scale),
                }
            } else if w >= 1.0 {
                Transform {
                    translation: Vec3::from(a.translation / w),
                    rotation: normalize_rotation(a.rotation),
                    scale: Vec3::from(a.scale / w),
                }
            } else if w > 0.0 {
                let rest = 1.0 - w;
                let br = if a.rotation.dot(b.rotation) < 0.0 {
                    -b.rotation
                } else {
                    b.rotation
                };
                Transform {
                    translation: Vec3::from(a.translation + Vec3A::from(b.translation) * rest),
                    rotation: normalize_rotation(a.rotation + br * rest),
                    scale: Vec3::from(a.scale + Vec3A::from(b.scale) * rest),
                }
            } else {
                *b
            };
        }
    }

    /// A pseudo-random stream in [-1, 1) (xorshift), from `seed`.
    fn stream(mut seed: u32) -> impl FnMut() -> f32 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            (seed >> 8) as f32 / (1u32 << 23) as f32 - 1.0
        }
    }

    use crate::transform::transform_bits as bits;

    /// `n` transforms of random translation, rotation (not unit) and positive scale.
    fn random_pose(next: &mut impl FnMut() -> f32, n: usize) -> Vec<Transform> {
        (0..n)
            .map(|_| {
                Transform::new(
                    Vec3::new(next(), next(), next()) * 10.0,
                    Quat::from_xyzw(next(), next(), next(), next()),
                    Vec3::new(next(), next(), next()) + 1.5,
                )
            })
            .collect()
    }

    #[test]
    fn blend_matches_the_per_joint_reference_bit_for_bit() {
        let mut next = stream(0x9e37_79b9);
        for n in [1, 3, 4, 5, 8, 23, 40] {
            let mut pose = || random_pose(&mut next, n);
            let (bind, mut p1, p2, mut p3) = (pose(), pose(), pose(), pose());
            // Values the blend must never read: a joint masked to 0, a joint a layer does not drive.
            p1[0].translation.x = f32::NAN;
            if n > 1 {
                p3[1].scale.y = f32::INFINITY;
            }
            // Masks reaching every regime: 0, between 0 and 1, 1, and totals above 1; a NaN.
            let levels = [0.0, 0.25, 1.0, 0.7, 0.5, 1.0, f32::NAN, 0.0];
            let m1: Vec<f32> = (0..n).map(|j| levels[j % 8]).collect();
            let m2: Vec<f32> = (0..n).map(|j| levels[(j * 3 + 1) % 8]).collect();
            let all: Vec<JointIndex> = (0..n as JointIndex).collect();
            let some: Vec<JointIndex> = (0..n as JointIndex).filter(|j| j % 3 != 1).collect();
            // Out of order, with a joint listed twice: the per-joint way.
            let twice: Vec<JointIndex> = (0..n as JointIndex).rev().chain([0]).collect();
            for weight in [1.0, 0.6, 2.0] {
                let layers = [
                    Layer::new(&p1, &all).with_mask(&m1),
                    Layer::new(&p2, &some).with_weight(weight),
                    Layer::new(&p3, &some).with_mask(&m2).with_weight(weight),
                    Layer::new(&p2, &twice).with_mask(&m2).with_weight(0.3),
                ];
                // Every prefix, and every suffix in reverse order (each kind of layer comes first
                // after a reset at some point: whole-body, partial, and the per-joint way).
                let mut reversed = layers.to_vec();
                reversed.reverse();
                for (k, order) in
                    (0..=layers.len()).flat_map(|k| [(k, &layers[..]), (k, &reversed[..])])
                {
                    let layers = &order[..k];
                    let mut b = BlendBuffers::new(n);
                    let mut out = vec![Transform::IDENTITY; n];
                    b.blend(&bind, layers, &[], &mut out).unwrap();
                    let mut want = vec![Transform::IDENTITY; n];
                    reference_blend(&bind, layers, &mut want);
                    assert_eq!(bits(&out), bits(&want), "{n} joints, {k} layers");
                    // The baseline (SSE2) copy gives the same bits as the AVX copy.
                    let mut base = vec![Transform::IDENTITY; n];
                    crate::cpu::baseline(|| b.blend(&bind, layers, &[], &mut base)).unwrap();
                    assert_eq!(bits(&out), bits(&base), "{n} joints, {k} layers, baseline");
                    // Total weights as the reference sums them.
                    for j in 0..n {
                        let w = layers.iter().fold(0.0f32, |t, l| {
                            let w = l.weight * l.mask.map_or(1.0, |m| m[j]);
                            let times = l.driven.iter().filter(|&&d| d as usize == j).count();
                            (0..times).fold(t, |t, _| if w > 0.0 { t + w } else { t })
                        });
                        assert_eq!(b.total_weight(j).map(f32::to_bits), Some(w.to_bits()));
                    }
                }
            }
        }
    }

    #[test]
    fn block_layers_give_the_transform_layers_bits() {
        let mut next = stream(0x1234_5678);
        for n in [1, 4, 5, 23, 40] {
            let mut pose = || random_pose(&mut next, n);
            let (bind, p1, p2) = (pose(), pose(), pose());
            let levels = [0.0, 0.25, 1.0, 0.7, 0.5, 1.0, f32::NAN, 0.0];
            let m1: Vec<f32> = (0..n).map(|j| levels[j % 8]).collect();
            let m2: Vec<f32> = (0..n).map(|j| levels[(j * 3 + 1) % 8]).collect();
            let all: Vec<JointIndex> = (0..n as JointIndex).collect();
            let some: Vec<JointIndex> = (0..n as JointIndex).filter(|j| j % 3 != 1).collect();
            let (b1, b2) = (
                PoseBlocks::from_joints(&p1, &all),
                PoseBlocks::from_joints(&p2, &some),
            );
            let bind_blocks = PoseBlocks::from_transforms(&bind);
            for weight in [1.0, 0.6, 2.0] {
                let layers = [
                    Layer::new(&p1, &all).with_mask(&m1),
                    Layer::new(&p2, &some).with_mask(&m2).with_weight(weight),
                ];
                let mut want = vec![Transform::IDENTITY; n];
                let mut b = BlendBuffers::new(n);
                b.blend(&bind, &layers, &[], &mut want).unwrap();
                // Both layers as blocks, resolved into blocks and into transforms.
                let mut out = PoseBlocks::new(n);
                for base in [false, true] {
                    let run = |b: &mut BlendBuffers, out: &mut PoseBlocks| {
                        b.reset();
                        b.accumulate_blocks(&b1, 1.0, Some(&m1))?;
                        b.accumulate_blocks(&b2, weight, Some(&m2))?;
                        b.resolve_blocks(&bind_blocks, out)
                    };
                    if base {
                        crate::cpu::baseline(|| run(&mut b, &mut out)).unwrap();
                    } else {
                        run(&mut b, &mut out).unwrap();
                    }
                    assert!((0..n).all(|j| out.holds(j)));
                    let mut got = vec![Transform::IDENTITY; n];
                    assert!(out.write_transforms(&mut got));
                    assert_eq!(bits(&got), bits(&want), "{n} joints, weight {weight}");
                    b.resolve(&bind, &mut got).unwrap();
                    assert_eq!(bits(&got), bits(&want), "{n} joints, weight {weight}");
                }
                // One layer of each kind, in either order.
                b.reset();
                b.accumulate(&layers[0]).unwrap();
                b.accumulate_blocks(&b2, weight, Some(&m2)).unwrap();
                let mut got = vec![Transform::IDENTITY; n];
                b.resolve(&bind, &mut got).unwrap();
                assert_eq!(bits(&got), bits(&want));
                b.reset();
                b.accumulate_blocks(&b1, 1.0, Some(&m1)).unwrap();
                b.accumulate(&layers[1]).unwrap();
                b.resolve(&bind, &mut got).unwrap();
                assert_eq!(bits(&got), bits(&want));
            }
            // Nothing accumulated: the bind pose; wrong sizes are refused.
            let mut b = BlendBuffers::new(n);
            b.reset();
            let mut out = PoseBlocks::new(n);
            b.resolve_blocks(&bind_blocks, &mut out).unwrap();
            let mut got = vec![Transform::IDENTITY; n];
            assert!(out.write_transforms(&mut got));
            assert_eq!(bits(&got), bits(&bind));
            let short = PoseBlocks::new(n + 1);
            assert!(b.accumulate_blocks(&short, 1.0, None).is_err());
            assert!(b.accumulate_blocks(&b1, 1.0, Some(&m1[1..])).is_err());
            assert!(b.resolve_blocks(&short, &mut out).is_err());
        }
    }

    #[test]
    fn single_full_layer_is_passed_through() {
        let pose = [Transform::new(
            Vec3::new(1.0, 2.0, 3.0),
            Quat::from_rotation_y(0.5),
            Vec3::splat(2.0),
        )];
        let bind = [Transform::IDENTITY];
        let mut b = BlendBuffers::new(1);
        let mut out = [Transform::IDENTITY];
        b.blend(&bind, &[Layer::new(&pose, &[0])], &[], &mut out)
            .unwrap();
        assert_eq!(out[0].translation, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(out[0].scale, Vec3::splat(2.0));
        assert!(out[0].rotation.angle_between(Quat::from_rotation_y(0.5)) < 1e-6);
    }

    #[test]
    fn undriven_joints_keep_the_bind_pose_exactly() {
        let bind = [
            Transform::from_translation(Vec3::X),
            Transform::new(Vec3::Y, Quat::from_rotation_x(0.3), Vec3::splat(3.0)),
        ];
        let pose = [Transform::from_translation(Vec3::Z); 2];
        let mut b = BlendBuffers::new(2);
        let mut out = [Transform::IDENTITY; 2];
        b.blend(&bind, &[Layer::new(&pose, &[0])], &[], &mut out)
            .unwrap();
        assert_eq!(out[0].translation, Vec3::Z);
        assert_eq!(out[1], bind[1]);
        assert_eq!(b.total_weight(0), Some(1.0));
        assert_eq!(b.total_weight(1), Some(0.0));
    }
}
