//! Per-character animation state over shared clips: layers, a play queue with cross-fades, dormant clips.
//!
//! An [`Animator`] holds, for one character, every clip it may play. Each clip is added once
//! ([`Animator::add_clip`]): it is bound to the skeleton by name, given a sampling cursor and a pose
//! buffer, and starts **dormant** (bound, not playing). A dormant clip costs nothing per frame and can be
//! activated at any time without rebinding or allocating.
//!
//! Playing clips are **layers**. A layer has a time, a speed, a weight, an optional per-joint mask, and a
//! fade factor (0..1, moved linearly by fades). Its effective weight is `weight * fade`. Non-additive
//! layers are blended as [`crate::BlendBuffers`] blends layers sampled with
//! [`Sampler::sample_layer`] (rotations as interpolated, normalised once after the blend); additive
//! layers, sampled with [`Sampler::sample`], are applied on top, in the order the clips were added
//! (see [`crate::blend`]). The result is the same bits as those per-joint functions (tested); the
//! animator computes it four joints at a time (structure-of-arrays blocks), sampling a masked layer only where
//! its mask reaches.
//!
//! One layer may be the **current** clip of the play sequence, with a **queue** of clips to play next.
//! When the current clip ends — a non-looping clip reaching its duration, or a looping clip completing
//! a cycle — and the queue is not empty, the next clip starts at time 0 and fades in linearly over its
//! fade length while the previous one fades out over the same length (from whatever fade factor it had
//! to 0) and then goes dormant. [`Animator::cross_fade`] and [`Animator::skip`] do the same immediately.
//! Time past the end inside the frame that ended the clip is carried over into the next clip and its
//! fade, so the transition does not depend on frame boundaries. A clip only ends while its speed is
//! positive. A non-looping clip that ended holds its last frame while it fades out.
//!
//! [`Animator::update`] and [`Animator::evaluate`] never allocate.

use crate::blend::{apply_additive, BlendError, Layer};
use crate::clip::{ClipBinding, ClipError, Sampler};
use crate::cpu::multiversion;
use crate::skinning::{self, SkinError};
use crate::soa;
use crate::{Clip, Skeleton, Transform};
use glam::{Mat4, Vec4};
use std::collections::VecDeque;
use std::sync::Arc;

/// Identifies a clip inside one [`Animator`] (the order clips were added, from 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ClipId(pub usize);

