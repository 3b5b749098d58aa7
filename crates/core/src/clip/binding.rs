//! Binding a clip to a skeleton: which joint each track drives, and the sampler's block plan.

use super::data::{animated, Channel, Clip, Identity};
use crate::skeleton::{JointIndex, Skeleton};
use crate::soa::{self, PlanBlock};
use crate::Transform;
use glam::Vec3;

/// A clip bound to a skeleton: for each track, the joint it drives. Made once, reused every frame.
///
/// Besides the joint of each track it holds the sampler's *plan*: the blocks of four skeleton joints
/// the clip drives (structure-of-arrays blocks), per block and channel kind which lanes are animated and the
/// values of the others (constants, bind values), and for every animated component of a driven joint
/// where it sits in a (decoded) frame and where it goes in a block. Sampling then needs no per-joint
/// matching and runs four joints per instruction.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipBinding {
    pub(super) joint_of_track: Vec<Option<JointIndex>>,
    pub(super) unmatched: Vec<String>,
    pub(super) driven: Vec<JointIndex>,
    pub(super) skeleton_len: usize,
    /// Floats per frame of the layout the plan's offsets point into.
    pub(super) frame_stride: usize,
    pub(super) plan: Vec<PlanBlock>,
    /// `(offset in a frame, float index in the plan's blocks)` for every animated component of a
    /// driven joint, by offset.
    pub(super) gather: Vec<(u32, u32)>,
    /// `gather` as the sampler loads keys: whole blocks by transposition where every driven joint of
    /// the block has the same animated channels, single vectors elsewhere.
    pub(super) blocks: Vec<GatherBlock>,
    pub(super) vectors: Vec<GatherVector>,
    /// For a compressed clip (whose keys load without `blocks` and `vectors`): per plan block and
    /// animated kind, the channel each lane decodes, in plan order.
    pub(super) decode: Vec<DecodeBlock>,
    pub(super) id: Identity,
}

/// Four lanes of one plan block that a compressed key decodes straight into, one channel kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct DecodeBlock {
    /// Vector index inside a key slot of the kind's first component.
    pub(super) first: u32,
    /// Per lane: the compressed channel (component / 3) decoded into it, where `lanes` is set.
    pub(super) channel: [u32; 4],
    /// The animated lanes (the others keep their fixed values).
    pub(super) lanes: u8,
    pub(super) rotation: bool,
}

/// The [`DecodeBlock`]s of `plan`: `channel_of(joint, kind)` names the compressed channel animating a
/// joint's kind (translation, rotation, scale) in the lanes the plan marks animated.
pub(super) fn decode_plan(
    plan: &[PlanBlock],
    channel_of: impl Fn(usize, usize) -> u32,
) -> Vec<DecodeBlock> {
    let mut out = Vec::new();
    for (p, pb) in plan.iter().enumerate() {
        for (kind, first) in [soa::T, soa::R, soa::S].into_iter().enumerate() {
            let lanes = pb.animated[kind] & pb.driven;
            if lanes != 0 {
                out.push(DecodeBlock {
                    first: (p * soa::COMPONENTS + first) as u32,
                    channel: [0, 1, 2, 3].map(|l| channel_of(pb.block * 4 + l, kind)),
                    lanes,
                    rotation: kind == 1,
                });
            }
        }
    }
    out
}

/// A block of a key slot loaded by transposition: lane `l`'s animated floats are contiguous in a frame
/// from `base[l]` (lanes of joints the clip does not drive borrow a driven lane's), and float `k` of
/// every lane goes to block component `components[k]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct GatherBlock {
    /// Vector index of the block's first component inside a slot.
    pub(super) first: u32,
    pub(super) base: [u32; 4],
    pub(super) components: [u8; soa::COMPONENTS],
    pub(super) floats: u8,
}

