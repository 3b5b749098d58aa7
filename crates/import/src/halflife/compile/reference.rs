//! Reference SMDs into bone-space vertices and merged normals (`Grab_Triangles`), and animation
//! SMDs into frames with the root turn (`Grab_Animation`).

use super::math::{
    add, angle_imatrix, angle_matrix, clip_rotation, concat, normalize, sub, transform,
    two_decimals, Fixup,
};
use super::state::{lookup_texture, mirror_flags, Anim, RefModel, State};
use crate::halflife::smd::Smd;
use sinew_core::glam::Vec3;
use std::f64::consts::PI;

pub(super) fn reference_model(
    s: &mut State,
    name: &str,
    smd: &Smd,
    flip: bool,
    scale: f32,
) -> RefModel {
    let mirrored: Vec<bool> = mirror_flags(&smd.nodes, &s.mirrored);
    // The skeleton block: every line overwrites its bone, so the last frame wins.
    let mut skeleton = vec![([0f32; 3], [0f32; 3]); smd.nodes.len()];
    if let Some((_, last)) = smd.frames.last() {
        for (k, v) in last.iter().enumerate() {
            let mut p = [v[0] * scale, v[1] * scale, v[2] * scale];
            if mirrored[k] {
                p = p.map(|x| -x);
            }
            skeleton[k] = (
                p,
                [
                    clip_rotation(v[3]),
                    clip_rotation(v[4]),
                    clip_rotation(v[5]),
                ],
            );
        }
    }
    // Bone-to-world of the reference pose (studiomdl's `bonefixup`), in studiomdl's own arithmetic:
    // vertices are truncated to two decimals in bone space, so a last-bit difference can move one
    // by 0.01.
    let mut fixup: Vec<Fixup> = Vec::with_capacity(skeleton.len());
    for (k, node) in smd.nodes.iter().enumerate() {
        let (p, r) = skeleton[k];
        let (m, im) = (angle_matrix(r), angle_imatrix(r));
        let entry = match node.parent.and_then(|q| fixup.get(q)) {
            Some(parent) => Fixup {
                m: concat(&parent.m, &m),
                im: concat(&im, &parent.im),
                org: add(transform(p, &parent.m), parent.org),
            },
            None => Fixup { m, im, org: p },
        };
        fixup.push(entry);
    }
    let adjust = s.default_adjust;
    let mut model = RefModel {
        name: name.to_string(),
        nodes: smd.nodes.clone(),
        skeleton,
        verts: Vec::new(),
        normals: Vec::new(),
        meshes: Vec::new(),
        bonemap: Vec::new(),
    };
    let normal_blend = (2.0f64 * (PI / 180.0)).cos() as f32;
    for tri in &smd.triangles {
        let slot = lookup_texture(s, &tri.material);
        let mesh = match model.meshes.iter().position(|m| m.0 == slot) {
            Some(m) => m,
            None => {
                model.meshes.push((slot, Vec::new()));
                model.meshes.len() - 1
            }
        };
        let mut corners = [(0usize, 0usize, [0f32; 2]); 3];
        for (j, v) in tri.vertices.iter().enumerate() {
            let identity = Fixup {
                m: [
                    [1.0, 0.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0, 0.0],
                    [0.0, 0.0, 1.0, 0.0],
                ],
                im: [
                    [1.0, 0.0, 0.0, 0.0],
                    [0.0, 1.0, 0.0, 0.0],
                    [0.0, 0.0, 1.0, 0.0],
                ],
                org: [0.0; 3],
            };
            let f = fixup.get(v.bone).unwrap_or(&identity);
            let p = [
                (v.position[0] - adjust[0]) * scale,
                (v.position[1] - adjust[1]) * scale,
                (v.position[2] - adjust[2]) * scale,
            ];
            let local = transform(sub(p, f.org), &f.im).map(two_decimals);
            let n = normalize(transform(v.normal, &f.im));
            let ni = match model.normals.iter().position(|(o, b, k)| {
                Vec3::from_array(*o).dot(Vec3::from_array(n)) > normal_blend
                    && *b == v.bone
                    && *k == slot
            }) {
                Some(i) => i,
                None => {
                    model.normals.push((n, v.bone, slot));
                    model.normals.len() - 1
                }
            };
            let vi = match model
                .verts
                .iter()
                .position(|(o, b)| *o == local && *b == v.bone)
            {
                Some(i) => i,
                None => {
                    model.verts.push((local, v.bone));
                    model.verts.len() - 1
                }
            };
            // studiomdl stores corners in reverse unless `reverse` is given; the MDL reader turns
            // them back, so keep the order the MDL will read as.
            let at = if flip { 2 - j } else { j };
            corners[at] = (vi, ni, v.uv);
        }
        model.meshes[mesh].1.push(corners);
    }
    model
}

/// studiomdl's `Grab_Animation` and `Shift_Animation`: frames `start..=end`, root bones moved by
/// the origin, turned by `zrotation` and scaled.
pub(super) fn grab_animation(
    s: &State,
    smd: &Smd,
    start: i32,
    end: i32,
    adjust: [f32; 3],
    scale: f32,
    zrotation: f64,
) -> Option<Anim> {
    let mirrored = mirror_flags(&smd.nodes, &s.mirrored);
    let (cz, sz) = (zrotation.cos() as f32, zrotation.sin() as f32);
    let frames: Vec<Vec<([f32; 3], [f32; 3])>> = smd
        .frames
        .iter()
        .filter(|(t, _)| *t >= start && *t <= end)
        .map(|(_, values)| {
            values
                .iter()
                .enumerate()
                .map(|(k, v)| {
                    let mut pos = [v[0], v[1], v[2]];
                    let mut rot = [v[3], v[4], v[5]];
                    if smd.nodes[k].parent.is_none() {
                        let p = [pos[0] - adjust[0], pos[1] - adjust[1], pos[2] - adjust[2]];
                        pos = [cz * p[0] - sz * p[1], sz * p[0] + cz * p[1], p[2]];
                        rot[2] = (f64::from(rot[2]) + zrotation) as f32;
                    }
                    if mirrored[k] {
                        pos = pos.map(|x| -x);
                    }
                    pos = pos.map(|x| x * scale);
                    (pos, rot.map(clip_rotation))
                })
                .collect()
        })
        .collect();
    if frames.is_empty() {
        return None;
    }
    Some(Anim {
        nodes: smd.nodes.clone(),
        frames,
    })
}
