//! Decoder of the `GAME` section (format 1.3): game data kept from the source.

use super::cursor::{f32s_of, Cur, Result, Strs};
use crate::format::error::FormatErrorKind as K;
use crate::format::game::{
    Attachment, BodyGroup, BoneController, ClipBlend, ClipEvent, ClipGameData, GameData, Hitbox,
    MaterialFlags,
};
use crate::format::write::GAME_CLIP_RECORD;
use crate::format::NO_STRING;

/// Most skin families a GAME section may declare when they have no slots (GoldSrc allows 100).
pub const MAX_EMPTY_SKIN_FAMILIES: u64 = 256;

fn vec3(b: &[u8]) -> [f32; 3] {
    let mut f = f32s_of(b);
    [
        f.next().unwrap_or(0.0),
        f.next().unwrap_or(0.0),
        f.next().unwrap_or(0.0),
    ]
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    b.get(at..at + 4)
        .map_or(0, |s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
}

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_bits(u32_at(b, at))
}

/// Checks that every float of a record is finite.
fn finite(c: &Cur, at: usize, values: &[f32], what: &'static str) -> Result<()> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(c.err_at(at, K::NonFinite { what }))
    }
}

/// A string index inside a record, looked up (or empty for [`NO_STRING`] when `optional`).
fn string(
    c: &Cur,
    strs: &Strs,
    at: usize,
    index: u32,
    optional: bool,
    what: &'static str,
) -> Result<String> {
    if optional && index == NO_STRING {
        return Ok(String::new());
    }
    strs.get(c, at, index, what)
}

