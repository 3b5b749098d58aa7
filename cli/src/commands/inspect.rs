//! `sinew inspect FILE`: what a file holds, as a human report on stderr or JSON on stdout.
//!
//! The JSON report is [`InspectReport`]; its field names are a stable interface documented in
//! docs/cli.md. Add fields, never rename or remove them.

use crate::cli::InspectArgs;
use crate::output::{print_json, Ctx};
use crate::Status;
use serde::Serialize;
use sinew_core::glam::{EulerRot, Quat, Vec3};
use sinew_core::{Lod, Skeleton, Transform};
use sinew_scene::{Diagnostic, Level, Scene};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// Runs `sinew inspect`.
pub fn run(args: &InspectArgs, ctx: &Ctx) -> anyhow::Result<Status> {
    let scene = crate::input::import(&args.file, &args.import)?;
    let file_size = std::fs::metadata(&args.file).map(|m| m.len()).ok();
    let mut report = build_report(&args.file, file_size, &scene);
    if scene.source_format == sinew_scene::SourceFormat::Sinew {
        // The scene has the decoded curves; how each channel is stored comes from the asset itself.
        // The import above already read and checked the file.
        if let Ok(bytes) = std::fs::read(&args.file) {
            if let Ok(asset) = sinew_core::format::read(&bytes) {
                add_encodings(&mut report, &asset.clips);
            }
            if let Ok(sections) = sinew_core::format::sections(&bytes) {
                report.sections = sections
                    .iter()
                    .map(|s| SectionReport {
                        tag: String::from_utf8_lossy(&s.tag.0).into_owned(),
                        offset: s.offset,
                        size: s.size,
                        checksum_ok: s.checksum_ok,
                        known: s.known,
                    })
                    .collect();
            }
        }
    }
    if ctx.json {
        print_json(&report)?;
    } else if ctx.human() {
        eprint!("{}", human(&report));
    }
    Ok(Status::Success)
}

/// The whole report of `sinew inspect --json`.
#[derive(Debug, Serialize)]
pub struct InspectReport {
    /// The path as given on the command line.
    pub file: String,
    /// Source format: `ms3d`, `gltf`, `obj`, `bvh` or `sinew`.
    pub format: &'static str,
    /// Size of the file in bytes.
    pub file_size: Option<u64>,
    /// Totals over the whole file.
    pub summary: Summary,
    /// The skeleton, or `null` when the file has none.
    pub skeleton: Option<SkeletonReport>,
    /// Animation clips.
    pub clips: Vec<ClipReport>,
    /// Meshes.
    pub meshes: Vec<MeshReport>,
    /// Materials.
    pub materials: Vec<MaterialReport>,
    /// Named joint masks (`.sinew` MASK section; empty for other formats).
    pub masks: Vec<MaskReport>,
    /// Sizes by section of a `.sinew` file, in file order (empty for other formats).
    pub sections: Vec<SectionReport>,
    /// Every diagnostic the importer raised, in order.
    pub diagnostics: Vec<DiagnosticReport>,
}

/// One section of a `.sinew` file.
#[derive(Debug, Serialize)]
pub struct SectionReport {
    /// Four-character tag (`STRS`, `SKEL`, `MESH`, `CLIP`, `SRCV`, `MASK`, or unknown).
    pub tag: String,
    /// Byte offset from the start of the file.
    pub offset: u64,
    /// Size in bytes (padding not included).
    pub size: u64,
    /// Whether the bytes match the stored CRC-32.
    pub checksum_ok: bool,
    /// Whether this version of sinew knows the tag (unknown sections are skipped).
    pub known: bool,
}

/// One named joint mask.
#[derive(Debug, Serialize)]
pub struct MaskReport {
    /// Mask name.
    pub name: String,
    /// `{joint, weight}` pairs as stored; joints not listed have weight 0.
    pub weights: Vec<MaskWeight>,
}

/// One joint of a mask.
#[derive(Debug, Serialize)]
pub struct MaskWeight {
    /// Joint name.
    pub joint: String,
    /// Weight in [0, 1].
    pub weight: f32,
}

/// How one channel of a track is stored in a `.sinew` file.
#[derive(Debug, Serialize, Clone, PartialEq)]
pub struct ChannelEncodingReport {
    /// `bind` (not stored), `constant` (one f32 value), `f32` (plain values in every frame) or
    /// `quantized`.
    pub kind: &'static str,
    /// Quantized only: per component, the smallest bit width over all segments.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_bits: Option<[u8; 3]>,
    /// Quantized only: per component, the largest bit width over all segments.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_bits: Option<[u8; 3]>,
}