/// Why an animator call was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AnimatorError {
    /// No clip with this id was added.
    #[error("no clip {0:?} in this animator")]
    UnknownClip(ClipId),
    /// A mask has the wrong length or a negative or non-finite value.
    #[error("mask must hold {expected} finite values >= 0 (got {got} values)")]
    BadMask {
        /// Joints in the skeleton.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// A weight, speed, time or fade length that is not finite (or a negative fade length).
    #[error("{0} must be finite (and a fade length not negative)")]
    BadValue(&'static str),
    /// Sampling failed (a binding made for another skeleton, or a wrong output length).
    #[error(transparent)]
    Clip(#[from] ClipError),
    /// Blending failed.
    #[error(transparent)]
    Blend(#[from] BlendError),
    /// Local-to-model or the palette failed (output buffers of the wrong length).
    #[error(transparent)]
    Skin(#[from] SkinError),
}

/// A linear fade of a layer's fade factor from `from` to `to` over `length` seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Fade {
    from: f32,
    to: f32,
    elapsed: f32,
    length: f32,
}

impl Fade {
    const FULL: Fade = Fade {
        from: 1.0,
        to: 1.0,
        elapsed: 0.0,
        length: 0.0,
    };

    fn factor(&self) -> f32 {
        if self.length <= 0.0 || self.elapsed >= self.length {
            self.to
        } else {
            self.from + (self.to - self.from) * (self.elapsed / self.length)
        }
    }

    fn done(&self) -> bool {
        self.length <= 0.0 || self.elapsed >= self.length
    }
}

#[derive(Debug, Clone)]
struct Slot {
    clip: Arc<Clip>,
    binding: Arc<ClipBinding>,
    /// `binding` restricted to the joints the mask reaches (mask > 0); `None` without a mask.
    masked: Option<ClipBinding>,
    sampler: Sampler,
    /// The layer's last sampled blocks (one per block of its binding's plan).
    blocks: Vec<Vec4>,
    mask: Option<Vec<f32>>,
    /// `mask` as blocks of four joints.
    mask_blocks: Option<Vec<Vec4>>,
    active: bool,
    time: f32,
    speed: f32,
    weight: f32,
    fade: Fade,
}

/// Per-character animation state. See the module docs.
#[derive(Debug, Clone)]
pub struct Animator {
    skeleton: Arc<Skeleton>,
    slots: Vec<Slot>,
    current: Option<usize>,
    queue: VecDeque<(usize, f32)>,
    /// Blend accumulators, [`soa::ACCUM`] vectors per block of four joints.
    accum: Vec<Vec4>,
    /// The blended local pose, [`soa::COMPONENTS`] vectors per block.
    local: Vec<Vec4>,
    /// Local transforms, for additive layers and the per-joint output.
    locals: Vec<Transform>,
    /// An additive layer's sampled differences, one per joint.
    differences: Vec<Transform>,
    /// Local matrices for [`Animator::evaluate_palette`].
    local_matrices: Vec<f32>,
}

impl Animator {
    /// An animator with no clips for a character on `skeleton`.
    pub fn new(skeleton: Arc<Skeleton>) -> Self {
        let n = skeleton.len();
        Self {
            slots: Vec::new(),
            current: None,
            queue: VecDeque::new(),
            accum: vec![Vec4::ZERO; soa::block_count(n) * soa::ACCUM],
            local: vec![Vec4::ZERO; soa::block_count(n) * soa::COMPONENTS],
            locals: skeleton_bind(&skeleton),
            differences: vec![Transform::IDENTITY; n],
            local_matrices: vec![0.0; soa::block_count(n) * 48],
            skeleton,
        }
    }

    /// The skeleton this animator poses.
    pub fn skeleton(&self) -> &Arc<Skeleton> {
        &self.skeleton
    }

    /// Adds a clip, binding it to the skeleton by joint name. The clip starts dormant.
    pub fn add_clip(&mut self, clip: Arc<Clip>) -> ClipId {
        let binding = Arc::new(ClipBinding::new(&clip, &self.skeleton));
        self.push_slot(clip, binding)
    }

    /// Adds a clip with a binding made earlier (and shared between characters). The binding must have
    /// been made for this clip and this animator's skeleton.
    pub fn add_bound_clip(
        &mut self,
        clip: Arc<Clip>,
        binding: Arc<ClipBinding>,
    ) -> Result<ClipId, AnimatorError> {
        // Sampling once checks the binding against clip and skeleton.
        let mut pose = self.skeleton.bind_local().to_vec();
        Sampler::new().sample(&clip, &binding, &self.skeleton, 0.0, &mut pose)?;
        Ok(self.push_slot(clip, binding))
    }

    fn push_slot(&mut self, clip: Arc<Clip>, binding: Arc<ClipBinding>) -> ClipId {
        let id = self.slots.len();
        let mut sampler = Sampler::new();
        let mut blocks = Vec::new();
        // Sizes the sampler's key cache and the blocks now, so that frames never allocate.
        let _ = sampler.sample_blocks(&clip, &binding, 0.0, &mut blocks);
        self.slots.push(Slot {
            clip,
            binding,
            masked: None,
            sampler,
            blocks,
            mask: None,
            mask_blocks: None,
            active: false,
            time: 0.0,
            speed: 1.0,
            weight: 1.0,
            fade: Fade::FULL,
        });
        self.queue.reserve(self.slots.len());
        ClipId(id)
    }

    fn slot(&self, id: ClipId) -> Result<&Slot, AnimatorError> {
        self.slots.get(id.0).ok_or(AnimatorError::UnknownClip(id))
    }

    fn slot_mut(&mut self, id: ClipId) -> Result<&mut Slot, AnimatorError> {
        self.slots
            .get_mut(id.0)
            .ok_or(AnimatorError::UnknownClip(id))
    }

    /// Number of clips added.
    pub fn clip_count(&self) -> usize {
        self.slots.len()
    }

    /// The clip behind an id.
    pub fn clip(&self, id: ClipId) -> Result<&Arc<Clip>, AnimatorError> {
        Ok(&self.slot(id)?.clip)
    }

    /// The binding of a clip (for its unmatched track names).
    pub fn binding(&self, id: ClipId) -> Result<&Arc<ClipBinding>, AnimatorError> {
        Ok(&self.slot(id)?.binding)
    }

    /// Sets or clears a clip's per-joint mask (one value >= 0 per skeleton joint).
    pub fn set_mask(&mut self, id: ClipId, mask: Option<Vec<f32>>) -> Result<(), AnimatorError> {
        let n = self.skeleton.len();
        if let Some(m) = &mask {
            if m.len() != n || !m.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(AnimatorError::BadMask {
                    expected: n,
                    got: m.len(),
                });
            }
        }
        let s = self.slot_mut(id)?;
        s.masked = mask.as_deref().map(|m| {
            s.binding
                .restricted(|j| m.get(j as usize).is_some_and(|&w| w > 0.0))
        });
        s.mask_blocks = mask.as_deref().map(|m| {
            let mut blocks = vec![Vec4::ZERO; soa::block_count(m.len())];
            for (j, &v) in m.iter().enumerate() {
                blocks[j / 4][j % 4] = v;
            }
            blocks
        });
        s.mask = mask;
        let binding = s.masked.as_ref().unwrap_or(&s.binding);
        let _ = s
            .sampler
            .sample_blocks(&s.clip, binding, s.time, &mut s.blocks);
        Ok(())
    }

    /// Sets a clip's layer weight (default 1).
    pub fn set_weight(&mut self, id: ClipId, weight: f32) -> Result<(), AnimatorError> {
        finite(weight, "weight")?;
        self.slot_mut(id)?.weight = weight;
        Ok(())
    }

    /// Sets a clip's playback speed (default 1; negative plays backwards).
    pub fn set_speed(&mut self, id: ClipId, speed: f32) -> Result<(), AnimatorError> {
        finite(speed, "speed")?;
        self.slot_mut(id)?.speed = speed;
        Ok(())
    }

    /// Sets a clip's playback time, seconds.
    pub fn set_time(&mut self, id: ClipId, time: f32) -> Result<(), AnimatorError> {
        finite(time, "time")?;
        self.slot_mut(id)?.time = time;
        Ok(())
    }

    /// A clip's playback time (wrapped for looping clips, clamped for others).
    pub fn time(&self, id: ClipId) -> Result<f32, AnimatorError> {
        Ok(self.slot(id)?.time)
    }

    /// True when the clip is playing (it is a layer), false when dormant.
    pub fn is_active(&self, id: ClipId) -> Result<bool, AnimatorError> {
        Ok(self.slot(id)?.active)
    }

    /// A clip's effective blend weight this frame: `weight * fade`, or 0 when dormant.
    pub fn effective_weight(&self, id: ClipId) -> Result<f32, AnimatorError> {
        let s = self.slot(id)?;
        Ok(if s.active {
            s.weight * s.fade.factor()
        } else {
            0.0
        })
    }

    /// Makes a dormant clip a layer at time 0 and full fade (an active clip keeps its time), outside the
    /// play sequence. Use this for masked or additive layers on top of the sequence.
    pub fn activate(&mut self, id: ClipId) -> Result<(), AnimatorError> {
        let s = self.slot_mut(id)?;
        if !s.active {
            s.time = 0.0;
            s.sampler = Sampler::new();
        }
        s.active = true;
        s.fade = Fade::FULL;
        Ok(())
    }

    /// Fades a layer's fade factor linearly to `to` over `length` seconds (activating it at fade 0 and
    /// time 0 if dormant). A layer that fades to 0 goes dormant when the fade ends.
    pub fn fade_to(&mut self, id: ClipId, to: f32, length: f32) -> Result<(), AnimatorError> {
        finite(to, "fade target")?;
        fade_length(length)?;
        let s = self.slot_mut(id)?;
        let from = if s.active { s.fade.factor() } else { 0.0 };
        if !s.active {
            s.time = 0.0;
            s.sampler = Sampler::new();
        }
        s.active = true;
        s.fade = Fade {
            from,
            to,
            elapsed: 0.0,
            length,
        };
        Ok(())
    }

    /// Stops a layer at once; it goes dormant (still bound). If it was the current clip, the sequence
    /// has no current clip until the next [`play`](Self::play), [`cross_fade`](Self::cross_fade) or
    /// [`skip`](Self::skip).
    pub fn deactivate(&mut self, id: ClipId) -> Result<(), AnimatorError> {
        self.slot_mut(id)?.active = false;
        if self.current == Some(id.0) {
            self.current = None;
        }
        Ok(())
    }

    /// The current clip of the play sequence.
    pub fn current(&self) -> Option<ClipId> {
        self.current.map(ClipId)
    }

    /// The queued clips with their fade lengths, next first.
    pub fn queued(&self) -> impl Iterator<Item = (ClipId, f32)> + '_ {
        self.queue.iter().map(|&(i, f)| (ClipId(i), f))
    }

    /// Makes `id` the current clip at once, with no fade: the previous current clip goes dormant.
    pub fn play(&mut self, id: ClipId) -> Result<(), AnimatorError> {
        self.cross_fade(id, 0.0)
    }

    /// Makes `id` the current clip now, starting at time 0 and fading in over `fade` seconds while the
    /// previous current clip fades out. The queue is kept and follows the new clip.
    pub fn cross_fade(&mut self, id: ClipId, fade: f32) -> Result<(), AnimatorError> {
        fade_length(fade)?;
        self.slot(id)?;
        self.transition(id.0, fade, 0.0);
        Ok(())
    }

    /// Queues `id` to start, with a cross-fade of `fade` seconds, when the clips queued before it have
    /// played. With no current clip it starts now.
    pub fn enqueue(&mut self, id: ClipId, fade: f32) -> Result<(), AnimatorError> {
        fade_length(fade)?;
        self.slot(id)?;
        if self.current.is_none() {
            self.transition(id.0, fade, 0.0);
        } else {
            self.queue.push_back((id.0, fade));
        }
        Ok(())
    }

    /// Starts the next queued clip now, with its fade. Returns false when the queue is empty.
    pub fn skip(&mut self) -> bool {
        match self.queue.pop_front() {
            Some((next, fade)) => {
                self.transition(next, fade, 0.0);
                true
            }
            None => false,
        }
    }

    /// Removes every queued clip.
    pub fn clear_queue(&mut self) {
        self.queue.clear();
    }

    /// `next` becomes current; `carry` seconds have already passed since the switch.
    fn transition(&mut self, next: usize, fade: f32, carry: f32) {
        if let Some(prev) = self.current {
            if prev != next {
                if let Some(p) = self.slots.get_mut(prev) {
                    if fade <= 0.0 {
                        p.active = false;
                    } else {
                        p.fade = Fade {
                            from: p.fade.factor(),
                            to: 0.0,
                            elapsed: carry,
                            length: fade,
                        };
                        if p.fade.done() {
                            p.active = false;
                        }
                    }
                }
            }
        }
        let Some(s) = self.slots.get_mut(next) else {
            return;
        };
        let from = if s.active { s.fade.factor() } else { 0.0 };
        s.active = true;
        s.sampler = Sampler::new();
        s.time = wrap_time(&s.clip, carry * s.speed);
        s.fade = if fade <= 0.0 {
            Fade::FULL
        } else {
            Fade {
                from,
                to: 1.0,
                elapsed: carry,
                length: fade,
            }
        };
        self.current = Some(next);
    }

    /// Advances every layer's time by `dt * speed` and every fade by `dt` seconds, then moves the queue
    /// on if the current clip ended. A `dt` that is negative or not finite does nothing.
    pub fn update(&mut self, dt: f32) {
        if !dt.is_finite() || dt < 0.0 {
            return;
        }
        let mut ended: Option<f32> = None;
        for (i, s) in self.slots.iter_mut().enumerate() {
            if !s.active {
                continue;
            }
            let d = s.clip.duration();
            let raw = s.time + dt * s.speed;
            if self.current == Some(i) && s.speed > 0.0 && raw >= d {
                // Seconds of this frame left after the end.
                ended = Some(((raw - d) / s.speed).clamp(0.0, dt));
            }
            s.time = wrap_time(&s.clip, raw);
            s.fade.elapsed += dt;
            if s.fade.done() && s.fade.to <= 0.0 {
                s.active = false;
                if self.current == Some(i) {
                    self.current = None;
                }
            }
        }
        if let Some(carry) = ended {
            if let Some((next, fade)) = self.queue.pop_front() {
                self.transition(next, fade, carry);
            }
        }
    }

    /// Samples every active layer with its own cursor and blends them into `out` (one local transform
    /// per skeleton joint). Joints no layer drives take the bind pose.
    pub fn evaluate(&mut self, out: &mut [Transform]) -> Result<(), AnimatorError> {
        let n = self.skeleton.len();
        if out.len() != n {
            return Err(ClipError::OutputLength {
                expected: n,
                got: out.len(),
            }
            .into());
        }
        self.blend_normal_layers()?;
        for (block, o) in self
            .local
            .chunks_exact(soa::COMPONENTS)
            .zip(out.chunks_mut(4))
        {
            soa::write_transforms(block, 0b1111, o);
        }
        self.apply_additive_layers(out)
    }

    /// [`Animator::evaluate`] followed by [`crate::local_to_model_and_palette`]: the model matrix of every
    /// joint and its skinning palette entry, for this frame. Without additive layers the blended pose
    /// goes from the blend's four-joint blocks straight into local-to-model; the results are the same
    /// bits as the two calls.
    pub fn evaluate_palette(
        &mut self,
        models: &mut [Mat4],
        palette: &mut [Mat4],
    ) -> Result<(), AnimatorError> {
        if self.slots.iter().any(|s| s.active && s.clip.additive()) {
            let mut locals = std::mem::take(&mut self.locals);
            let result = self.evaluate(&mut locals);
            self.locals = locals;
            result?;
            skinning::local_to_model_and_palette(
                self.skeleton.parents(),
                &self.locals,
                self.skeleton.inverse_bind(),
                models,
                palette,
            )?;
            return Ok(());
        }
        self.blend_normal_layers()?;
        // Field by field, so that the skeleton is borrowed, not cloned (an `Arc` clone is two atomic
        // operations per frame).
        skinning::local_to_model_and_palette_blocks(
            &self.skeleton,
            &self.local,
            &mut self.local_matrices,
            models,
            palette,
        )?;
        Ok(())
    }

    /// Samples the active normal layers and blends them into `self.local` (blocks).
    fn blend_normal_layers(&mut self) -> Result<(), AnimatorError> {
        blend_layers(
            &mut self.slots,
            self.skeleton.bind_blocks(),
            &mut self.accum,
            &mut self.local,
        )
    }

    /// Applies the active additive layers, in the order their clips were added, to `out`.
    fn apply_additive_layers(&mut self, out: &mut [Transform]) -> Result<(), AnimatorError> {
        for s in self.slots.iter_mut() {
            let w = s.weight * s.fade.factor();
            if !s.active || !s.clip.additive() || w.is_nan() || w <= 0.0 {
                continue;
            }
            let binding = s.masked.as_ref().unwrap_or(&s.binding);
            s.sampler
                .sample_blocks(&s.clip, binding, s.time, &mut s.blocks)?;
            for (pb, block) in binding
                .plan()
                .iter()
                .zip(s.blocks.chunks_exact(soa::COMPONENTS))
            {
                let out = self.differences.get_mut(pb.block * 4..).unwrap_or_default();
                soa::write_transforms(block, pb.driven, out);
            }
            apply_additive(
                out,
                &Layer {
                    pose: &self.differences,
                    driven: binding.driven(),
                    weight: w,
                    mask: s.mask.as_deref(),
                },
            )?;
        }
        Ok(())
    }
}

multiversion! {
    /// Samples the active normal layers of `slots` and blends them into `local` (blocks), with `bind`
    /// (blocks) where their weights fall short.
    fn blend_layers(
        slots: &mut [Slot],
        bind: &[Vec4],
        accum: &mut [Vec4],
        local: &mut [Vec4],
    ) -> Result<(), AnimatorError> => blend_layers_generic;
}

#[inline(always)]
fn blend_layers_generic(
    slots: &mut [Slot],
    bind: &[Vec4],
    accum: &mut [Vec4],
    local: &mut [Vec4],
) -> Result<(), AnimatorError> {
    accum.fill(Vec4::ZERO);
    for s in slots.iter_mut() {
        let w = s.weight * s.fade.factor();
        if !s.active || s.clip.additive() || w.is_nan() || w <= 0.0 {
            continue;
        }
        let binding = s.masked.as_ref().unwrap_or(&s.binding);
        let mask = s.mask_blocks.as_deref();
        s.sampler.sample_each(
            &s.clip,
            binding,
            s.time,
            soa::Rotations::Interpolated,
            |pb, block| {
                soa::accumulate_block(accum, pb, block, w, mask);
            },
        )?;
    }
    soa::resolve(accum, bind, local);
    Ok(())
}

fn skeleton_bind(skeleton: &Skeleton) -> Vec<Transform> {
    skeleton.bind_local().to_vec()
}

/// Wraps a looping clip's time into `[0, duration)`; clamps a non-looping clip's into `[0, duration]`.
fn wrap_time(clip: &Clip, t: f32) -> f32 {
    let d = clip.duration();
    if clip.looping() {
        if t >= 0.0 && t < d {
            // `rem_euclid` would return `t` itself, at the cost of a library call per frame.
            return t;
        }
        if d > 0.0 {
            let r = t.rem_euclid(d);
            if r >= d {
                0.0
            } else {
                r
            }
        } else {
            0.0
        }
    } else {
        t.clamp(0.0, d)
    }
}

fn finite(v: f32, what: &'static str) -> Result<(), AnimatorError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(AnimatorError::BadValue(what))
    }
}

