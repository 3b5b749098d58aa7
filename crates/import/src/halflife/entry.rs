//! The three Half-Life entry points of sinew-import: an MDL, an SMD alone, or a QC with its SMDs, each
//! to a scene through the studio model.

use super::model::{
    BodyPart, Corner, StudioBone, StudioMesh, StudioModel, StudioSequence, StudioTexture,
    StudioVertex, Submodel,
};
use super::smd::Smd;
use super::{compile, mdl, qc, scene, smd};
use crate::text::clip_name;
use crate::{ImportError, ImportOptions, Resolver};
use sinew_scene::{Diagnostic, Scene, SourceFormat};
use std::collections::HashMap;

/// Imports a GoldSrc `.mdl` (version 10), reading `NAMET.mdl` and `NAME01.mdl` ... through `resolve`.
pub fn import_mdl(
    file: &str,
    bytes: &[u8],
    resolve: Resolver<'_>,
    options: &ImportOptions,
) -> Result<Scene, ImportError> {
    let (model, diagnostics) = mdl::read(file, bytes, resolve, options.allow_missing)?;
    scene::build_scene(
        file,
        &clip_name(file),
        &model,
        SourceFormat::Mdl,
        diagnostics,
    )
}

/// Imports a QC script: the SMD files it names are read through `resolve`, beside the QC (`$cd`).
pub fn import_qc(
    file: &str,
    bytes: &[u8],
    resolve: Resolver<'_>,
    options: &ImportOptions,
) -> Result<Scene, ImportError> {
    let script = qc::load(file, bytes, resolve)?;
    let (model, diagnostics) = compile::compile(file, &script, resolve, options.allow_missing)?;
    scene::build_scene(
        file,
        &clip_name(file),
        &model,
        SourceFormat::Qc,
        diagnostics,
    )
}

/// Imports one SMD: a reference (triangles) gives skeleton and mesh, bound in its first frame; an
/// animation (no triangles, or more than one frame) gives a clip at 30 frames per second.
pub fn import_smd(
    file: &str,
    bytes: &[u8],
    _resolve: Resolver<'_>,
    _options: &ImportOptions,
) -> Result<Scene, ImportError> {
    let parsed = smd::parse(file, bytes)?;
    let name = clip_name(file);
    let (model, mut diagnostics) = studio_from_smd(&name, &parsed);
    diagnostics.splice(0..0, parsed.diagnostics.iter().cloned());
    scene::build_scene(file, &name, &model, SourceFormat::Smd, diagnostics)
}

/// A vertex of one SMD by its influences and position bits.
type VertexKey = (Vec<(usize, u32)>, [u32; 3]);

