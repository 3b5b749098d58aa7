//! studiomdl's `SimplifyModel` and what follows: the bone union, relinking, motion extraction,
//! quantisation, hit boxes, transitions and skins, into a studio model.

use super::state::{State, UnionBone, MAX_BONES};
use crate::halflife::model::{
    BodyPart, Corner, StudioBone, StudioController, StudioMesh, StudioModel, StudioSequence,
    StudioTexture, StudioVertex, Submodel,
};
use crate::halflife::qc::Script;
use crate::halflife::scene::euler_to_quat;
use crate::ImportError;
use sinew_core::format::game::{material_flags, motion_flags};
use sinew_core::glam::{Mat3, Vec3};
use sinew_scene::Diagnostic;
use std::f64::consts::PI;

/// studiomdl's `SimplifyModel` and what follows: the bone union, relinking, motion extraction,
/// quantisation, hit boxes, transitions, skins; then the studio model.
pub(super) fn build(
    mut s: State,
    script: &Script,
) -> Result<(StudioModel, Vec<Diagnostic>), ImportError> {
    let qc = s.qc.to_string();
    let err = |section: &str, msg: String| ImportError::in_section(&qc, section, msg);

    // OptimizeAnimations: looping sequences end where they start; ExtractMotion.
    for seq in &mut s.sequences {
        let n = seq.anims.first().map_or(0, |a| a.frames.len());
        if n == 0 {
            continue;
        }
        if seq.looping {
            for a in &mut seq.anims {
                let first = a.frames[0].clone();
                if let Some(last) = a.frames.last_mut() {
                    for (k, (p, r)) in last.iter_mut().enumerate() {
                        for (c, flag) in [motion_flags::LX, motion_flags::LY, motion_flags::LZ]
                            .into_iter()
                            .enumerate()
                        {
                            if seq.motion & flag == 0 {
                                p[c] = first[k].0[c];
                            }
                        }
                        *r = first[k].1;
                    }
                }
            }
        }
    }
    let mut linear: Vec<[f32; 3]> = Vec::with_capacity(s.sequences.len());
    for seq in &mut s.sequences {
        let n = seq.anims.first().map_or(0, |a| a.frames.len());
        let mut motion = [0f32; 3];
        if n > 1 {
            let a0 = &seq.anims[0];
            let (p0, pk) = (a0.frames[0][0].0, a0.frames[n - 1][0].0);
            for (c, flag) in [motion_flags::LX, motion_flags::LY, motion_flags::LZ]
                .into_iter()
                .enumerate()
            {
                if seq.motion & flag != 0 {
                    motion[c] = pk[c] - p0[c];
                }
            }
            let roots: Vec<usize> = a0
                .nodes
                .iter()
                .enumerate()
                .filter(|(_, nd)| nd.parent.is_none())
                .map(|(k, _)| k)
                .collect();
            for a in &mut seq.anims {
                for (j, frame) in a.frames.iter_mut().enumerate() {
                    let f = (j as f64 / (n - 1) as f64) as f32;
                    for &k in &roots {
                        if let Some((p, _)) = frame.get_mut(k) {
                            for c in 0..3 {
                                p[c] -= motion[c] * f;
                            }
                        }
                    }
                }
            }
        }
        linear.push(motion);
        // Unused rotation motion of root bones is held at frame 0.
        let roots: Vec<usize> = seq
            .anims
            .first()
            .map(|a| {
                a.nodes
                    .iter()
                    .enumerate()
                    .filter(|(_, nd)| nd.parent.is_none())
                    .map(|(k, _)| k)
                    .collect()
            })
            .unwrap_or_default();
        for a in &mut seq.anims {
            let Some(first) = a.frames.first().cloned() else {
                continue;
            };
            for frame in &mut a.frames {
                for &k in &roots {
                    for (c, flag) in [motion_flags::XR, motion_flags::YR, motion_flags::ZR]
                        .into_iter()
                        .enumerate()
                    {
                        if seq.motion & flag != 0 {
                            if let (Some(f), Some(f0)) = (frame.get_mut(k), first.get(k)) {
                                f.1[c] = f0.1[c];
                            }
                        }
                    }
                }
            }
        }
    }

    // Transitions (MakeTransitions).
    let nodes = s
        .sequences
        .iter()
        .map(|q| q.nodes.0.max(0) as usize)
        .max()
        .unwrap_or(0)
        .min(255);
    let mut xnode = vec![vec![0i32; nodes]; nodes];
    for q in &s.sequences {
        let (a, b) = (q.nodes.0, q.nodes.1);
        if a != b && a >= 1 && b >= 1 && (a as usize) <= nodes && (b as usize) <= nodes {
            xnode[a as usize - 1][b as usize - 1] = b;
            if q.nodes.2 != 0 {
                xnode[b as usize - 1][a as usize - 1] = a;
            }
        }
    }
    loop {
        let mut hit = false;
        for i in 0..nodes {
            for j in 0..nodes {
                if i != j && xnode[i][j] == 0 {
                    for k in 0..nodes.saturating_sub(1) {
                        if xnode[k][j] > 0 && xnode[i][k] > 0 {
                            xnode[i][j] = -xnode[i][k];
                            hit = true;
                            break;
                        }
                    }
                }
            }
        }
        for row in &mut xnode {
            for v in row.iter_mut() {
                *v = v.abs();
            }
        }
        if !hit {
            break;
        }
    }

    // Bones used by vertices, with their ancestors, renamed, then their union in first-use order.
    for m in &mut s.models {
        for n in &mut m.nodes {
            if let Some((_, to)) = s.renames.iter().find(|(f, _)| *f == n.name) {
                n.name = to.clone();
            }
        }
    }
    let mut bones: Vec<UnionBone> = Vec::new();
    for m in &mut s.models {
        let mut used = vec![false; m.nodes.len()];
        for (_, b) in &m.verts {
            if let Some(u) = used.get_mut(*b) {
                *u = true;
            }
        }
        for k in 0..used.len() {
            if used[k] {
                let mut p = m.nodes[k].parent;
                let mut guard = 0;
                while let Some(q) = p {
                    if used[q] || guard > used.len() {
                        break;
                    }
                    used[q] = true;
                    p = m.nodes[q].parent;
                    guard += 1;
                }
            }
        }
        m.bonemap = vec![None; m.nodes.len()];
        for (j, &is_used) in used.iter().enumerate() {
            if !is_used {
                continue;
            }
            let name = &m.nodes[j].name;
            let parent = m.nodes[j].parent.and_then(|p| {
                let pn = &m.nodes[p].name;
                bones.iter().position(|b| b.0 == *pn)
            });
            let k = match bones.iter().position(|b| b.0 == *name) {
                Some(k) => {
                    if bones[k].1 != parent {
                        return Err(err(
                            "bones",
                            format!(
                                "bone {name:?} has a different parent in {} than in an earlier model",
                                m.name
                            ),
                        ));
                    }
                    k
                }
                None => {
                    bones.push((name.clone(), parent, m.skeleton[j].0, m.skeleton[j].1));
                    bones.len() - 1
                }
            };
            m.bonemap[j] = Some(k);
        }
    }
    if bones.len() >= MAX_BONES {
        return Err(err(
            "bones",
            format!(
                "{} bones used; GoldSrc models hold at most {}",
                bones.len(),
                MAX_BONES - 1
            ),
        ));
    }
    let find = |name: &str| bones.iter().position(|b| b.0.eq_ignore_ascii_case(name));

    // Bind-pose bone-to-model transforms of the union, for vertices and normals.
    let mut world: Vec<(Mat3, Vec3)> = Vec::with_capacity(bones.len());
    for b in &bones {
        let m = Mat3::from_quat(euler_to_quat(b.3));
        let entry = match b.1.and_then(|p| world.get(p).copied()) {
            Some((pm, porg)) => (pm * m, pm * Vec3::from_array(b.2) + porg),
            None => (m, Vec3::from_array(b.2)),
        };
        world.push(entry);
    }

    // Sequences relinked to the union; bones an animation lacks hold their default.
    let mut sequences = Vec::with_capacity(s.sequences.len());
    for (seq, lin) in s.sequences.iter().zip(&linear) {
        let mut blends = Vec::with_capacity(seq.anims.len());
        for a in &seq.anims {
            let map: Vec<Option<usize>> = bones
                .iter()
                .map(|b| {
                    let mut names = a.nodes.iter().map(|n| {
                        s.renames
                            .iter()
                            .find(|(f, _)| *f == n.name)
                            .map_or(n.name.as_str(), |(_, t)| t.as_str())
                    });
                    names.position(|n| n == b.0)
                })
                .collect();
            let frames: Vec<Vec<[f32; 6]>> = a
                .frames
                .iter()
                .map(|f| {
                    bones
                        .iter()
                        .enumerate()
                        .map(|(j, b)| match map[j].and_then(|k| f.get(k)) {
                            Some((p, r)) => [p[0], p[1], p[2], r[0], r[1], r[2]],
                            None => [b.2[0], b.2[1], b.2[2], b.3[0], b.3[1], b.3[2]],
                        })
                        .collect()
                })
                .collect();
            blends.push(frames);
        }
        let n = blends.first().map_or(0, Vec::len) as i32;
        sequences.push(StudioSequence {
            label: seq.label.clone(),
            fps: seq.fps,
            looping: seq.looping,
            activity: (seq.activity, seq.weight),
            events: seq
                .events
                .iter()
                .map(|(f, e, k, o)| ((*f).clamp(0, (n - 1).max(0)), *e, *k, o.clone()))
                .collect(),
            motion_type: seq.motion,
            motion_bone: 0,
            linear_movement: *lin,
            blend_type: [
                if seq.blend.0 == u32::MAX {
                    0
                } else {
                    seq.blend.0
                },
                0,
            ],
            blend_start: [seq.blend.1, 0.0],
            blend_end: [seq.blend.2, 0.0],
            nodes: seq.nodes,
            blends,
        });
    }
    quantise(&bones, &mut sequences);

    // Submodels: vertices and normals back from bone space with the union's bind pose.
    let mut body_parts: Vec<BodyPart> = s
        .parts
        .iter()
        .map(|(name, _)| BodyPart {
            name: name.clone(),
            submodels: Vec::new(),
        })
        .collect();
    for (p, (_, choices)) in s.parts.iter().enumerate() {
        for choice in choices {
            let sub = match choice.and_then(|m| s.models.get(m)) {
                None => Submodel {
                    name: "blank".into(),
                    vertices: Vec::new(),
                    meshes: Vec::new(),
                },
                Some(m) => {
                    let bone = |b: usize| m.bonemap.get(b).copied().flatten().unwrap_or(0);
                    let vertices = m
                        .verts
                        .iter()
                        .map(|(local, b)| {
                            let (rot, org) = world[bone(*b)];
                            StudioVertex {
                                position: (rot * Vec3::from_array(*local) + org).to_array(),
                                influences: vec![(bone(*b), 1.0)],
                            }
                        })
                        .collect();
                    let meshes = m
                        .meshes
                        .iter()
                        .map(|(slot, tris)| {
                            // studiomdl stores no coordinates for chrome textures (the renderer
                            // makes them from the view), so neither does the compile.
                            let chrome = s
                                .textures
                                .get(*slot)
                                .is_some_and(|t| t.flags & material_flags::CHROME != 0);
                            StudioMesh {
                                skin_slot: *slot,
                                triangles: tris
                                    .iter()
                                    .map(|t| {
                                        // Back to counter-clockwise (the MDL reader does the same).
                                        [t[2], t[1], t[0]].map(|(v, n, uv)| {
                                            let (nrm, b, _) = m.normals[n];
                                            Corner {
                                                vertex: v,
                                                normal: (world[bone(b)].0 * Vec3::from_array(nrm))
                                                    .to_array(),
                                                uv: if chrome {
                                                    [0.0, 0.0]
                                                } else {
                                                    [uv[0], 1.0 - uv[1]]
                                                },
                                            }
                                        })
                                    })
                                    .collect(),
                            }
                        })
                        .collect();
                    Submodel {
                        name: m.name.clone(),
                        vertices,
                        meshes,
                    }
                }
            };
            body_parts[p].submodels.push(sub);
        }
    }

    // Hit boxes: as given, or one per bone that vertices span (with its children's origins).
    let mut hitboxes = Vec::new();
    if s.hitboxes.is_empty() {
        let mut group = vec![i32::MIN; bones.len()];
        for (g, name) in &s.hitgroups {
            match find(name) {
                Some(k) => group[k] = *g,
                None => {
                    return Err(err(
                        "$hgroup",
                        format!("no bone {name:?} for hit group {g}"),
                    ));
                }
            }
        }
        for k in 0..bones.len() {
            if group[k] == i32::MIN {
                group[k] = bones[k].1.map_or(0, |p| group[p]);
            }
        }
        let mut bmin = vec![[0f32; 3]; bones.len()];
        let mut bmax = vec![[0f32; 3]; bones.len()];
        for m in &s.models {
            for (p, b) in &m.verts {
                let Some(k) = m.bonemap.get(*b).copied().flatten() else {
                    continue;
                };
                for c in 0..3 {
                    bmin[k][c] = bmin[k][c].min(p[c]);
                    bmax[k][c] = bmax[k][c].max(p[c]);
                }
            }
        }
        for bone in &bones {
            if let Some(j) = bone.1 {
                for c in 0..3 {
                    bmin[j][c] = bmin[j][c].min(bone.2[c]);
                    bmax[j][c] = bmax[j][c].max(bone.2[c]);
                }
            }
        }
        for k in 0..bones.len() {
            if (0..3).all(|c| bmin[k][c] < bmax[k][c] - 1.0) {
                hitboxes.push((k, group[k], bmin[k], bmax[k]));
            }
        }
    } else {
        for (g, name, min, max, t) in &s.hitboxes {
            let Some(k) = find(name) else {
                return Err(script.error_at(t, "$hbox", format!("no bone {name:?} in the model")));
            };
            hitboxes.push((k, *g, *min, *max));
        }
    }
    let mut controllers = Vec::new();
    for (index, name, channel, start, end, t) in &s.controllers {
        let Some(k) = find(name) else {
            return Err(script.error_at(
                t,
                "$controller",
                format!("no bone {name:?} in the model"),
            ));
        };
        controllers.push(StudioController {
            bone: k,
            channel: *channel,
            start: *start,
            end: *end,
            rest: 0,
            index: *index,
        });
    }
    let mut attachments = Vec::new();
    for (name, org, t) in &s.attachments {
        let Some(k) = find(name) else {
            return Err(script.error_at(
                t,
                "$attachment",
                format!("no bone {name:?} in the model"),
            ));
        };
        attachments.push((String::new(), k, *org));
    }

    // Skins: studiomdl's texture groups over the textures in first-use order.
    let skinrefs = if s.skinref_count == 0 {
        s.textures.len()
    } else {
        s.skinref_count
    };
    let mut skin_families = vec![(0..skinrefs).collect::<Vec<usize>>()];
    if let Some(groups) = s.texture_groups.first() {
        if let Some(base) = groups.first() {
            skin_families = groups
                .iter()
                .map(|row| {
                    let mut fam: Vec<usize> = (0..skinrefs).collect();
                    for (j, &b) in base.iter().enumerate() {
                        if let (Some(slot), Some(&t)) = (fam.get_mut(b), row.get(j)) {
                            *slot = t;
                        }
                    }
                    fam
                })
                .collect();
        }
    }
    let textures = s
        .textures
        .iter()
        .map(|t| StudioTexture {
            name: t.name.clone(),
            flags: t.flags,
            width: 0,
            height: 0,
            indices: Vec::new(),
            palette: Vec::new(),
        })
        .collect();

    let model = StudioModel {
        bones: bones
            .iter()
            .map(|b| StudioBone {
                name: b.0.clone(),
                parent: b.1,
                value: [b.2[0], b.2[1], b.2[2], b.3[0], b.3[1], b.3[2]],
            })
            .collect(),
        body_parts,
        textures,
        skin_families,
        sequences,
        controllers,
        hitboxes,
        attachments,
        eye_position: Some(s.eye),
        transitions: xnode
            .iter()
            .flatten()
            .map(|&v| v.clamp(0, 255) as u8)
            .collect(),
        transition_nodes: nodes as u32,
    };
    Ok((model, s.diagnostics))
}