/// How the three channels of a track are stored.
#[derive(Debug, Serialize, Clone, PartialEq)]
pub struct TrackEncodingReport {
    /// Translation.
    pub translation: ChannelEncodingReport,
    /// Rotation (quantized: the three smallest components).
    pub rotation: ChannelEncodingReport,
    /// Scale.
    pub scale: ChannelEncodingReport,
}

/// Channel counts per encoding over a clip.
#[derive(Debug, Serialize, Default, Clone, PartialEq)]
pub struct EncodingCounts {
    /// Whether the clip is stored compressed.
    pub compressed: bool,
    /// Channels not stored (bind value).
    pub bind: usize,
    /// Channels stored as one value.
    pub constant: usize,
    /// Channels stored as plain f32 frames.
    pub f32: usize,
    /// Channels stored quantized.
    pub quantized: usize,
    /// Smallest bit width of any quantized component (0 without quantized channels).
    pub min_bits: u8,
    /// Largest bit width of any quantized component (0 without quantized channels).
    pub max_bits: u8,
}

fn channel_encoding(e: sinew_core::ChannelEncoding) -> ChannelEncodingReport {
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

/// Totals.
#[derive(Debug, Serialize)]
pub struct Summary {
    /// Number of joints (0 without a skeleton).
    pub joints: usize,
    /// Number of clips.
    pub clips: usize,
    /// Number of meshes.
    pub meshes: usize,
    /// Vertices over all meshes (LOD 0).
    pub vertices: usize,
    /// Triangles over all meshes (LOD 0).
    pub triangles: usize,
    /// Number of materials.
    pub materials: usize,
    /// Diagnostics at warning level.
    pub warnings: usize,
}

/// The skeleton.
#[derive(Debug, Serialize)]
pub struct SkeletonReport {
    /// Number of joints.
    pub joint_count: usize,
    /// Indices of the joints without a parent.
    pub roots: Vec<usize>,
    /// Joints in skeleton order (parents before children).
    pub joints: Vec<JointReport>,
}

/// One joint.
#[derive(Debug, Serialize)]
pub struct JointReport {
    /// Index in the skeleton.
    pub index: usize,
    /// Joint name.
    pub name: String,
    /// Parent index, `null` for a root.
    pub parent: Option<usize>,
    /// Parent name, `null` for a root.
    pub parent_name: Option<String>,
    /// Depth in the tree (roots are 0).
    pub depth: usize,
    /// Bind-pose local transform.
    pub bind: TransformReport,
}

/// A local transform in several spellings.
#[derive(Debug, Serialize)]
pub struct TransformReport {
    /// Translation x, y, z.
    pub translation: [f32; 3],
    /// Rotation quaternion x, y, z, w.
    pub rotation: [f32; 4],
    /// The same rotation as Euler angles in degrees, x, y, z, with R = Rz * Ry * Rx.
    pub rotation_euler_deg: [f32; 3],
    /// Scale x, y, z.
    pub scale: [f32; 3],
}

/// One clip.
#[derive(Debug, Serialize)]
pub struct ClipReport {
    /// Clip name.
    pub name: String,
    /// Duration, seconds.
    pub duration: f32,
    /// Nominal frames per second.
    pub sample_rate: f32,
    /// Whether the clip loops.
    pub looping: bool,
    /// Whether the clip is additive.
    pub additive: bool,
    /// Number of distinct key times over all tracks.
    pub key_times: usize,
    /// Number of keys over all tracks and channels.
    pub keys: KeyCounts,
    /// Names of the joints the clip drives (tracks with at least one key), in track order.
    pub driven_joints: Vec<String>,
    /// Driven names that are not joints of the file's skeleton; `null` when the file has no skeleton.
    pub unmatched_joints: Option<Vec<String>>,
    /// Per-track key counts.
    pub tracks: Vec<TrackReport>,
    /// `.sinew` input: channel counts per storage encoding; `null` for other formats.
    pub encodings: Option<EncodingCounts>,
}

/// Key counts by channel.
#[derive(Debug, Serialize, Default)]
pub struct KeyCounts {
    /// Translation keys.
    pub translation: usize,
    /// Rotation keys.
    pub rotation: usize,
    /// Scale keys.
    pub scale: usize,
    /// Sum of the three.
    pub total: usize,
}

/// One track of a clip.
#[derive(Debug, Serialize)]
pub struct TrackReport {
    /// The joint name the track drives.
    pub joint: String,
    /// Translation keys.
    pub translation_keys: usize,
    /// Rotation keys.
    pub rotation_keys: usize,
    /// Scale keys.
    pub scale_keys: usize,
    /// `.sinew` input: how each channel is stored; `null` for other formats.
    pub encoding: Option<TrackEncodingReport>,
}

/// One mesh.
#[derive(Debug, Serialize)]
pub struct MeshReport {
    /// Mesh name.
    pub name: String,
    /// Vertices (after splitting by normal/UV).
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Vertices in the source file's own vertex list.
    pub source_vertices: u32,
    /// Whether the mesh has skin influences.
    pub skinned: bool,
    /// Whether every vertex has a normal.
    pub has_normals: bool,
    /// Whether every vertex has a UV.
    pub has_uvs: bool,
    /// Submeshes in index order.
    pub submeshes: Vec<SubmeshReport>,
    /// `influences[n]` = number of vertices with exactly n non-zero weights (n = 0..4); `null` for a
    /// static mesh.
    pub influences: Option<[usize; 5]>,
    /// Axis-aligned bounds of the positions; `null` for a mesh without vertices.
    pub bounds: Option<Bounds>,
    /// Generated LODs, most detailed first (LOD 0, the mesh itself, is not listed).
    pub lods: Vec<LodReport>,
}

/// A submesh.
#[derive(Debug, Serialize)]
pub struct SubmeshReport {
    /// Material name.
    pub material: String,
    /// First index in the index buffer.
    pub first_index: u32,
    /// Number of indices.
    pub index_count: u32,
    /// Number of triangles (`index_count / 3`).
    pub triangles: u32,
}

/// Axis-aligned bounds.
#[derive(Debug, Serialize)]
pub struct Bounds {
    /// Minimum x, y, z.
    pub min: [f32; 3],
    /// Maximum x, y, z.
    pub max: [f32; 3],
}

/// A generated LOD.
#[derive(Debug, Serialize)]
pub struct LodReport {
    /// LOD level (1 is the first generated one).
    pub level: usize,
    /// Triangles.
    pub triangles: usize,
    /// Vertices.
    pub vertices: usize,
    /// Requested fraction of LOD 0's triangles.
    pub target_ratio: f32,
    /// Fraction of LOD 0's triangles kept.
    pub reached_ratio: f32,
    /// Simplifier error relative to the mesh extent.
    pub error_relative: f32,
    /// Simplifier error in model units.
    pub error_model: f32,
    /// Whether the error limit stopped simplification before the target.
    pub stopped_by_error_limit: bool,
}

/// A material.
#[derive(Debug, Serialize)]
pub struct MaterialReport {
    /// Material name.
    pub name: String,
    /// Base colour RGBA, linear.
    pub base_color: [f32; 4],
    /// Texture path or URI as written in the source.
    pub texture: Option<String>,
}

/// A diagnostic.
#[derive(Debug, Clone, Serialize)]
pub struct DiagnosticReport {
    /// `info` or `warning`.
    pub level: &'static str,
    /// Stable kebab-case code.
    pub code: String,
    /// One human sentence.
    pub message: String,
    /// Named figures, in the importer's order.
    pub figures: Vec<Figure>,
}

/// A named figure behind a diagnostic.
#[derive(Debug, Clone, Serialize)]
pub struct Figure {
    /// Figure name.
    pub name: String,
    /// Value.
    pub value: f64,
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

fn v3(v: Vec3) -> [f32; 3] {
    v.to_array()
}

fn transform_report(t: &Transform) -> TransformReport {
    let q: Quat = t.rotation;
    let (z, y, x) = q.to_euler(EulerRot::ZYX);
    TransformReport {
        translation: v3(t.translation),
        rotation: q.to_array(),
        rotation_euler_deg: [x.to_degrees(), y.to_degrees(), z.to_degrees()],
        scale: v3(t.scale),
    }
}

fn skeleton_report(s: &Skeleton) -> SkeletonReport {
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

pub(crate) fn clip_report(c: &sinew_scene::SceneClip, skeleton: Option<&Skeleton>) -> ClipReport {
    let mut keys = KeyCounts::default();
    let mut times: Vec<f32> = Vec::new();
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
        times.extend_from_slice(&t.translation.times);
        times.extend_from_slice(&t.rotation.times);
        times.extend_from_slice(&t.scale.times);
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
    times.sort_by(f32::total_cmp);
    times.dedup();
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

fn influences(lod: &Lod) -> Option<[usize; 5]> {
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

fn bounds(positions: &[Vec3]) -> Option<Bounds> {
    let first = *positions.first()?;
    let (min, max) = positions
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    Some(Bounds {
        min: v3(min),
        max: v3(max),
    })
}

pub(crate) fn mesh_report(m: &sinew_scene::Mesh) -> MeshReport {
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
            })
            .collect(),
    }
}

fn level_name(level: Level) -> &'static str {
    match level {
        Level::Info => "info",
        Level::Warning => "warning",
    }
}

pub(crate) fn diag_report(d: &Diagnostic) -> DiagnosticReport {
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

/// A number with at most 4 decimals, trailing zeros dropped, and no `-0`.
pub(crate) fn num(x: f32) -> String {
    let s = format!("{x:.4}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".to_string()
    } else {
        s
    }
}

pub(crate) fn nums(v: &[f32]) -> String {
    v.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", ")
}

/// The human-readable report (written to stderr by `run`).
pub fn human(r: &InspectReport) -> String {
    let mut o = String::new();
    let size = r
        .file_size
        .map_or_else(String::new, |s| format!(", {s} bytes"));
    let _ = writeln!(o, "{}: {}{size}", r.file, r.format);
    let s = &r.summary;
    let _ = writeln!(
        o,
        "  {} joints, {} clips, {} meshes ({} vertices, {} triangles), {} materials, {} warnings",
        s.joints, s.clips, s.meshes, s.vertices, s.triangles, s.materials, s.warnings
    );

    match &r.skeleton {
        None => {
            let _ = writeln!(o, "skeleton: none");
        }
        Some(sk) => {
            let _ = writeln!(o, "skeleton: {} joints", sk.joint_count);
            // Depth-first from each root, children in index order.
            let mut children: BTreeMap<Option<usize>, Vec<usize>> = BTreeMap::new();
            for j in &sk.joints {
                children.entry(j.parent).or_default().push(j.index);
            }
            let mut stack: Vec<usize> = children.get(&None).cloned().unwrap_or_default();
            stack.reverse();
            while let Some(i) = stack.pop() {
                let Some(j) = sk.joints.get(i) else { continue };
                let b = &j.bind;
                let parent = j
                    .parent
                    .map_or_else(|| "root".to_string(), |p| format!("parent {p}"));
                let _ = writeln!(
                    o,
                    "  {:indent$}[{}] {} ({parent})  T({}) R({})deg S({})",
                    "",
                    j.index,
                    j.name,
                    nums(&b.translation),
                    nums(&b.rotation_euler_deg),
                    nums(&b.scale),
                    indent = j.depth * 2
                );
                if let Some(kids) = children.get(&Some(i)) {
                    stack.extend(kids.iter().rev());
                }
            }
        }
    }

    let _ = writeln!(o, "clips: {}", r.clips.len());
    for c in &r.clips {
        let mut flags = Vec::new();
        if c.looping {
            flags.push("looping");
        }
        if c.additive {
            flags.push("additive");
        }
        let flags = if flags.is_empty() {
            String::new()
        } else {
            format!(", {}", flags.join(", "))
        };
        let _ = writeln!(
            o,
            "  \"{}\": {} s at {} fps, {} key times, {} keys (T {}, R {}, S {}){flags}",
            c.name,
            num(c.duration),
            num(c.sample_rate),
            c.key_times,
            c.keys.total,
            c.keys.translation,
            c.keys.rotation,
            c.keys.scale
        );
        let _ = writeln!(
            o,
            "    drives {} joints: {}",
            c.driven_joints.len(),
            c.driven_joints.join(", ")
        );
        if let Some(e) = &c.encodings {
            let bits = if e.quantized > 0 {
                format!(" ({}-{} bits)", e.min_bits, e.max_bits)
            } else {
                String::new()
            };
            let _ = writeln!(
                o,
                "    stored {}: {} quantized{bits}, {} f32, {} constant, {} bind channels",
                if e.compressed { "compressed" } else { "plain" },
                e.quantized,
                e.f32,
                e.constant,
                e.bind
            );
        }
        match &c.unmatched_joints {
            None => {
                let _ = writeln!(
                    o,
                    "    no skeleton in this file to match joint names against"
                );
            }
            Some(u) if u.is_empty() => {}
            Some(u) => {
                let _ = writeln!(
                    o,
                    "    {} names match no joint of the skeleton: {}",
                    u.len(),
                    u.join(", ")
                );
            }
        }
    }

    let _ = writeln!(o, "meshes: {}", r.meshes.len());
    for m in &r.meshes {
        let _ = writeln!(
            o,
            "  \"{}\": {} vertices ({} in source), {} triangles, {}{}{}",
            m.name,
            m.vertices,
            m.source_vertices,
            m.triangles,
            if m.skinned { "skinned" } else { "static" },
            if m.has_normals { ", normals" } else { "" },
            if m.has_uvs { ", uvs" } else { "" },
        );
        for sm in &m.submeshes {
            let _ = writeln!(
                o,
                "    submesh: {} triangles, material \"{}\"",
                sm.triangles, sm.material
            );
        }
        if let Some(h) = m.influences {
            let _ = writeln!(
                o,
                "    influences per vertex: 0: {}, 1: {}, 2: {}, 3: {}, 4: {}",
                h[0], h[1], h[2], h[3], h[4]
            );
        }
        if let Some(b) = &m.bounds {
            let _ = writeln!(o, "    bounds: ({}) .. ({})", nums(&b.min), nums(&b.max));
        }
        for l in &m.lods {
            let _ = writeln!(
                o,
                "    LOD {}: {} triangles, {} vertices, ratio {} (target {}), error {} ({} model units){}",
                l.level,
                l.triangles,
                l.vertices,
                num(l.reached_ratio),
                num(l.target_ratio),
                num(l.error_relative),
                num(l.error_model),
                if l.stopped_by_error_limit {
                    ", stopped by error limit"
                } else {
                    ""
                }
            );
        }
    }

    if !r.materials.is_empty() {
        let _ = writeln!(o, "materials: {}", r.materials.len());
        for m in &r.materials {
            let tex = m
                .texture
                .as_deref()
                .map_or_else(String::new, |t| format!(", texture \"{t}\""));
            let _ = writeln!(
                o,
                "  \"{}\": base colour ({}){tex}",
                m.name,
                nums(&m.base_color)
            );
        }
    }

    if !r.masks.is_empty() {
        let _ = writeln!(o, "masks: {}", r.masks.len());
        for m in &r.masks {
            let _ = writeln!(o, "  \"{}\": {} joints", m.name, m.weights.len());
        }
    }

    if !r.sections.is_empty() {
        let _ = writeln!(o, "sections (bytes):");
        for s in &r.sections {
            let _ = writeln!(
                o,
                "  {} {:>9} at {}{}",
                s.tag,
                s.size,
                s.offset,
                if s.known { "" } else { " (unknown, skipped)" }
            );
        }
    }

    let _ = writeln!(o, "diagnostics: {}", r.diagnostics.len());
    for d in &r.diagnostics {
        let figs = if d.figures.is_empty() {
            String::new()
        } else {
            let f: Vec<String> = d
                .figures
                .iter()
                .map(|f| format!("{}={}", f.name, f.value))
                .collect();
            format!(" ({})", f.join(", "))
        };
        let _ = writeln!(o, "  {} [{}] {}{figs}", d.level, d.code, d.message);
    }
    o
}

#[cfg(test)]
mod tests {
    use super::*;
    use sinew_core::{Curve, JointDesc, Submesh, TrackCurves};
    use sinew_scene::{SceneClip, SourceFormat};

    fn scene() -> Scene {
        let joints = vec![
            JointDesc {
                name: "child".into(),
                parent: Some("root".into()),
                bind_local: Transform::new(
                    Vec3::new(0.0, 2.0, 0.0),
                    Quat::from_rotation_z(90f32.to_radians()),
                    Vec3::ONE,
                ),
                inverse_bind: None,
            },
            JointDesc {
                name: "root".into(),
                parent: None,
                bind_local: Transform::IDENTITY,
                inverse_bind: None,
            },
        ];
        let (skeleton, _) = Skeleton::from_unordered(joints).unwrap();
        let mut s = Scene::new(SourceFormat::Ms3d);
        s.skeleton = Some(skeleton);
        s.clips.push(SceneClip {
            name: "wave".into(),
            duration: 1.0,
            sample_rate: 30.0,
            looping: true,
            additive: false,
            tracks: vec![
                TrackCurves {
                    joint: "child".into(),
                    translation: Curve::new(vec![0.0, 1.0], vec![Vec3::ZERO, Vec3::X]),
                    rotation: Curve::new(vec![0.0, 0.5], vec![Quat::IDENTITY; 2]),
                    scale: Curve::default(),
                },
                TrackCurves {
                    joint: "ghost".into(),
                    translation: Curve::new(vec![0.25], vec![Vec3::ZERO]),
                    rotation: Curve::default(),
                    scale: Curve::default(),
                },
            ],
        });
        let geometry = Lod {
            positions: vec![
                Vec3::new(-1.0, 0.0, 0.0),
                Vec3::new(1.0, 2.0, 0.0),
                Vec3::new(0.0, 1.0, 3.0),
            ],
            joints: vec![[0, 0, 0, 0], [0, 1, 0, 0], [0, 1, 0, 0]],
            weights: vec![
                [1.0, 0.0, 0.0, 0.0],
                [0.5, 0.5, 0.0, 0.0],
                [0.25, 0.75, 0.0, 0.0],
            ],
            indices: vec![0, 1, 2],
            submeshes: vec![Submesh {
                first_index: 0,
                index_count: 3,
                material: "skin".into(),
            }],
            ..Lod::default()
        };
        s.meshes.push(sinew_scene::Mesh {
            name: "body".into(),
            geometry,
            source_vertex: vec![0, 1, 2],
            source_vertex_count: 3,
            lods: Vec::new(),
        });
        s.diagnostics
            .push(Diagnostic::warning("odd-thing", "Something odd.").with_figure("count", 3.0));
        s
    }

    #[test]
    fn report_counts_joints_keys_influences_and_unmatched() {
        let r = build_report(Path::new("x.ms3d"), Some(10), &scene());
        let sk = r.skeleton.as_ref().unwrap();
        assert_eq!(sk.joint_count, 2);
        assert_eq!(sk.joints[0].name, "root");
        assert_eq!(sk.joints[1].parent, Some(0));
        assert_eq!(sk.joints[1].depth, 1);
        let e = sk.joints[1].bind.rotation_euler_deg;
        assert!((e[2] - 90.0).abs() < 1e-3 && e[0].abs() < 1e-3, "{e:?}");
        let c = &r.clips[0];
        assert_eq!(c.keys.translation, 3);
        assert_eq!(c.keys.rotation, 2);
        assert_eq!(c.keys.total, 5);
        // distinct times: 0, 0.25, 0.5, 1
        assert_eq!(c.key_times, 4);
        assert_eq!(c.driven_joints, vec!["child", "ghost"]);
        assert_eq!(
            c.unmatched_joints.as_deref(),
            Some(&["ghost".to_string()][..])
        );
        let m = &r.meshes[0];
        assert_eq!(m.influences, Some([0, 1, 2, 0, 0]));
        let b = m.bounds.as_ref().unwrap();
        assert_eq!(b.min, [-1.0, 0.0, 0.0]);
        assert_eq!(b.max, [1.0, 2.0, 3.0]);
        assert_eq!(r.summary.warnings, 1);
        assert_eq!(r.diagnostics[0].figures[0].value, 3.0);
    }

    #[test]
    fn human_report_shows_tree_indentation() {
        let text = human(&build_report(Path::new("x.ms3d"), None, &scene()));
        assert!(text.contains("\n  [0] root (root)"), "{text}");
        assert!(
            text.contains("\n    [1] child (parent 0)  T(0, 2, 0) R(0, 0, 90)deg"),
            "{text}"
        );
        assert!(
            text.contains("1 names match no joint of the skeleton: ghost"),
            "{text}"
        );
        assert!(
            text.contains("warning [odd-thing] Something odd. (count=3)"),
            "{text}"
        );
    }

    #[test]
    fn numbers_are_trimmed() {
        assert_eq!(num(1.0), "1");
        assert_eq!(num(-0.00001), "0");
        assert_eq!(num(2.5), "2.5");
    }
}
