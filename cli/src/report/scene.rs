//! The report of what a file holds (`inspect --json`), and the parts of it other commands print too
//! (clips, meshes, LODs, diagnostics). Field names are a stable interface documented in docs/cli.md:
//! add fields, never rename or remove them.

use serde::Serialize;

/// The whole report of `sinew inspect --json`.
#[derive(Debug, Serialize)]
pub struct InspectReport {
    /// The path as given on the command line.
    pub file: String,
    /// Source format: `ms3d`, `gltf`, `obj`, `bvh`, `mdl`, `smd`, `qc` or `sinew`.
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
    /// Game data (Half-Life models; `.sinew` GAME section), or `null`.
    pub game: Option<super::game::GameReport>,
    /// Texture images the source carries, as `name`, `width`, `height` (Half-Life models).
    pub images: Vec<ImageReport>,
}

/// One texture image a source carries.
#[derive(Debug, Serialize)]
pub struct ImageReport {
    /// Texture name.
    pub name: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
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
    /// Whether the level could only be built by letting collapses cross UV seams (always false
    /// when read from a `.sinew` file, which does not store it).
    pub uv_seams_opened: bool,
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