/// Splits `gather` into whole blocks that load by transposition and the remaining vectors.
pub(super) fn gather_plan(
    plan: &[PlanBlock],
    gather: &[(u32, u32)],
) -> (Vec<GatherBlock>, Vec<GatherVector>) {
    let per_block = (soa::COMPONENTS * 4) as u32;
    let mut moves: Vec<(u32, u32)> = gather.iter().map(|&(s, d)| (d, s)).collect();
    moves.sort_unstable();
    let mut blocks = Vec::new();
    let mut rest = Vec::new();
    let mut start = 0;
    while start < moves.len() {
        let pos = moves[start].0 / per_block;
        let end = start + moves[start..].partition_point(|&(d, _)| d / per_block == pos);
        let group = &moves[start..end];
        start = end;
        // Per lane: (component, source) in component order.
        let mut lanes: [Vec<(u8, u32)>; 4] = Default::default();
        for &(d, s) in group {
            let within = d % per_block;
            lanes[(within % 4) as usize].push(((within / 4) as u8, s));
        }
        let driven = plan.get(pos as usize).map_or(0, |pb| pb.driven);
        let reference = lanes.iter().find(|l| !l.is_empty());
        let whole = reference.is_some_and(|r| {
            (0..4).all(|l| {
                let lane = &lanes[l];
                let same = lane.len() == r.len()
                    && lane.iter().zip(r).all(|(a, b)| a.0 == b.0)
                    && lane.windows(2).all(|w| w[1].1 == w[0].1 + 1);
                same || (lane.is_empty() && driven & (1 << l) == 0)
            })
        });
        match reference {
            Some(r) if whole => {
                let mut components = [0u8; soa::COMPONENTS];
                for (k, &(c, _)) in r.iter().enumerate().take(soa::COMPONENTS) {
                    components[k] = c;
                }
                let base = [0, 1, 2, 3].map(|l| lanes[l].first().unwrap_or(&r[0]).1);
                blocks.push(GatherBlock {
                    first: pos * soa::COMPONENTS as u32,
                    base,
                    components,
                    floats: r.len().min(soa::COMPONENTS) as u8,
                });
            }
            _ => rest.extend(gather_vectors(
                &group.iter().map(|&(d, s)| (s, d)).collect::<Vec<_>>(),
            )),
        }
    }
    (blocks, rest)
}

/// One vector of a key slot that holds animated lanes: the frame offset of each lane (0 for lanes that
/// keep their fixed value) and which lanes are animated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct GatherVector {
    /// Vector index inside a slot.
    pub(super) dst: u32,
    pub(super) src: [u32; 4],
    pub(super) lanes: u8,
}

/// Groups `(src, dst)` float moves by destination vector (four floats), in destination order.
pub(super) fn gather_vectors(gather: &[(u32, u32)]) -> Vec<GatherVector> {
    let mut by_dst: Vec<GatherVector> = Vec::new();
    let mut moves: Vec<(u32, u32)> = gather.iter().map(|&(s, d)| (d, s)).collect();
    moves.sort_unstable();
    for (d, s) in moves {
        let (vector, lane) = (d / 4, (d % 4) as usize);
        match by_dst.last_mut() {
            Some(v) if v.dst == vector => {
                v.src[lane] = s;
                v.lanes |= 1 << lane;
            }
            _ => {
                let mut src = [0; 4];
                src[lane] = s;
                by_dst.push(GatherVector {
                    dst: vector,
                    src,
                    lanes: 1 << lane,
                });
            }
        }
    }
    by_dst
}

