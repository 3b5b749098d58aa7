//! A studio model to a sinew scene: skeleton, every body-part choice (submodel) as a mesh of its own,
//! the body groups that say which meshes make a body, one material per texture (with its image), one
//! clip per sequence and blend, and everything else as game data. docs/formats/halflife.md describes
//! each rule.

use super::model::{StudioModel, StudioSequence, StudioTexture, Submodel};
use crate::ImportError;
use sinew_core::format::game::{
    material_flags, Attachment, BodyGroup, BoneController, ClipBlend, ClipEvent, ClipGameData,
    GameData, Hitbox, MaterialFlags,
};
use sinew_core::glam::{EulerRot, Quat, Vec2, Vec3};
use sinew_core::{Curve, JointDesc, Lod, Skeleton, Submesh, TrackCurves, Transform};
use sinew_scene::{Diagnostic, Image, Material, Mesh, Scene, SceneClip, SourceFormat};
use std::collections::{HashMap, HashSet};

/// The rotation of studio Euler angles (x, y, z), as the Half-Life SDK's `AngleQuaternion` builds it:
/// `Rz * Ry * Rx` acting on column vectors.
pub fn euler_to_quat(angles: [f32; 3]) -> Quat {
    Quat::from_euler(EulerRot::ZYX, angles[2], angles[1], angles[0])
}

/// A bone's local transform from its six values.
pub fn bone_transform(v: [f32; 6]) -> Transform {
    Transform {
        translation: Vec3::new(v[0], v[1], v[2]),
        rotation: euler_to_quat([v[3], v[4], v[5]]),
        scale: Vec3::ONE,
    }
}

/// Unique, non-empty names: an empty name becomes `<fallback><i>`, a repeated one gets `#<n>`.
fn unique_names(
    names: impl Iterator<Item = String>,
    fallback: &str,
    what: &str,
    diagnostics: &mut Vec<Diagnostic>,
) -> Vec<String> {
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for (i, name) in names.enumerate() {
        let mut n = if name.is_empty() {
            diagnostics.push(Diagnostic::warning(
                "halflife-empty-name",
                format!("{what} {i} has no name; named {fallback}{i}"),
            ));
            format!("{fallback}{i}")
        } else {
            name.clone()
        };
        if seen.contains(&n) {
            let mut k = 2;
            while seen.contains(&format!("{n}#{k}")) {
                k += 1;
            }
            let renamed = format!("{n}#{k}");
            diagnostics.push(Diagnostic::warning(
                "halflife-duplicate-name",
                format!("{what} {i} repeats the name {n:?}; renamed {renamed:?}"),
            ));
            n = renamed;
        }
        seen.insert(n.clone());
        out.push(n);
    }
    out
}

/// The RGBA pixels of an indexed texture; with the masked flag, palette index 255 is transparent.
pub fn texture_rgba(t: &StudioTexture) -> Option<Vec<u8>> {
    let n = (t.width as usize).checked_mul(t.height as usize)?;
    if t.indices.len() != n || t.palette.len() != 768 {
        return None;
    }
    let masked = t.flags & material_flags::MASKED != 0;
    let mut out = Vec::with_capacity(n * 4);
    for &i in &t.indices {
        let p = 3 * i as usize;
        out.extend_from_slice(&t.palette[p..p + 3]);
        out.push(if masked && i == 255 { 0 } else { 255 });
    }
    Some(out)
}

/// The last path component of a submodel or texture name as written (`../refs/triangle` -> `triangle`).
fn base_name(name: &str) -> &str {
    name.rsplit(['/', '\\']).next().unwrap_or(name)
}

