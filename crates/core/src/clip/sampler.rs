//! Sampling a bound clip at a time, with a cursor that makes playing forward cheap.

use super::binding::ClipBinding;
use super::data::{Clip, ClipError};
use super::key_cache::KeyCache;
use crate::pose_blocks::PoseBlocks;
use crate::skeleton::Skeleton;
use crate::soa::{self, PlanBlock};
use crate::Transform;

/// Per-character sampling state: a cursor into a clip's key times so that playing forward never searches
/// from the first key, and the two most recently used keys laid out as the binding's blocks (made on
/// first use for a clip and binding and reused, so playing forward gathers or decodes a key only when
/// the cursor passes it).
#[derive(Debug, Clone, Default)]
pub struct Sampler {
    pub(super) cursor: usize,
    pub(super) cache: KeyCache,
}

/// Equality compares the cursor only: the key cache is a memo that never changes results.
impl PartialEq for Sampler {
    fn eq(&self, other: &Self) -> bool {
        self.cursor == other.cursor
    }
}
impl Eq for Sampler {}

impl Sampler {
    /// A sampler at the first key.
    pub fn new() -> Self {
        Self::default()
    }

    /// Finds the key pair around `t` (already mapped by [`Clip::local_time`]) and the blend factor.
    /// Returns `(k0, k1, alpha)`; `alpha == 0` means frame `k0` exactly.
    #[inline]
    pub fn locate(&mut self, clip: &Clip, t: f32) -> (usize, usize, f32) {
        let times = &clip.times;
        let n = times.len();
        if n <= 1 || t <= times[0] {
            self.cursor = 0;
            if clip.looping && n > 1 && t < times[0] {
                // Before the first key of a looping clip: coming from the last frame around the wrap.
                let span = times[0] + (clip.duration - times[n - 1]);
                if span > 0.0 {
                    let a = (t + clip.duration - times[n - 1]) / span;
                    return (n - 1, 0, a.clamp(0.0, 1.0));
                }
            }
            return (0, 0, 0.0);
        }
        let mut c = self.cursor.min(n - 1);
        if times[c] > t {
            c = times.partition_point(|&x| x <= t) - 1;
        } else {
            let mut steps = 0;
            while c + 1 < n && times[c + 1] <= t {
                c += 1;
                steps += 1;
                if steps == 8 {
                    c = times.partition_point(|&x| x <= t) - 1;
                    break;
                }
            }
        }
        self.cursor = c;
        if c + 1 >= n {
            if clip.looping {
                let span = clip.duration - times[c] + times[0];
                if span > 0.0 {
                    return (c, 0, ((t - times[c]) / span).clamp(0.0, 1.0));
                }
            }
            return (c, c, 0.0);
        }
        let a = (t - times[c]) / (times[c + 1] - times[c]);
        (c, c + 1, a)
    }

    /// Samples the clip at playback time `t` into `out` (one transform per skeleton joint), writing only
    /// the joints the clip drives. Missing channels take the joint's bind value; for an additive clip they
    /// take the identity difference. Rotations are normalised ([`nlerp`] between keys).
    pub fn sample(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        skeleton: &Skeleton,
        t: f32,
        out: &mut [Transform],
    ) -> Result<(), ClipError> {
        self.sample_transforms(clip, binding, skeleton, t, soa::Rotations::Normalized, out)
    }

    /// [`Sampler::sample`] for a normal layer of a blend: the same translations and scales, and
    /// rotations as interpolated, the shortest-path weighted sum of the two keys (a key as stored),
    /// not normalised, because the blend normalises the sum of its layers once (see [`crate::blend`]).
    /// This is what the [`crate::Animator`] blends, so [`crate::BlendBuffers`] fed with it gives the
    /// animator's pose bit for bit.
    pub fn sample_layer(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        skeleton: &Skeleton,
        t: f32,
        out: &mut [Transform],
    ) -> Result<(), ClipError> {
        self.sample_transforms(
            clip,
            binding,
            skeleton,
            t,
            soa::Rotations::Interpolated,
            out,
        )
    }