impl ClipBinding {
    /// Binds the clip's tracks to the skeleton's joints by exact name.
    pub fn new(clip: &Clip, skeleton: &Skeleton) -> ClipBinding {
        let mut joint_of_track = Vec::with_capacity(clip.tracks.len());
        let mut unmatched = Vec::new();
        let mut driven = Vec::new();
        // Per skeleton block: the block being built (None until a driven joint falls in it).
        let mut blocks: Vec<Option<PlanBlock>> = vec![None; soa::block_count(skeleton.len())];
        // (frame offset, joint, component within the block) before blocks get their plan positions.
        let mut gather: Vec<(usize, usize, usize)> = Vec::new();
        let identity = Transform::IDENTITY;
        // Per joint and kind: the compressed channel animating it.
        let mut channel_of = vec![[0u32; 3]; skeleton.len()];
        for t in &clip.tracks {
            let j = skeleton.find(&t.joint);
            joint_of_track.push(j);
            let Some(j) = j else {
                unmatched.push(t.joint.clone());
                continue;
            };
            driven.push(j);
            let ju = j as usize;
            let (b, lane) = (ju / 4, ju % 4);
            let Some(block) = blocks.get_mut(b) else {
                continue;
            };
            let pb = block.get_or_insert_with(|| PlanBlock {
                block: b,
                driven: 0,
                animated: [0; 3],
                source: [soa::Source::Fixed; 3],
                fixed: soa::from_transforms(&[identity; 4])
                    .try_into()
                    .unwrap_or([glam::Vec4::ZERO; soa::COMPONENTS]),
            });
            pb.driven |= 1 << lane;
            let bind = if clip.additive {
                identity
            } else {
                skeleton.bind_local().get(ju).copied().unwrap_or(identity)
            };
            let kinds: [(Option<u32>, [f32; 4], usize, usize); 3] = [
                (
                    animated(t.translation),
                    fixed3(t.translation, bind.translation),
                    soa::T,
                    3,
                ),
                (
                    animated(t.rotation),
                    match t.rotation {
                        Channel::Constant(q) => q.to_array(),
                        _ => bind.rotation.to_array(),
                    },
                    soa::R,
                    4,
                ),
                (animated(t.scale), fixed3(t.scale, bind.scale), soa::S, 3),
            ];
            for (kind, (anim, fixed, first, n)) in kinds.into_iter().enumerate() {
                for (c, &v) in fixed.iter().enumerate().take(n) {
                    pb.fixed[first + c][lane] = v;
                }
                if let Some(o) = anim {
                    pb.animated[kind] |= 1 << lane;
                    if let Some(c) = channel_of.get_mut(ju) {
                        c[kind] = o / 3;
                    }
                    let at = clip.frame_offset(o);
                    for c in 0..n {
                        gather.push((at.saturating_add(c), ju, first + c));
                    }
                }
            }
        }
        driven.sort_unstable();
        let mut position = vec![usize::MAX; blocks.len()];
        let mut plan = Vec::new();
        for (b, block) in blocks.into_iter().enumerate() {
            if let Some(mut pb) = block {
                pb.set_sources();
                position[b] = plan.len();
                plan.push(pb);
            }
        }
        let mut gather: Vec<(u32, u32)> = gather
            .into_iter()
            .filter_map(|(src, j, c)| {
                let pos = *position.get(j / 4)?;
                let dst = (pos * soa::COMPONENTS + c) * 4 + j % 4;
                Some((u32::try_from(src).ok()?, u32::try_from(dst).ok()?))
            })
            .collect();
        gather.sort_unstable();
        let (blocks, vectors, decode) = if clip.quantized.is_some() {
            let decode = decode_plan(&plan, |j, kind| channel_of.get(j).map_or(0, |c| c[kind]));
            (Vec::new(), Vec::new(), decode)
        } else {
            let (blocks, vectors) = gather_plan(&plan, &gather);
            (blocks, vectors, Vec::new())
        };
        ClipBinding {
            decode,
            joint_of_track,
            unmatched,
            driven,
            skeleton_len: skeleton.len(),
            frame_stride: clip.frame_stride(),
            blocks,
            vectors,
            plan,
            gather,
            id: Identity::new(),
        }
    }