/// Builds the scene. `model_name` names the mesh of a model that has a single submodel.
pub fn build_scene(
    file: &str,
    model_name: &str,
    model: &StudioModel,
    format: SourceFormat,
    mut diagnostics: Vec<Diagnostic>,
) -> Result<Scene, ImportError> {
    let mut scene = Scene::new(format);
    let joint_names = unique_names(
        model.bones.iter().map(|b| b.name.clone()),
        "bone",
        "bone",
        &mut diagnostics,
    );
    if !model.bones.is_empty() {
        let joints = model
            .bones
            .iter()
            .zip(&joint_names)
            .map(|(b, name)| JointDesc {
                name: name.clone(),
                parent: b.parent.map(|p| joint_names[p].clone()),
                bind_local: bone_transform(b.value),
                inverse_bind: None,
            })
            .collect();
        let (skeleton, _) = Skeleton::from_unordered(joints)
            .map_err(|e| ImportError::in_section(file, "bones", e.to_string()))?;
        scene.skeleton = Some(skeleton);
    }
    // Joint index in the skeleton of each bone (from_unordered may reorder; bones are parents-first,
    // so it keeps the order, but look up by name to be safe).
    let joint_of: Vec<u16> = joint_names
        .iter()
        .map(|n| scene.skeleton.as_ref().and_then(|s| s.find(n)).unwrap_or(0))
        .collect();

    // Materials: one per texture, named by the texture; slots without a texture get `slot<i>`.
    let texture_names = unique_names(
        model
            .textures
            .iter()
            .map(|t| base_name(&t.name).to_string()),
        "texture",
        "texture",
        &mut diagnostics,
    );
    for (t, name) in model.textures.iter().zip(&texture_names) {
        scene.materials.push(Material {
            name: name.clone(),
            base_color: [1.0; 4],
            texture: Some(name.clone()),
        });
        match texture_rgba(t) {
            Some(rgba) => scene.images.push(Image {
                name: name.clone(),
                width: t.width,
                height: t.height,
                rgba,
            }),
            None if !t.indices.is_empty() => diagnostics.push(Diagnostic::warning(
                "halflife-bad-texture",
                format!(
                    "texture {name:?}: pixel or palette size does not match {}x{}",
                    t.width, t.height
                ),
            )),
            None => {}
        }
    }
    let slot_material = |slot: usize| -> String {
        model
            .skin_families
            .first()
            .and_then(|row| row.get(slot))
            .and_then(|&t| texture_names.get(t))
            .cloned()
            .unwrap_or_else(|| format!("slot{slot}"))
    };
    let mut used: Vec<String> = Vec::new();

    // Meshes: every non-blank submodel in body-part order, each its own mesh named `part/submodel`
    // (the body groups say which make a body; a model with a single submodel names it after the file).
    let part_names = unique_names(
        model.body_parts.iter().map(|p| p.name.clone()),
        "bodypart",
        "body part",
        &mut diagnostics,
    );
    let mut subs: Vec<(String, &Submodel)> = Vec::new();
    let mut groups = Vec::new();
    for (part, pname) in model.body_parts.iter().zip(&part_names) {
        let mut entries = Vec::new();
        let sub_names = unique_names(
            part.submodels
                .iter()
                .map(|s| base_name(&s.name).to_string()),
            "submodel",
            "submodel",
            &mut diagnostics,
        );
        for (sub, sname) in part.submodels.iter().zip(&sub_names) {
            let full = format!("{pname}/{sname}");
            if sub.vertices.is_empty() {
                entries.push(String::new());
                continue;
            }
            entries.push(full.clone());
            subs.push((full, sub));
        }
        groups.push(BodyGroup {
            name: pname.clone(),
            meshes: entries,
        });
    }
    let skinned = scene.skeleton.is_some();
    let single = subs.len() == 1;
    for (name, sub) in subs {
        let name = if single { model_name } else { name.as_str() };
        let mesh = build_mesh(name, &[sub], &joint_of, skinned, &slot_material, &mut used);
        scene.meshes.push(mesh);
    }
    // Slots with no texture still need a material.
    for m in used {
        if !scene.materials.iter().any(|x| x.name == m) {
            scene.materials.push(Material {
                name: m,
                base_color: [1.0; 4],
                texture: None,
            });
        }
    }

    // Clips, and the game data of each.
    let mut game = GameData::default();
    let seq_names = unique_names(
        model.sequences.iter().map(|s| s.label.clone()),
        "sequence",
        "sequence",
        &mut diagnostics,
    );
    for (seq, label) in model.sequences.iter().zip(&seq_names) {
        if seq.blends.is_empty() {
            diagnostics.push(Diagnostic::warning(
                "halflife-sequence-without-data",
                format!("sequence {label:?} has no animation data (a file it needs is missing, see above); left out"),
            ));
            continue;
        }
        let count = seq.blends.len();
        for (k, frames) in seq.blends.iter().enumerate() {
            let name = if count == 1 {
                label.clone()
            } else {
                format!("{label}.blend{k}")
            };
            scene
                .clips
                .push(build_clip(&name, seq, frames, &joint_names));
            game.clips.push(ClipGameData {
                clip: name,
                activity: seq.activity.0,
                activity_weight: seq.activity.1,
                events: seq
                    .events
                    .iter()
                    .map(|(frame, event, kind, options)| ClipEvent {
                        frame: *frame,
                        event: *event,
                        kind: *kind,
                        options: options.clone(),
                    })
                    .collect(),
                motion_type: seq.motion_type,
                motion_joint: if seq.motion_type != 0 {
                    joint_names
                        .get(seq.motion_bone)
                        .cloned()
                        .unwrap_or_default()
                } else {
                    String::new()
                },
                linear_movement: seq.linear_movement,
                blend: (count > 1).then(|| ClipBlend {
                    sequence: label.clone(),
                    index: k as u32,
                    count: count as u32,
                    types: seq.blend_type,
                    start: seq.blend_start,
                    end: seq.blend_end,
                }),
                entry_node: seq.nodes.0,
                exit_node: seq.nodes.1,
                node_flags: seq.nodes.2,
            });
        }
    }

    let joint = |b: usize| joint_names.get(b).cloned().unwrap_or_default();
    game.eye_position = model.eye_position.filter(|e| e.iter().any(|&v| v != 0.0));
    game.attachments = model
        .attachments
        .iter()
        .map(|(name, bone, offset)| Attachment {
            name: name.clone(),
            joint: joint(*bone),
            offset: *offset,
        })
        .collect();
    game.hitboxes = model
        .hitboxes
        .iter()
        .map(|&(bone, group, min, max)| Hitbox {
            joint: joint(bone),
            group,
            min,
            max,
        })
        .collect();
    game.controllers = model
        .controllers
        .iter()
        .map(|c| BoneController {
            index: c.index,
            joint: joint(c.bone),
            channel: c.channel,
            start: c.start,
            end: c.end,
            rest: c.rest,
        })
        .collect();
    if model.body_parts.len() > 1 || model.body_parts.iter().any(|p| p.submodels.len() > 1) {
        game.body_groups = groups;
    }
    if model.skin_families.len() > 1 {
        game.skin_families = model
            .skin_families
            .iter()
            .map(|row| {
                row.iter()
                    .map(|&t| texture_names.get(t).cloned().unwrap_or_default())
                    .collect()
            })
            .collect();
    }
    game.material_flags = model
        .textures
        .iter()
        .zip(&texture_names)
        .filter(|(t, _)| t.flags != 0)
        .map(|(t, name)| MaterialFlags {
            material: name.clone(),
            flags: t.flags,
        })
        .collect();
    game.transitions = model.transitions.clone();
    game.transition_nodes = model.transition_nodes;
    scene.game = game;
    scene.diagnostics = diagnostics;
    Ok(scene)
}

