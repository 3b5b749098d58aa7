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

use crate::skeleton::JointIndex;
use crate::soa::normalize_rotation;
use crate::Transform;
use glam::{Quat, Vec3, Vec3A};

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

#[derive(Debug, Clone, Copy)]
struct Accum {
    translation: Vec3A,
    scale: Vec3A,
    rotation: Quat,
    weight: f32,
}

const ZERO: Accum = Accum {
    translation: Vec3A::ZERO,
    scale: Vec3A::ZERO,
    rotation: Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
    weight: 0.0,
};

/// Preallocated accumulators for blending poses of one skeleton size. Make once, reuse every frame.
#[derive(Debug, Clone)]
pub struct BlendBuffers {
    accum: Vec<Accum>,
}

impl BlendBuffers {
    /// Buffers for a skeleton of `joints` joints.
    pub fn new(joints: usize) -> Self {
        Self {
            accum: vec![ZERO; joints],
        }
    }

    /// Number of joints the buffers were made for.
    pub fn joint_count(&self) -> usize {
        self.accum.len()
    }

    /// Clears the accumulated weights; call before the first layer of a frame.
    pub fn reset(&mut self) {
        self.accum.fill(ZERO);
    }

    /// Total normal-layer weight accumulated so far on each joint.
    pub fn total_weight(&self, joint: usize) -> Option<f32> {
        self.accum.get(joint).map(|a| a.weight)
    }

    /// Adds a normal (non-additive) layer. See the module docs for the arithmetic.
    pub fn accumulate(&mut self, layer: &Layer<'_>) -> Result<(), BlendError> {
        let n = self.accum.len();
        layer.check(n)?;
        let pose = layer.pose;
        let accum = &mut self.accum[..];
        for &j in layer.driven {
            let ju = j as usize;
            let (Some(p), Some(a)) = (pose.get(ju), accum.get_mut(ju)) else {
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
        Ok(())
    }

    /// Writes the blend of the accumulated normal layers to `out`, filling with the bind pose where the
    /// total weight is below 1 and normalising where it is above.
    pub fn resolve(&self, bind: &[Transform], out: &mut [Transform]) -> Result<(), BlendError> {
        let n = self.accum.len();
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
        for ((a, b), o) in self.accum.iter().zip(bind).zip(out.iter_mut()) {
            let w = a.weight;
            *o = if w == 1.0 {
                // Dividing a non-NaN value by exactly 1 changes no bits: skip the two divisions.
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
