//! Local poses kept four joints per block (structure of arrays), for code that samples and blends
//! without going through [`Transform`] slices.
//!
//! [`PoseBlocks`] is the layout the [`crate::Animator`] uses inside a frame, made public so that a
//! caller composing the steps itself (sample each clip, blend the layers, then local-to-model) can
//! stay in it: [`Sampler::sample_layer_blocks`](crate::Sampler::sample_layer_blocks) writes a
//! layer's blocks, [`BlendBuffers::accumulate_blocks`](crate::BlendBuffers::accumulate_blocks) adds
//! them, [`BlendBuffers::resolve_blocks`](crate::BlendBuffers::resolve_blocks) writes the blend, and
//! [`PoseBlocks::write_transforms`] turns any of them back into transforms. Nothing is transposed on
//! the way, which is what the per-joint API pays for on every layer. The results are the same bits
//! as the [`Transform`] path (tests compare them).

use crate::skeleton::JointIndex;
use crate::soa;
use crate::Transform;
use glam::Vec4;

/// A local pose of a skeleton, four joints per block: block `b` holds joints `4b .. 4b + 4`, one SIMD
/// lane each, as ten vectors (translation x y z, rotation x y z w, scale x y z).
///
/// Each block also records which of its lanes hold a value (*held* lanes): a pose made from
/// transforms holds every joint; a sampled layer holds the joints its clip drives, and a blend reads
/// only those.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseBlocks {
    joints: usize,
    /// [`soa::COMPONENTS`] vectors per block.
    pub(crate) blocks: Vec<Vec4>,
    /// Per block, the lanes holding a value (bit `l` = lane `l`).
    pub(crate) held: Vec<u8>,
}

impl PoseBlocks {
    /// A pose of `joints` joints holding none of them (every lane the identity).
    pub fn new(joints: usize) -> Self {
        Self {
            joints,
            blocks: soa::from_transforms(&vec![Transform::IDENTITY; joints]),
            held: vec![0; soa::block_count(joints)],
        }
    }

    /// The pose `transforms` (one per joint), holding every joint.
    pub fn from_transforms(transforms: &[Transform]) -> Self {
        let joints = transforms.len();
        Self {
            joints,
            blocks: soa::from_transforms(transforms),
            held: every_lane(joints),
        }
    }

    /// The pose `transforms` (one per joint), holding only the joints listed in `held` (indices
    /// outside the skeleton are ignored), as a sampled layer of a clip driving them would.
    pub fn from_joints(transforms: &[Transform], held: &[JointIndex]) -> Self {
        let mut pose = Self::from_transforms(transforms);
        pose.held.fill(0);
        for &j in held {
            let j = j as usize;
            if j < pose.joints {
                if let Some(h) = pose.held.get_mut(j / 4) {
                    *h |= 1 << (j % 4);
                }
            }
        }
        pose
    }

    /// Number of joints.
    pub fn joint_count(&self) -> usize {
        self.joints
    }

    /// Whether joint `joint` holds a value.
    pub fn holds(&self, joint: usize) -> bool {
        joint < self.joints
            && self
                .held
                .get(joint / 4)
                .is_some_and(|h| h & (1 << (joint % 4)) != 0)
    }

    /// Joint `joint`'s transform, when the pose holds it.
    pub fn transform(&self, joint: usize) -> Option<Transform> {
        if !self.holds(joint) {
            return None;
        }
        let block = self
            .blocks
            .get((joint / 4) * soa::COMPONENTS..(joint / 4 + 1) * soa::COMPONENTS)?;
        // `write_transforms` writes lane `l` to `out[l]`: read the one lane through four.
        let mut four = [Transform::IDENTITY; 4];
        soa::write_transforms(block, 1 << (joint % 4), &mut four);
        four.get(joint % 4).copied()
    }

    /// Writes the held joints to `out` (one transform per joint; the others are left as they are).
    /// `false`, writing nothing, when `out` has another length.
    pub fn write_transforms(&self, out: &mut [Transform]) -> bool {
        if out.len() != self.joints {
            return false;
        }
        for ((block, &held), o) in self
            .blocks
            .chunks_exact(soa::COMPONENTS)
            .zip(&self.held)
            .zip(out.chunks_mut(4))
        {
            soa::write_transforms(block, held, o);
        }
        true
    }
}

/// Per block, the lanes of joints that exist: all four but in a last, partial block.
pub(crate) fn every_lane(joints: usize) -> Vec<u8> {
    (0..soa::block_count(joints))
        .map(|b| 0b1111u8 >> (4 * b + 4).saturating_sub(joints).min(4))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Quat, Vec3};

    fn pose(n: usize) -> Vec<Transform> {
        (0..n)
            .map(|j| {
                let f = j as f32;
                Transform::new(
                    Vec3::new(f, -f, 0.5 * f),
                    Quat::from_rotation_y(0.1 * f),
                    Vec3::splat(1.0 + f),
                )
            })
            .collect()
    }

    #[test]
    fn transforms_round_trip_and_held_lanes_follow_the_list() {
        for n in [0, 1, 4, 5, 9] {
            let p = pose(n);
            let blocks = PoseBlocks::from_transforms(&p);
            assert_eq!(blocks.joint_count(), n);
            let mut back = vec![Transform::IDENTITY; n];
            assert!(blocks.write_transforms(&mut back));
            assert_eq!(back, p);
            assert!(!blocks.write_transforms(&mut vec![Transform::IDENTITY; n + 1]));
            for (j, t) in p.iter().enumerate() {
                assert_eq!(blocks.transform(j), Some(*t));
            }
            assert_eq!(blocks.transform(n), None);
        }
        let p = pose(6);
        let some = PoseBlocks::from_joints(&p, &[1, 4, 99]);
        let held: Vec<usize> = (0..8).filter(|&j| some.holds(j)).collect();
        assert_eq!(held, [1, 4]);
        let mut back = vec![Transform::IDENTITY; 6];
        assert!(some.write_transforms(&mut back));
        for (j, t) in back.iter().enumerate() {
            let want = if j == 1 || j == 4 {
                p[j]
            } else {
                Transform::IDENTITY
            };
            assert_eq!(*t, want, "joint {j}");
        }
        assert_eq!(PoseBlocks::new(3).transform(0), None);
    }
}