/// Key of a vertex of the output mesh: studio vertex (with its submodel), normal and uv, by bits.
type VertexKey = (usize, usize, [u32; 3], [u32; 2]);

fn build_mesh(
    name: &str,
    parts: &[&Submodel],
    joint_of: &[u16],
    skinned: bool,
    slot_material: &dyn Fn(usize) -> String,
    used: &mut Vec<String>,
) -> Mesh {
    let mut lod = Lod::default();
    let mut source_vertex = Vec::new();
    let mut index_of: HashMap<VertexKey, u32> = HashMap::new();
    let mut base = 0usize;
    for (p, sub) in parts.iter().enumerate() {
        for mesh in &sub.meshes {
            let material = slot_material(mesh.skin_slot);
            if !used.contains(&material) {
                used.push(material.clone());
            }
            let first = lod.indices.len() as u32;
            for tri in &mesh.triangles {
                for c in tri {
                    let Some(v) = sub.vertices.get(c.vertex) else {
                        continue;
                    };
                    let key = (
                        p,
                        c.vertex,
                        c.normal.map(f32::to_bits),
                        c.uv.map(f32::to_bits),
                    );
                    let next = lod.positions.len() as u32;
                    let i = *index_of.entry(key).or_insert_with(|| {
                        lod.positions.push(Vec3::from_array(v.position));
                        let n = Vec3::from_array(c.normal);
                        lod.normals.push(n.try_normalize().unwrap_or(Vec3::Z));
                        lod.uvs.push(Vec2::from_array(c.uv));
                        if skinned {
                            let mut j = [0u16; 4];
                            let mut w = [0f32; 4];
                            for (k, &(bone, weight)) in v.influences.iter().take(4).enumerate() {
                                j[k] = joint_of.get(bone).copied().unwrap_or(0);
                                w[k] = weight;
                            }
                            if v.influences.is_empty() {
                                w[0] = 1.0;
                            }
                            lod.joints.push(j);
                            lod.weights.push(w);
                        }
                        source_vertex.push((base + c.vertex) as u32);
                        next
                    });
                    lod.indices.push(i);
                }
            }
            let count = lod.indices.len() as u32 - first;
            if count > 0 {
                lod.submeshes.push(Submesh {
                    first_index: first,
                    index_count: count,
                    material,
                });
            }
        }
        base += sub.vertices.len();
    }
    Mesh {
        name: name.to_string(),
        geometry: lod,
        source_vertex,
        source_vertex_count: base as u32,
        lods: Vec::new(),
        lods_not_built: Vec::new(),
    }
}