/// The studio model of one SMD, in the SMD's own axes (no studiomdl turn, no quantisation).
pub fn studio_from_smd(name: &str, smd: &Smd) -> (StudioModel, Vec<Diagnostic>) {
    let mut diagnostics = Vec::new();
    // Bones parents-first (an SMD may list a child before its parent).
    let n = smd.nodes.len();
    let mut order: Vec<usize> = Vec::with_capacity(n);
    let mut placed = vec![false; n];
    while order.len() < n {
        let before = order.len();
        for k in 0..n {
            if !placed[k] && smd.nodes[k].parent.is_none_or(|p| placed[p]) {
                placed[k] = true;
                order.push(k);
            }
        }
        if order.len() == before {
            break; // cycles were refused by the parser
        }
    }
    let mut new_index = vec![0usize; n];
    for (i, &k) in order.iter().enumerate() {
        new_index[k] = i;
    }
    let first = smd
        .frames
        .first()
        .map(|(_, v)| v.clone())
        .unwrap_or_default();
    let bones = order
        .iter()
        .map(|&k| StudioBone {
            name: smd.nodes[k].name.clone(),
            parent: smd.nodes[k].parent.map(|p| new_index[p]),
            value: first.get(k).copied().unwrap_or([0.0; 6]),
        })
        .collect();

    // One submodel; vertices shared by position and influences, one mesh per material.
    let mut textures: Vec<String> = Vec::new();
    let mut vertices: Vec<StudioVertex> = Vec::new();
    let mut index: HashMap<VertexKey, usize> = HashMap::new();
    let mut meshes: Vec<StudioMesh> = Vec::new();
    let mut over_four = 0usize;
    for tri in &smd.triangles {
        let slot = match textures.iter().position(|t| *t == tri.material) {
            Some(i) => i,
            None => {
                textures.push(tri.material.clone());
                textures.len() - 1
            }
        };
        let corners = tri.vertices.clone().map(|v| {
            let mut influences: Vec<(usize, f32)> = v
                .links
                .iter()
                .filter(|(_, w)| *w > 0.0)
                .map(|&(b, w)| (new_index[b], w))
                .collect();
            let sum: f32 = influences.iter().map(|(_, w)| w).sum();
            if influences.is_empty() {
                influences.push((new_index[v.bone], 1.0));
            } else if sum < 1.0 - 1e-4 {
                // Source's studiomdl gives the rest of the weight to the vertex's parent bone.
                influences.push((new_index[v.bone], 1.0 - sum));
            }
            influences.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            if influences.len() > 4 {
                over_four += 1;
                influences.truncate(4);
            }
            let total: f32 = influences.iter().map(|(_, w)| w).sum();
            for (_, w) in &mut influences {
                *w /= total;
            }
            let key = (
                influences
                    .iter()
                    .map(|&(b, w)| (b, w.to_bits()))
                    .collect::<Vec<_>>(),
                v.position.map(f32::to_bits),
            );
            let vi = *index.entry(key).or_insert_with(|| {
                vertices.push(StudioVertex {
                    position: v.position,
                    influences,
                });
                vertices.len() - 1
            });
            Corner {
                vertex: vi,
                normal: v.normal,
                uv: [v.uv[0], 1.0 - v.uv[1]],
            }
        });
        match meshes.iter_mut().find(|m| m.skin_slot == slot) {
            Some(m) => m.triangles.push(corners),
            None => meshes.push(StudioMesh {
                skin_slot: slot,
                triangles: vec![corners],
            }),
        }
    }
    if over_four > 0 {
        diagnostics.push(Diagnostic::warning(
            "smd-influences-reduced",
            format!("{over_four} vertex corners had more than four weight links; the four largest were kept and renormalised"),
        ));
    }
    let body_parts = if smd.triangles.is_empty() {
        Vec::new()
    } else {
        vec![BodyPart {
            name: name.to_string(),
            submodels: vec![Submodel {
                name: name.to_string(),
                vertices,
                meshes,
            }],
        }]
    };

    // A clip when there is no mesh or more than one frame; missing time numbers hold the previous frame.
    let mut sequences = Vec::new();
    if smd.triangles.is_empty() || smd.frames.len() > 1 {
        if let (Some((t0, _)), Some((t1, _))) = (smd.frames.first(), smd.frames.last()) {
            let span = (*t1 as i64 - *t0 as i64 + 1) as usize;
            let mut frames = Vec::with_capacity(span);
            let mut it = smd.frames.iter().peekable();
            let mut current: Vec<[f32; 6]> = Vec::new();
            let mut gaps = 0usize;
            for t in 0..span as i64 {
                match it.peek() {
                    Some((ft, v)) if *ft as i64 - *t0 as i64 == t => {
                        current = v.clone();
                        it.next();
                    }
                    _ => gaps += 1,
                }
                frames.push(
                    order
                        .iter()
                        .map(|&k| current.get(k).copied().unwrap_or([0.0; 6]))
                        .collect(),
                );
            }
            if gaps > 0 {
                diagnostics.push(Diagnostic::warning(
                    "smd-missing-frames",
                    format!("{gaps} frame numbers between {t0} and {t1} have no `time` block; they hold the previous frame"),
                ));
            }
            sequences.push(StudioSequence {
                label: name.to_string(),
                fps: 30.0,
                blends: vec![frames],
                ..StudioSequence::default()
            });
        }
    }
    let model = StudioModel {
        bones,
        body_parts,
        textures: textures
            .iter()
            .map(|t| StudioTexture {
                name: t.clone(),
                flags: 0,
                width: 0,
                height: 0,
                indices: Vec::new(),
                palette: Vec::new(),
            })
            .collect(),
        skin_families: vec![(0..textures.len()).collect()],
        sequences,
        ..StudioModel::default()
    };
    (model, diagnostics)
}