    pub(super) fn sample_transforms(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        skeleton: &Skeleton,
        t: f32,
        rotations: soa::Rotations,
        out: &mut [Transform],
    ) -> Result<(), ClipError> {
        if out.len() != skeleton.len() {
            return Err(ClipError::OutputLength {
                expected: skeleton.len(),
                got: out.len(),
            });
        }
        if binding.skeleton_len != skeleton.len() {
            return Err(ClipError::BindingMismatch);
        }
        self.sample_each(clip, binding, t, rotations, |pb, block| {
            soa::write_transforms(
                block,
                pb.driven,
                out.get_mut(pb.block * 4..).unwrap_or_default(),
            );
        })
    }

    /// [`Sampler::sample_layer`] into blocks: the same values, bit for bit, written four joints per
    /// block into `out` (a pose of the binding's skeleton), which then holds exactly the joints the
    /// clip drives. For [`BlendBuffers::accumulate_blocks`](crate::BlendBuffers::accumulate_blocks).
    pub fn sample_layer_blocks(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        t: f32,
        out: &mut PoseBlocks,
    ) -> Result<(), ClipError> {
        if binding.skeleton_len != out.joint_count() {
            return Err(ClipError::OutputLength {
                expected: binding.skeleton_len,
                got: out.joint_count(),
            });
        }
        out.held.fill(0);
        let (blocks, held) = (&mut out.blocks, &mut out.held);
        self.sample_each(
            clip,
            binding,
            t,
            soa::Rotations::Interpolated,
            |pb, block| {
                let range = pb.block * soa::COMPONENTS..(pb.block + 1) * soa::COMPONENTS;
                if let (Some(o), Some(h)) = (blocks.get_mut(range), held.get_mut(pb.block)) {
                    o.copy_from_slice(block);
                    *h = pb.driven;
                }
            },
        )
    }

    /// Samples the clip at playback time `t` into `out`, one block of [`soa::COMPONENTS`] vectors per
    /// block of the binding's plan (`out` is resized to that). Lanes of joints the clip does not drive
    /// hold unspecified finite values.
    #[inline(always)]
    pub(crate) fn sample_blocks(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        t: f32,
        out: &mut Vec<glam::Vec4>,
    ) -> Result<(), ClipError> {
        let len = binding.plan.len() * soa::COMPONENTS;
        if out.len() != len {
            out.resize(len, glam::Vec4::ZERO);
        }
        let mut blocks = out.chunks_exact_mut(soa::COMPONENTS);
        self.sample_each(clip, binding, t, soa::Rotations::Normalized, |_, block| {
            if let Some(o) = blocks.next() {
                o.copy_from_slice(block);
            }
        })
    }

    /// Samples the clip at playback time `t` block by block, handing each block of the binding's plan
    /// to `f` as it is made (in plan order). Lanes of joints the clip does not drive hold unspecified
    /// finite values.
    #[inline(always)]
    pub(crate) fn sample_each(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        t: f32,
        rotations: soa::Rotations,
        mut f: impl FnMut(&PlanBlock, &soa::Block),
    ) -> Result<(), ClipError> {
        if binding.joint_of_track.len() != clip.tracks.len()
            || binding.frame_stride != clip.frame_stride()
        {
            return Err(ClipError::BindingMismatch);
        }
        let len = binding.plan.len() * soa::COMPONENTS;
        let t = clip.local_time(t);
        let (k0, k1, a) = self.locate(clip, t);
        let (s0, s1) = self.cache.slots(clip, binding, k0, k1);
        let slots = &self.cache.slots;
        let (c0, c1) = (
            slots.get(s0 * len..(s0 + 1) * len).unwrap_or_default(),
            slots.get(s1 * len..(s1 + 1) * len).unwrap_or_default(),
        );
        let raw = clip.quantized.is_some();
        let blocks = c0
            .chunks_exact(soa::COMPONENTS)
            .zip(c1.chunks_exact(soa::COMPONENTS));
        let mut block = [glam::Vec4::ZERO; soa::COMPONENTS];
        for (pb, (b0, b1)) in binding.plan.iter().zip(blocks) {
            if let (Ok(b0), Ok(b1)) = (<&soa::Block>::try_from(b0), <&soa::Block>::try_from(b1)) {
                soa::sample_block(pb, b0, b1, a, raw, rotations, &mut block);
                f(pb, &block);
            }
        }
        Ok(())
    }
}