fn build_clip(
    name: &str,
    seq: &StudioSequence,
    frames: &[Vec<[f32; 6]>],
    joint_names: &[String],
) -> SceneClip {
    let fps = if seq.fps.is_finite() && seq.fps > 0.0 {
        seq.fps
    } else {
        30.0
    };
    let times: Vec<f32> = (0..frames.len()).map(|k| k as f32 / fps).collect();
    let tracks = joint_names
        .iter()
        .enumerate()
        .map(|(b, joint)| {
            let values = |f: &dyn Fn(&[f32; 6]) -> Vec3| -> Vec<Vec3> {
                frames
                    .iter()
                    .map(|fr| fr.get(b).map_or(Vec3::ZERO, f))
                    .collect()
            };
            TrackCurves {
                joint: joint.clone(),
                translation: Curve::new(times.clone(), values(&|v| Vec3::new(v[0], v[1], v[2]))),
                rotation: Curve::new(
                    times.clone(),
                    frames
                        .iter()
                        .map(|fr| {
                            fr.get(b)
                                .map_or(Quat::IDENTITY, |v| euler_to_quat([v[3], v[4], v[5]]))
                        })
                        .collect(),
                ),
                scale: Curve::default(),
            }
        })
        .collect();
    SceneClip {
        name: name.to_string(),
        duration: times.last().copied().unwrap_or(0.0),
        sample_rate: fps,
        looping: seq.looping,
        additive: false,
        tracks,
    }
}
