//! The sampler's two decoded keys of one clip in one binding's block layout, and the compressed key decode (portable and AVX2).

use super::binding::{ClipBinding, DecodeBlock};
use super::data::{Clip, FRAME_PAD};
use crate::compressed::{LaneTable, Quantized};
use crate::soa::{self};

/// Two keys of one clip, in one binding's block layout.
#[derive(Debug, Clone, Default)]
pub(super) struct KeyCache {
    /// Identities of the clip and binding the slots belong to.
    pub(super) owner: Option<(u64, u64)>,
    /// The key held by each slot (`usize::MAX` = empty).
    pub(super) keys: [usize; 2],
    /// Two slots of `plan.len() * COMPONENTS` vectors: fixed values, animated lanes from the key.
    pub(super) slots: Vec<glam::Vec4>,
    /// For a compressed clip: the segment whose decode tables `tables` holds (`usize::MAX` = none),
    /// and one table per [`DecodeBlock`] of the binding. Made when the cursor enters a segment.
    pub(super) table_segment: usize,
    pub(super) tables: Vec<LaneTable>,
}

impl KeyCache {
    /// The slots holding keys `k0` and `k1`, loading whichever is missing.
    #[inline(always)]
    pub(super) fn slots(
        &mut self,
        clip: &Clip,
        binding: &ClipBinding,
        k0: usize,
        k1: usize,
    ) -> (usize, usize) {
        let len = binding.plan.len() * soa::COMPONENTS;
        let owner = Some((clip.id.0, binding.id.0));
        if self.owner != owner || self.slots.len() != 2 * len {
            self.owner = owner;
            self.keys = [usize::MAX; 2];
            self.table_segment = usize::MAX;
            self.slots.clear();
            for _ in 0..2 {
                for pb in &binding.plan {
                    self.slots.extend_from_slice(&pb.fixed);
                }
            }
        }
        let find = |k: usize| self.keys.iter().position(|&x| x == k);
        let (s0, s1) = match (find(k0), find(k1)) {
            (Some(a), Some(b)) => return (a, b),
            (Some(a), None) => (a, 1 - a),
            (None, Some(b)) => (1 - b, b),
            (None, None) => (0, if k0 == k1 { 0 } else { 1 }),
        };
        for (slot, k) in [(s0, k0), (s1, k1)] {
            if self.keys[slot] != k {
                self.load(clip, binding, k, slot * len);
                self.keys[slot] = k;
            }
        }
        (s0, s1)
    }

    /// Gathers key `k`'s animated components into the slot starting at vector `base`.
    #[inline(always)]
    pub(super) fn load(&mut self, clip: &Clip, binding: &ClipBinding, k: usize, base: usize) {
        let frame: &[f32] = match &clip.quantized {
            None => {
                // The frame and the floats after it (the next frame or the padding): runs are read
                // four floats at a time.
                let s = clip.stride;
                clip.frames
                    .get(k * s..(k + 1) * s + FRAME_PAD)
                    .unwrap_or_default()
            }
            Some(q) => {
                // Decoded four lanes at a time straight into the slot.
                let Some((segment, bit)) = q.key_start(k) else {
                    return;
                };
                if self.table_segment != segment {
                    self.tables.clear();
                    self.tables.extend(
                        binding
                            .decode
                            .iter()
                            .map(|d| q.lane_table(segment, d.channel, d.lanes)),
                    );
                    self.table_segment = segment;
                }
                decode_key(q, bit, &binding.decode, &self.tables, &mut self.slots, base);
                return;
            }
        };
        // Whole vectors are built in registers and stored once (scalar stores into a vector that is
        // read right after would defeat store-to-load forwarding).
        let slots = &mut self.slots;
        let row = |i: usize| {
            frame
                .get(i..i + 4)
                .map_or(glam::Vec4::ZERO, glam::Vec4::from_slice)
        };
        for g in &binding.blocks {
            let first = base + g.first as usize;
            let Some(Ok(block)) = slots
                .get_mut(first..first + soa::COMPONENTS)
                .map(<&mut soa::Block>::try_from)
            else {
                continue;
            };
            let [b0, b1, b2, b3] = g.base.map(|b| b as usize);
            for k in (0..g.floats as usize).step_by(4) {
                // Four floats of each lane's run, transposed into one vector per component.
                let t = glam::Mat4::from_cols(row(b0 + k), row(b1 + k), row(b2 + k), row(b3 + k))
                    .transpose();
                for (i, v) in [t.x_axis, t.y_axis, t.z_axis, t.w_axis]
                    .into_iter()
                    .enumerate()
                {
                    if k + i < g.floats as usize {
                        if let Some(slot) = block.get_mut(g.components[k + i] as usize) {
                            *slot = v;
                        }
                    }
                }
            }
        }
        let f = |i: u32| frame.get(i as usize).copied().unwrap_or(0.0);
        for g in &binding.vectors {
            if let Some(slot) = slots.get_mut(base + g.dst as usize) {
                let v = glam::Vec4::new(f(g.src[0]), f(g.src[1]), f(g.src[2]), f(g.src[3]));
                *slot = if g.lanes == 0b1111 {
                    v
                } else {
                    glam::Vec4::select(soa::lanes(g.lanes), v, *slot)
                };
            }
        }
    }
}

crate::cpu::dispatch_avx2! {
    /// Decodes the compressed key record starting at `bit` into the key slot starting at vector
    /// `base`: each [`DecodeBlock`] with its table, four lanes at a time.
    pub(super) fn decode_key(
        q: &Quantized,
        bit: usize,
        decode: &[DecodeBlock],
        tables: &[LaneTable],
        slots: &mut [glam::Vec4],
        base: usize,
    ) -> () => decode_key_portable, decode_key_avx2;
}

#[inline(always)]
pub(super) fn decode_key_portable(
    q: &Quantized,
    bit: usize,
    decode: &[DecodeBlock],
    tables: &[LaneTable],
    slots: &mut [glam::Vec4],
    base: usize,
) {
    for (d, table) in decode.iter().zip(tables) {
        store_lanes(d, q.decode_lanes(bit, table, d.rotation), slots, base);
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) fn decode_key_avx2(
    q: &Quantized,
    bit: usize,
    decode: &[DecodeBlock],
    tables: &[LaneTable],
    slots: &mut [glam::Vec4],
    base: usize,
) {
    for (d, table) in decode.iter().zip(tables) {
        let values = if table.one_load {
            q.decode_lanes_avx2(bit, table, d.rotation)
        } else {
            q.decode_lanes(bit, table, d.rotation)
        };
        store_lanes(d, values, slots, base);
    }
}

/// Stores a [`DecodeBlock`]'s decoded values in its animated lanes of the slot at vector `base`.
#[inline(always)]
pub(super) fn store_lanes(
    d: &DecodeBlock,
    values: [glam::Vec4; 4],
    slots: &mut [glam::Vec4],
    base: usize,
) {
    let first = base + d.first as usize;
    let n = if d.rotation { 4 } else { 3 };
    if let Some(dst) = slots.get_mut(first..first + n) {
        let keep = soa::lanes(d.lanes);
        for (o, v) in dst.iter_mut().zip(values) {
            *o = glam::Vec4::select(keep, v, *o);
        }
    }
}