/// studiomdl's 16-bit animation values: per bone and channel a scale from the largest difference
/// from the default over every frame of every sequence, each value truncated to a multiple of it.
pub(super) fn quantise(bones: &[UnionBone], sequences: &mut [StudioSequence]) {
    for (j, b) in bones.iter().enumerate() {
        let default = [b.2[0], b.2[1], b.2[2], b.3[0], b.3[1], b.3[2]];
        for k in 0..6 {
            let diff = |v: f32| -> f32 {
                let d = v - default[k];
                if k < 3 {
                    d
                } else if f64::from(d) >= PI {
                    (f64::from(d) - PI * 2.0) as f32
                } else if f64::from(d) < -PI {
                    (f64::from(d) + PI * 2.0) as f32
                } else {
                    d
                }
            };
            let (mut minv, mut maxv) = if k < 3 {
                (-128.0f32, 128.0f32)
            } else {
                ((-PI / 8.0) as f32, (PI / 8.0) as f32)
            };
            for seq in sequences.iter() {
                for frame in seq.blends.iter().flatten() {
                    if let Some(v) = frame.get(j) {
                        let d = diff(v[k]);
                        minv = minv.min(d);
                        maxv = maxv.max(d);
                    }
                }
            }
            let scale = if minv < maxv {
                if -minv > maxv {
                    (f64::from(minv) / -32768.0) as f32
                } else {
                    maxv / 32767.0
                }
            } else {
                1.0 / 32.0
            };
            for seq in sequences.iter_mut() {
                for frame in seq.blends.iter_mut().flatten() {
                    if let Some(v) = frame.get_mut(j) {
                        let raw = (diff(v[k]) / scale) as i16;
                        v[k] = default[k] + f32::from(raw) * scale;
                    }
                }
            }
        }
    }
}
