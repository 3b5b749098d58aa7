//! The game-data part of `inspect` (attachments, hit boxes, controllers, body groups, skins, clip
//! events...): JSON with flag and activity names spelled out, and its human rendering.

use serde::Serialize;
use sinew_core::format::game::{material_flags, motion_flags, GameData};
use sinew_import::halflife::compile::ACTIVITIES;
use std::fmt::Write as _;

/// What `inspect --json` prints under `game` (`null` when the file has none).
#[derive(Debug, Serialize)]
pub struct GameReport {
    /// Eye position, model space.
    pub eye_position: Option<[f32; 3]>,
    /// Attachments.
    pub attachments: Vec<AttachmentReport>,
    /// Hit boxes.
    pub hitboxes: Vec<HitboxReport>,
    /// Bone controllers.
    pub controllers: Vec<ControllerReport>,
    /// Body groups: choices in order, the first the default; `null` for a blank choice.
    pub body_groups: Vec<BodyGroupReport>,
    /// Skin families: the material in each slot, family 0 first.
    pub skin_families: Vec<Vec<String>>,
    /// Materials with flags.
    pub material_flags: Vec<MaterialFlagsReport>,
    /// Per-clip data.
    pub clips: Vec<ClipGameReport>,
    /// Transition graph: `table[from][to]`, the node to pass through (0 = none).
    pub transitions: Vec<Vec<u8>>,
}

/// One attachment.
#[derive(Debug, Serialize)]
pub struct AttachmentReport {
    /// Name (often empty in Half-Life models).
    pub name: String,
    /// Joint.
    pub joint: String,
    /// Offset in the joint's space.
    pub offset: [f32; 3],
}

/// One hit box.
#[derive(Debug, Serialize)]
pub struct HitboxReport {
    /// Joint.
    pub joint: String,
    /// Hit group.
    pub group: i32,
    /// Minimum corner, joint space.
    pub min: [f32; 3],
    /// Maximum corner.
    pub max: [f32; 3],
}

/// One bone controller.
#[derive(Debug, Serialize)]
pub struct ControllerReport {
    /// Controller number (4 = mouth).
    pub index: i32,
    /// Joint.
    pub joint: String,
    /// Channel, as QC spells it (`YR`, `X`, ... with `|RLOOP` for wrapping rotations).
    pub channel: String,
    /// Value at input 0.
    pub start: f32,
    /// Value at input 1.
    pub end: f32,
    /// Rest value.
    pub rest: i32,
}

/// One body group.
#[derive(Debug, Serialize)]
pub struct BodyGroupReport {
    /// Name.
    pub name: String,
    /// Mesh names, `null` for a blank choice.
    pub choices: Vec<Option<String>>,
}

/// One material's flags.
#[derive(Debug, Serialize)]
pub struct MaterialFlagsReport {
    /// Material.
    pub material: String,
    /// Flag names (`chrome`, `additive`, `masked`, ...).
    pub flags: Vec<String>,
    /// The flags as stored.
    pub value: u32,
}

/// One clip's game data.
#[derive(Debug, Serialize)]
pub struct ClipGameReport {
    /// Clip name.
    pub clip: String,
    /// Activity number.
    pub activity: i32,
    /// Activity name (`ACT_WALK`), or `null` when the number is not a Half-Life activity.
    pub activity_name: Option<&'static str>,
    /// Activity weight.
    pub activity_weight: i32,
    /// Events.
    pub events: Vec<EventReport>,
    /// Motion extraction flags (`LX`, ...), empty for none.
    pub motion: String,
    /// Joint the motion was extracted from.
    pub motion_joint: Option<String>,
    /// Movement taken out of the keys over the whole clip.
    pub linear_movement: [f32; 3],
    /// Blend parameters, `null` for a clip that is not one blend of a sequence.
    pub blend: Option<BlendReport>,
    /// Transition-graph entry node.
    pub entry_node: i32,
    /// Exit node.
    pub exit_node: i32,
    /// Node flags (1 = reversible).
    pub node_flags: i32,
}

/// One event.
#[derive(Debug, Serialize)]
pub struct EventReport {
    /// Frame.
    pub frame: i32,
    /// Event number.
    pub event: i32,
    /// Event type.
    pub kind: i32,
    /// Options text.
    pub options: String,
}

/// A blend's parameters.
#[derive(Debug, Serialize)]
pub struct BlendReport {
    /// The sequence the blends came from.
    pub sequence: String,
    /// This blend.
    pub index: u32,
    /// Number of blends.
    pub count: u32,
    /// Control types (`XR`, `YR`, ...; empty = unused).
    pub types: [String; 2],
    /// Control values of the first blend.
    pub start: [f32; 2],
    /// Control values of the last blend.
    pub end: [f32; 2],
}

