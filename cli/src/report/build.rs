//! Building the report parts from an imported scene.

use super::scene::{
    Bounds, ChannelEncodingReport, ClipReport, DiagnosticReport, EncodingCounts, Figure,
    InspectReport, JointReport, KeyCounts, LodReport, MaskReport, MaskWeight, MaterialReport,
    MeshReport, SkeletonReport, SubmeshReport, Summary, TrackEncodingReport, TrackReport,
    TransformReport,
};
use sinew_core::glam::{EulerRot, Quat, Vec3};
use sinew_core::{Lod, Skeleton, Transform};
use sinew_scene::{Diagnostic, Level, Scene};
use std::path::Path;

pub(super) fn channel_encoding(e: sinew_core::ChannelEncoding) -> ChannelEncodingReport {
    use sinew_core::ChannelEncoding as E;
    let (kind, min_bits, max_bits) = match e {
        E::Bind => ("bind", None, None),
        E::Constant => ("constant", None, None),
        E::F32 => ("f32", None, None),
        E::Quantized { min_bits, max_bits } => ("quantized", Some(min_bits), Some(max_bits)),
    };
    ChannelEncodingReport {
        kind,
        min_bits,
        max_bits,
    }
}

/// Fills the per-track `encoding` and per-clip `encodings` of a `.sinew` file's report from its stored
/// clips (same order as the imported scene's clips and tracks).
pub fn add_encodings(report: &mut InspectReport, clips: &[sinew_core::Clip]) {
    for (c, clip) in report.clips.iter_mut().zip(clips) {
        let mut counts = EncodingCounts {
            compressed: clip.is_compressed(),
            min_bits: u8::MAX,
            ..Default::default()
        };
        for (i, t) in c.tracks.iter_mut().enumerate() {
            let Some(e) = clip.channel_encodings(i) else {
                continue;
            };
            let e = e.map(channel_encoding);
            for ch in &e {
                match ch.kind {
                    "bind" => counts.bind += 1,
                    "constant" => counts.constant += 1,
                    "f32" => counts.f32 += 1,
                    _ => counts.quantized += 1,
                }
                if let (Some(lo), Some(hi)) = (ch.min_bits, ch.max_bits) {
                    counts.min_bits = counts.min_bits.min(lo.into_iter().min().unwrap_or(0));
                    counts.max_bits = counts.max_bits.max(hi.into_iter().max().unwrap_or(0));
                }
            }
            let [translation, rotation, scale] = e;
            t.encoding = Some(TrackEncodingReport {
                translation,
                rotation,
                scale,
            });
        }
        if counts.quantized == 0 {
            counts.min_bits = 0;
        }
        c.encodings = Some(counts);
    }
}

/// Builds the report of an imported scene.
pub fn build_report(path: &Path, file_size: Option<u64>, scene: &Scene) -> InspectReport {
    let skeleton = scene.skeleton.as_ref().map(skeleton_report);
    let clips: Vec<ClipReport> = scene
        .clips
        .iter()
        .map(|c| clip_report(c, scene.skeleton.as_ref()))
        .collect();
    let meshes: Vec<MeshReport> = scene.meshes.iter().map(mesh_report).collect();
    let materials = scene
        .materials
        .iter()
        .map(|m| MaterialReport {
            name: m.name.clone(),
            base_color: m.base_color,
            texture: m.texture.clone(),
        })
        .collect::<Vec<_>>();
    let diagnostics: Vec<DiagnosticReport> = scene.diagnostics.iter().map(diag_report).collect();
    InspectReport {
        file: path.display().to_string(),
        format: scene.source_format.name(),
        file_size,
        summary: Summary {
            joints: scene.skeleton.as_ref().map_or(0, Skeleton::len),
            clips: clips.len(),
            meshes: meshes.len(),
            vertices: meshes.iter().map(|m| m.vertices).sum(),
            triangles: meshes.iter().map(|m| m.triangles).sum(),
            materials: materials.len(),
            warnings: scene.warnings().count(),
        },
        skeleton,
        clips,
        meshes,
        materials,
        game: super::game::game_report(&scene.game),
        images: scene
            .images
            .iter()
            .map(|im| super::scene::ImageReport {
                name: im.name.clone(),
                width: im.width,
                height: im.height,
            })
            .collect(),
        sections: Vec::new(),
        masks: scene
            .masks
            .iter()
            .map(|m| MaskReport {
                name: m.name.clone(),
                weights: m
                    .weights
                    .iter()
                    .map(|(joint, weight)| MaskWeight {
                        joint: joint.clone(),
                        weight: *weight,
                    })
                    .collect(),
            })
            .collect(),
        diagnostics,
    }
}

pub(super) fn v3(v: Vec3) -> [f32; 3] {
    v.to_array()
}

pub(super) fn transform_report(t: &Transform) -> TransformReport {
    let q: Quat = t.rotation;
    let (z, y, x) = q.to_euler(EulerRot::ZYX);
    TransformReport {
        translation: v3(t.translation),
        rotation: q.to_array(),
        rotation_euler_deg: [x.to_degrees(), y.to_degrees(), z.to_degrees()],
        scale: v3(t.scale),
    }
}