    /// The same binding with every channel of the joints `keep` rejects left out: those joints are
    /// neither sampled nor listed in [`ClipBinding::driven`]. The [`crate::Animator`] samples a masked
    /// layer through such a binding (joints whose mask is zero), so a partial-body layer costs only the
    /// joints it reaches. Track-to-joint mapping and unmatched names are those of `self`.
    pub fn restricted(&self, mut keep: impl FnMut(JointIndex) -> bool) -> ClipBinding {
        let mut keep = |j: usize| keep(j as JointIndex);
        let identity = soa::from_transforms(&[Transform::IDENTITY]);
        let mut position = vec![usize::MAX; self.plan.len()];
        let mut plan = Vec::new();
        for (i, pb) in self.plan.iter().enumerate() {
            let mut pb = pb.clone();
            for lane in 0..4 {
                if pb.driven & (1 << lane) != 0 && !keep(pb.block * 4 + lane) {
                    pb.driven &= !(1 << lane);
                    for k in &mut pb.animated {
                        *k &= !(1 << lane);
                    }
                    // Lanes nobody reads still hold finite values (the identity).
                    for (c, v) in identity.iter().enumerate().take(soa::COMPONENTS) {
                        pb.fixed[c][lane] = v[0];
                    }
                }
            }
            if pb.driven != 0 {
                pb.set_sources();
                position[i] = plan.len();
                plan.push(pb);
            }
        }
        let block_floats = soa::COMPONENTS * 4;
        let gather: Vec<(u32, u32)> = self
            .gather
            .iter()
            .filter_map(|&(src, dst)| {
                let (old, within) = (dst as usize / block_floats, dst as usize % block_floats);
                let pos = *position.get(old)?;
                let pb = plan.get(pos)?;
                (pb.driven & (1 << (within % 4)) != 0)
                    .then(|| (src, (pos * block_floats + within) as u32))
            })
            .collect();
        let (blocks, vectors, decode) = if self.decode.is_empty() {
            let (blocks, vectors) = gather_plan(&plan, &gather);
            (blocks, vectors, Vec::new())
        } else {
            // The same channels, in the kept lanes of the kept blocks.
            let mut channel_of = vec![[0u32; 3]; self.skeleton_len];
            for d in &self.decode {
                let (p, c) = (
                    d.first as usize / soa::COMPONENTS,
                    d.first as usize % soa::COMPONENTS,
                );
                let kind = usize::from(c >= soa::R) + usize::from(c >= soa::S);
                let Some(pb) = self.plan.get(p) else { continue };
                for (l, &ch) in d.channel.iter().enumerate() {
                    if let Some(slot) = channel_of.get_mut(pb.block * 4 + l) {
                        slot[kind] = ch;
                    }
                }
            }
            let decode = decode_plan(&plan, |j, kind| channel_of.get(j).map_or(0, |c| c[kind]));
            (Vec::new(), Vec::new(), decode)
        };
        ClipBinding {
            decode,
            joint_of_track: self.joint_of_track.clone(),
            unmatched: self.unmatched.clone(),
            driven: self
                .driven
                .iter()
                .copied()
                .filter(|&j| keep(j as usize))
                .collect(),
            skeleton_len: self.skeleton_len,
            frame_stride: self.frame_stride,
            blocks,
            vectors,
            plan,
            gather,
            id: Identity::new(),
        }
    }

    /// The clip's track names that matched no joint.
    pub fn unmatched(&self) -> &[String] {
        &self.unmatched
    }
    /// The skeleton joints this clip drives, ascending.
    pub fn driven(&self) -> &[JointIndex] {
        &self.driven
    }
    /// For each track of the clip, the joint it drives.
    pub fn joint_of_track(&self) -> &[Option<JointIndex>] {
        &self.joint_of_track
    }
    /// The blocks of four joints this binding samples, ascending.
    pub(crate) fn plan(&self) -> &[PlanBlock] {
        &self.plan
    }
}

/// The fixed value of a translation or scale channel: its constant, or `bind` (padded to four).
pub(super) fn fixed3(c: Channel<Vec3>, bind: Vec3) -> [f32; 4] {
    let v = match c {
        Channel::Constant(v) => v,
        _ => bind,
    };
    [v.x, v.y, v.z, 0.0]
}