/// The report of a scene's game data, or `None` when there is none.
pub fn game_report(g: &GameData) -> Option<GameReport> {
    if g.is_empty() {
        return None;
    }
    let n = g.transition_nodes as usize;
    Some(GameReport {
        eye_position: g.eye_position,
        attachments: g
            .attachments
            .iter()
            .map(|a| AttachmentReport {
                name: a.name.clone(),
                joint: a.joint.clone(),
                offset: a.offset,
            })
            .collect(),
        hitboxes: g
            .hitboxes
            .iter()
            .map(|h| HitboxReport {
                joint: h.joint.clone(),
                group: h.group,
                min: h.min,
                max: h.max,
            })
            .collect(),
        controllers: g
            .controllers
            .iter()
            .map(|c| ControllerReport {
                index: c.index,
                joint: c.joint.clone(),
                channel: motion_flags::describe(c.channel),
                start: c.start,
                end: c.end,
                rest: c.rest,
            })
            .collect(),
        body_groups: g
            .body_groups
            .iter()
            .map(|b| BodyGroupReport {
                name: b.name.clone(),
                choices: b
                    .meshes
                    .iter()
                    .map(|m| (!m.is_empty()).then(|| m.clone()))
                    .collect(),
            })
            .collect(),
        skin_families: g.skin_families.clone(),
        material_flags: g
            .material_flags
            .iter()
            .map(|m| MaterialFlagsReport {
                material: m.material.clone(),
                flags: material_flags::describe(m.flags),
                value: m.flags,
            })
            .collect(),
        clips: g
            .clips
            .iter()
            .map(|c| ClipGameReport {
                clip: c.clip.clone(),
                activity: c.activity,
                activity_name: usize::try_from(c.activity)
                    .ok()
                    .filter(|&a| a > 0)
                    .and_then(|a| ACTIVITIES.get(a).copied()),
                activity_weight: c.activity_weight,
                events: c
                    .events
                    .iter()
                    .map(|e| EventReport {
                        frame: e.frame,
                        event: e.event,
                        kind: e.kind,
                        options: e.options.clone(),
                    })
                    .collect(),
                motion: motion_flags::describe(c.motion_type),
                motion_joint: (!c.motion_joint.is_empty()).then(|| c.motion_joint.clone()),
                linear_movement: c.linear_movement,
                blend: c.blend.as_ref().map(|b| BlendReport {
                    sequence: b.sequence.clone(),
                    index: b.index,
                    count: b.count,
                    types: b.types.map(motion_flags::describe),
                    start: b.start,
                    end: b.end,
                }),
                entry_node: c.entry_node,
                exit_node: c.exit_node,
                node_flags: c.node_flags,
            })
            .collect(),
        transitions: (0..n)
            .map(|i| {
                g.transitions
                    .get(i * n..(i + 1) * n)
                    .unwrap_or(&[])
                    .to_vec()
            })
            .collect(),
    })
}

fn v3(v: [f32; 3]) -> String {
    format!(
        "({}, {}, {})",
        super::num(v[0]),
        super::num(v[1]),
        super::num(v[2])
    )
}

/// The human rendering of the game data (appended to `inspect`'s report).
pub fn human(g: &GameReport) -> String {
    let mut o = String::new();
    let _ = writeln!(o, "game data:");
    if let Some(e) = g.eye_position {
        let _ = writeln!(o, "  eye position {}", v3(e));
    }
    for a in &g.attachments {
        let _ = writeln!(
            o,
            "  attachment {:?} on {} at {}",
            a.name,
            a.joint,
            v3(a.offset)
        );
    }
    for h in &g.hitboxes {
        let _ = writeln!(
            o,
            "  hit box group {} on {}: {} .. {}",
            h.group,
            h.joint,
            v3(h.min),
            v3(h.max)
        );
    }
    for c in &g.controllers {
        let _ = writeln!(
            o,
            "  controller {} on {}: {} {} .. {}",
            c.index,
            c.joint,
            c.channel,
            super::num(c.start),
            super::num(c.end)
        );
    }
    for b in &g.body_groups {
        let choices: Vec<String> = b
            .choices
            .iter()
            .map(|c| c.clone().unwrap_or_else(|| "(blank)".into()))
            .collect();
        let _ = writeln!(o, "  body group {:?}: {}", b.name, choices.join(", "));
    }
    for (i, f) in g.skin_families.iter().enumerate() {
        let _ = writeln!(o, "  skin family {i}: {}", f.join(", "));
    }
    for m in &g.material_flags {
        let _ = writeln!(o, "  material {:?}: {}", m.material, m.flags.join(", "));
    }
    for c in &g.clips {
        let mut line = format!("  clip {:?}:", c.clip);
        if let Some(a) = c.activity_name {
            let _ = write!(line, " {a} (weight {})", c.activity_weight);
        } else if c.activity != 0 {
            let _ = write!(
                line,
                " activity {} (weight {})",
                c.activity, c.activity_weight
            );
        }
        if !c.motion.is_empty() {
            let _ = write!(
                line,
                "; motion {} of {}",
                c.motion,
                c.motion_joint.as_deref().unwrap_or("?")
            );
            if c.linear_movement != [0.0; 3] {
                let _ = write!(line, " moving {}", v3(c.linear_movement));
            }
        }
        if let Some(b) = &c.blend {
            let _ = write!(
                line,
                "; blend {} of {} of {:?} ({} {} .. {})",
                b.index,
                b.count,
                b.sequence,
                b.types[0],
                super::num(b.start[0]),
                super::num(b.end[0])
            );
        }
        if c.entry_node != 0 || c.exit_node != 0 {
            let _ = write!(line, "; nodes {} -> {}", c.entry_node, c.exit_node);
        }
        for e in &c.events {
            let _ = write!(
                line,
                "; event {} at frame {} {:?}",
                e.event, e.frame, e.options
            );
        }
        let _ = writeln!(o, "{line}");
    }
    if !g.transitions.is_empty() {
        let _ = writeln!(o, "  transitions ({} nodes):", g.transitions.len());
        for row in &g.transitions {
            let r: Vec<String> = row.iter().map(u8::to_string).collect();
            let _ = writeln!(o, "    {}", r.join(" "));
        }
    }
    o
}