fn fade_length(v: f32) -> Result<(), AnimatorError> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(AnimatorError::BadValue("fade length"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Curve, JointDesc, TrackCurves};
    use glam::{Quat, Vec3};

    /// A 9-joint chain-and-branches skeleton, two clips over overlapping joints, masks and a fade.
    fn animator() -> Animator {
        let joints = (0..9)
            .map(|i| JointDesc {
                name: format!("j{i}"),
                parent: (i > 0).then(|| format!("j{}", [0, 0, 1, 2, 1, 4, 0, 6, 7][i])),
                bind_local: Transform::new(
                    Vec3::new(i as f32, 1.0, -0.5 * i as f32),
                    Quat::from_rotation_z(0.1 * i as f32),
                    Vec3::new(1.0, 1.0 + 0.1 * i as f32, 1.0),
                ),
                inverse_bind: None,
            })
            .collect();
        let skeleton = Arc::new(Skeleton::from_unordered(joints).unwrap().0);
        let times: Vec<f32> = (0..7).map(|k| k as f32 / 6.0).collect();
        let clip = |name: &str, phase: f32, joints: std::ops::Range<usize>| {
            let tracks = joints
                .map(|j| TrackCurves {
                    joint: format!("j{j}"),
                    translation: Curve::new(
                        times.clone(),
                        times
                            .iter()
                            .map(|&t| Vec3::splat((t + phase) * j as f32))
                            .collect(),
                    ),
                    rotation: Curve::new(
                        times.clone(),
                        times
                            .iter()
                            .map(|&t| Quat::from_rotation_x(3.0 * t + phase + j as f32))
                            .collect(),
                    ),
                    scale: Curve::new(vec![0.0], vec![Vec3::splat(1.0 + phase)]),
                })
                .collect();
            Arc::new(Clip::from_curves(name, 1.0, 6.0, true, false, tracks).unwrap())
        };
        let mut anim = Animator::new(skeleton);
        let a = anim.add_clip(clip("a", 0.0, 0..9));
        let b = anim.add_clip(clip("b", 0.5, 3..9));
        anim.set_mask(b, Some((0..9).map(|j| j as f32 * 0.2).collect()))
            .unwrap();
        anim.play(a).unwrap();
        anim.fade_to(b, 0.9, 0.5).unwrap();
        anim.set_weight(a, 0.7).unwrap();
        anim
    }

    #[test]
    fn avx_and_baseline_frames_are_the_same_bits() {
        let (mut fast, mut base) = (animator(), animator());
        let n = fast.skeleton().len();
        let bits = |m: &[Mat4]| -> Vec<u32> {
            m.iter()
                .flat_map(|m| m.to_cols_array())
                .map(f32::to_bits)
                .collect()
        };
        for _ in 0..40 {
            fast.update(1.0 / 50.0);
            base.update(1.0 / 50.0);
            let (mut m1, mut p1) = (vec![Mat4::ZERO; n], vec![Mat4::ZERO; n]);
            let (mut m2, mut p2) = (vec![Mat4::ZERO; n], vec![Mat4::ZERO; n]);
            fast.evaluate_palette(&mut m1, &mut p1).unwrap();
            crate::cpu::baseline(|| base.evaluate_palette(&mut m2, &mut p2)).unwrap();
            assert_eq!(bits(&m1), bits(&m2));
            assert_eq!(bits(&p1), bits(&p2));
            let (mut l1, mut l2) = (vec![Transform::IDENTITY; n], vec![Transform::IDENTITY; n]);
            fast.evaluate(&mut l1).unwrap();
            crate::cpu::baseline(|| base.evaluate(&mut l2)).unwrap();
            assert_eq!(l1, l2);
            // The block path and the per-joint functions agree too.
            let (mut m3, mut p3) = (vec![Mat4::ZERO; n], vec![Mat4::ZERO; n]);
            let s = fast.skeleton().clone();
            skinning::local_to_model_and_palette(
                s.parents(),
                &l1,
                s.inverse_bind(),
                &mut m3,
                &mut p3,
            )
            .unwrap();
            assert_eq!(bits(&m1), bits(&m3));
            assert_eq!(bits(&p1), bits(&p3));
        }
    }
}