/// Reads the section (layout in docs/format.md).
pub(super) fn game(c: &mut Cur, strs: &Strs) -> Result<GameData> {
    let flags = c.u32()?;
    let eye_at = c.pos;
    let eye = [c.f32()?, c.f32()?, c.f32()?];
    finite(c, eye_at, &eye, "eye position")?;
    let mut n = [0u64; 11];
    for v in &mut n {
        *v = c.u32()?.into();
    }
    c.skip(4)?;
    let [attachments, hitboxes, controllers, groups, entries, families, slots, material_flags, clips, events, nodes] =
        n;
    let mut g = GameData {
        eye_position: (flags & 1 != 0).then_some(eye),
        ..GameData::default()
    };
    let b = c.elements(attachments, 20, "attachments")?;
    for (k, r) in b.chunks_exact(20).enumerate() {
        let at = c.pos - b.len() + 20 * k;
        let offset = vec3(&r[8..20]);
        finite(c, at, &offset, "attachment offset")?;
        g.attachments.push(Attachment {
            name: string(c, strs, at, u32_at(r, 0), false, "attachment name string")?,
            joint: string(c, strs, at, u32_at(r, 4), false, "attachment joint string")?,
            offset,
        });
    }
    c.align()?;
    let b = c.elements(hitboxes, 32, "hit boxes")?;
    for (k, r) in b.chunks_exact(32).enumerate() {
        let at = c.pos - b.len() + 32 * k;
        let (min, max) = (vec3(&r[8..20]), vec3(&r[20..32]));
        finite(c, at, &[min, max].concat(), "hit box corner")?;
        g.hitboxes.push(Hitbox {
            joint: string(c, strs, at, u32_at(r, 0), false, "hit box joint string")?,
            group: u32_at(r, 4) as i32,
            min,
            max,
        });
    }
    c.align()?;
    let b = c.elements(controllers, 24, "controllers")?;
    for (k, r) in b.chunks_exact(24).enumerate() {
        let at = c.pos - b.len() + 24 * k;
        let (start, end) = (f32_at(r, 12), f32_at(r, 16));
        finite(c, at, &[start, end], "controller range")?;
        g.controllers.push(BoneController {
            index: u32_at(r, 0) as i32,
            joint: string(c, strs, at, u32_at(r, 4), false, "controller joint string")?,
            channel: u32_at(r, 8),
            start,
            end,
            rest: u32_at(r, 20) as i32,
        });
    }
    c.align()?;
    let group_records = c.elements(groups, 12, "body groups")?;
    let group_base = c.pos - group_records.len();
    c.align()?;
    let b = c.elements(entries, 4, "body group entries")?;
    let entry_base = c.pos - b.len();
    let mut meshes = Vec::with_capacity(b.len() / 4);
    for (k, r) in b.chunks_exact(4).enumerate() {
        meshes.push(string(
            c,
            strs,
            entry_base + 4 * k,
            u32_at(r, 0),
            true,
            "body group mesh string",
        )?);
    }
    for (k, r) in group_records.chunks_exact(12).enumerate() {
        let at = group_base + 12 * k;
        let (first, count) = (u32_at(r, 4) as usize, u32_at(r, 8) as usize);
        let list = first
            .checked_add(count)
            .and_then(|end| meshes.get(first..end))
            .ok_or_else(|| {
                c.err_at(
                    at,
                    K::Invalid(format!(
                        "body group entries {first}..+{count} outside the {} entries",
                        meshes.len()
                    )),
                )
            })?;
        g.body_groups.push(BodyGroup {
            name: string(c, strs, at, u32_at(r, 0), false, "body group name string")?,
            meshes: list.to_vec(),
        });
    }
    c.align()?;
    // With no slots the families take no bytes, so their count is not bounded by the file: a family
    // without slots is only kept up to MAX_EMPTY_SKIN_FAMILIES (the fuzzer found a count that asked
    // for 103 GB).
    if slots == 0 && families > MAX_EMPTY_SKIN_FAMILIES {
        return Err(c.err_at(
            c.pos,
            K::Invalid(format!(
                "{families} skin families without slots (at most {MAX_EMPTY_SKIN_FAMILIES})"
            )),
        ));
    }
    let table = c.elements(families.saturating_mul(slots), 4, "skin table")?;
    let table_base = c.pos - table.len();
    if slots > 0 {
        for (f, family) in table.chunks_exact(4 * slots as usize).enumerate() {
            let mut row = Vec::with_capacity(slots as usize);
            for (s, r) in family.chunks_exact(4).enumerate() {
                let at = table_base + 4 * (f * slots as usize + s);
                row.push(string(
                    c,
                    strs,
                    at,
                    u32_at(r, 0),
                    false,
                    "skin material string",
                )?);
            }
            g.skin_families.push(row);
        }
    } else {
        g.skin_families = vec![Vec::new(); families as usize];
    }
    c.align()?;
    let b = c.elements(material_flags, 8, "material flags")?;
    for (k, r) in b.chunks_exact(8).enumerate() {
        let at = c.pos - b.len() + 8 * k;
        g.material_flags.push(MaterialFlags {
            material: string(c, strs, at, u32_at(r, 0), false, "material flag string")?,
            flags: u32_at(r, 4),
        });
    }
    c.align()?;
    let clip_records = c.elements(clips, GAME_CLIP_RECORD, "clip records")?;
    let clip_base = c.pos - clip_records.len();
    c.align()?;
    let b = c.elements(events, 16, "events")?;
    let event_base = c.pos - b.len();
    let mut event_list = Vec::with_capacity(b.len() / 16);
    for (k, r) in b.chunks_exact(16).enumerate() {
        event_list.push(ClipEvent {
            frame: u32_at(r, 0) as i32,
            event: u32_at(r, 4) as i32,
            kind: u32_at(r, 8) as i32,
            options: string(
                c,
                strs,
                event_base + 16 * k,
                u32_at(r, 12),
                false,
                "event options string",
            )?,
        });
    }
    for (k, r) in clip_records.chunks_exact(GAME_CLIP_RECORD).enumerate() {
        let at = clip_base + GAME_CLIP_RECORD * k;
        let (first, count) = (u32_at(r, 12) as usize, u32_at(r, 16) as usize);
        let events = first
            .checked_add(count)
            .and_then(|end| event_list.get(first..end))
            .ok_or_else(|| {
                c.err_at(
                    at,
                    K::Invalid(format!(
                        "clip events {first}..+{count} outside the {} events",
                        event_list.len()
                    )),
                )
            })?;
        let linear_movement = vec3(&r[28..40]);
        let (start, end) = (
            [f32_at(r, 64), f32_at(r, 68)],
            [f32_at(r, 72), f32_at(r, 76)],
        );
        finite(c, at, &linear_movement, "linear movement")?;
        finite(c, at, &[start, end].concat(), "blend range")?;
        let blend = if u32_at(r, 40) & 1 != 0 {
            Some(ClipBlend {
                sequence: string(c, strs, at, u32_at(r, 44), true, "blend sequence string")?,
                index: u32_at(r, 48),
                count: u32_at(r, 52),
                types: [u32_at(r, 56), u32_at(r, 60)],
                start,
                end,
            })
        } else {
            None
        };
        g.clips.push(ClipGameData {
            clip: string(c, strs, at, u32_at(r, 0), false, "clip name string")?,
            activity: u32_at(r, 4) as i32,
            activity_weight: u32_at(r, 8) as i32,
            events: events.to_vec(),
            motion_type: u32_at(r, 20),
            motion_joint: string(c, strs, at, u32_at(r, 24), true, "motion joint string")?,
            linear_movement,
            blend,
            entry_node: u32_at(r, 80) as i32,
            exit_node: u32_at(r, 84) as i32,
            node_flags: u32_at(r, 88) as i32,
        });
    }
    c.align()?;
    let size = nodes.saturating_mul(nodes);
    g.transitions = c.elements(size, 1, "transition table")?.to_vec();
    g.transition_nodes = nodes as u32;
    Ok(g)
}