pub(super) fn skeleton_report(s: &Skeleton) -> SkeletonReport {
    let names = s.names();
    let parents = s.parents();
    let mut depth = vec![0usize; names.len()];
    let mut joints = Vec::with_capacity(names.len());
    for (i, name) in names.iter().enumerate() {
        let parent = parents.get(i).copied().flatten().map(usize::from);
        // Parents come before children, so the parent's depth is known.
        let d = parent.and_then(|p| depth.get(p)).map_or(0, |d| d + 1);
        if let Some(slot) = depth.get_mut(i) {
            *slot = d;
        }
        joints.push(JointReport {
            index: i,
            name: name.clone(),
            parent,
            parent_name: parent.and_then(|p| names.get(p)).cloned(),
            depth: d,
            bind: s
                .bind_local()
                .get(i)
                .map_or_else(|| transform_report(&Transform::IDENTITY), transform_report),
        });
    }
    SkeletonReport {
        joint_count: names.len(),
        roots: joints
            .iter()
            .filter(|j| j.parent.is_none())
            .map(|j| j.index)
            .collect(),
        joints,
    }
}

/// The report of one clip: timing, key counts, tracks and (with a skeleton) which joints it drives.
pub fn clip_report(c: &sinew_scene::SceneClip, skeleton: Option<&Skeleton>) -> ClipReport {
    let mut keys = KeyCounts::default();
    // Channels usually share their key times: each distinct list is added once, and the lists
    // (each sorted) are merged rather than sorted together.
    let mut lists: Vec<&[f32]> = Vec::new();
    let mut tracks = Vec::with_capacity(c.tracks.len());
    let mut driven = Vec::new();
    for t in &c.tracks {
        let (nt, nr, ns) = (
            t.translation.times.len(),
            t.rotation.times.len(),
            t.scale.times.len(),
        );
        keys.translation += nt;
        keys.rotation += nr;
        keys.scale += ns;
        for list in [&t.translation.times, &t.rotation.times, &t.scale.times] {
            if !list.is_empty() && !lists.contains(&list.as_slice()) {
                lists.push(list);
            }
        }
        if nt + nr + ns > 0 {
            driven.push(t.joint.clone());
        }
        tracks.push(TrackReport {
            joint: t.joint.clone(),
            translation_keys: nt,
            rotation_keys: nr,
            scale_keys: ns,
            encoding: None,
        });
    }
    keys.total = keys.translation + keys.rotation + keys.scale;
    let times = sinew_core::clip::union_of_times(&lists);
    let unmatched = skeleton.map(|s| {
        driven
            .iter()
            .filter(|n| s.find(n).is_none())
            .cloned()
            .collect()
    });
    ClipReport {
        name: c.name.clone(),
        duration: c.duration,
        sample_rate: c.sample_rate,
        looping: c.looping,
        additive: c.additive,
        key_times: times.len(),
        keys,
        driven_joints: driven,
        unmatched_joints: unmatched,
        tracks,
        encodings: None,
    }
}

pub(super) fn influences(lod: &Lod) -> Option<[usize; 5]> {
    if lod.weights.is_empty() {
        return None;
    }
    let mut h = [0usize; 5];
    for w in &lod.weights {
        let n = w.iter().filter(|&&x| x > 0.0).count();
        if let Some(slot) = h.get_mut(n) {
            *slot += 1;
        }
    }
    Some(h)
}

pub(super) fn bounds(positions: &[Vec3]) -> Option<Bounds> {
    let first = *positions.first()?;
    let (min, max) = positions
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    Some(Bounds {
        min: v3(min),
        max: v3(max),
    })
}

/// The report of one mesh: LOD 0 geometry, skinning, bounds, submeshes and generated LODs.
pub fn mesh_report(m: &sinew_scene::Mesh) -> MeshReport {
    let g = &m.geometry;
    let n = g.positions.len();
    MeshReport {
        name: m.name.clone(),
        vertices: g.vertex_count(),
        triangles: g.triangle_count(),
        source_vertices: m.source_vertex_count,
        skinned: g.is_skinned(),
        has_normals: n > 0 && g.normals.len() == n,
        has_uvs: n > 0 && g.uvs.len() == n,
        submeshes: g
            .submeshes
            .iter()
            .map(|s| SubmeshReport {
                material: s.material.clone(),
                first_index: s.first_index,
                index_count: s.index_count,
                triangles: s.index_count / 3,
            })
            .collect(),
        influences: influences(g),
        bounds: bounds(&g.positions),
        lods: m
            .lods
            .iter()
            .enumerate()
            .map(|(i, l)| LodReport {
                level: i + 1,
                triangles: l.lod.triangle_count(),
                vertices: l.lod.vertex_count(),
                target_ratio: l.target_ratio,
                reached_ratio: l.reached_ratio,
                error_relative: l.error_relative,
                error_model: l.error_model,
                stopped_by_error_limit: l.stopped_by_error_limit,
                uv_seams_opened: l.uv_seams_opened,
            })
            .collect(),
    }
}

pub(super) fn level_name(level: Level) -> &'static str {
    match level {
        Level::Info => "info",
        Level::Warning => "warning",
    }
}

/// The report of one diagnostic.
pub fn diag_report(d: &Diagnostic) -> DiagnosticReport {
    DiagnosticReport {
        level: level_name(d.level),
        code: d.code.clone(),
        message: d.message.clone(),
        figures: d
            .figures
            .iter()
            .map(|(name, value)| Figure {
                name: name.clone(),
                value: *value,
            })
            .collect(),
    }
}
