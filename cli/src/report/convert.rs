//! What `convert`, `split` and `lod` report per input and output: the written file, its meshes and clips,
//! and the pipeline steps (motion binding and mapping, timeline cuts, partial-body splits).

use super::scene::{DiagnosticReport, KeyCounts, LodReport};
use serde::Serialize;
use sinew_pipeline::compress::ClipCompressionReport;

/// One rig joint of a mapping report.
#[derive(Debug, Clone, Serialize)]
pub struct EntryReport {
    /// Rig joint name.
    pub rig: String,
    /// Motion joint bound to it, `null` when unmatched.
    pub motion: Option<String>,
    /// `exact`, `normalised`, `synonym`, `fuzzy`, `file`, or `null` when unmatched.
    pub method: Option<&'static str>,
    /// For `synonym`: the slot both joints fall in.
    pub slot: Option<String>,
    /// For `fuzzy`: the similarity score (0.75 to 1).
    pub score: Option<f32>,
    /// The rig joint's side: `centre`, `left` or `right`.
    pub side: &'static str,
}

/// How a motion's joints bind to a rig's joints.
#[derive(Debug, Clone, Serialize)]
pub struct MappingReport {
    /// Rig label (file name).
    pub rig: String,
    /// Motion label (file name).
    pub motion: String,
    /// Name family detected for the rig: `biped`, `cmu`, `mixamo`, `other`.
    pub rig_family: &'static str,
    /// Name family detected for the motion.
    pub motion_family: &'static str,
    /// Number of rig joints bound to a motion joint.
    pub bound: usize,
    /// One entry per rig joint, in rig order.
    pub entries: Vec<EntryReport>,
    /// Rig joints bound to nothing.
    pub unmatched_rig: Vec<String>,
    /// Motion joints bound to nothing.
    pub unmatched_motion: Vec<String>,
    /// Known ambiguities (codes in docs/mapping.md).
    pub warnings: Vec<DiagnosticReport>,
    /// `map --png` only: what the picture shows (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub picture: Option<sinew_pipeline::preview::mapping::MapPictureReport>,
}

/// A rest/bind orientation difference above the warning threshold.
#[derive(Debug, Clone, Serialize)]
pub struct RestDifferenceReport {
    /// Rig joint.
    pub rig: String,
    /// Motion joint.
    pub motion: String,
    /// Angle between the model-space orientations, degrees.
    pub degrees: f32,
}

/// What binding one `--anim` file did.
#[derive(Debug, Clone, Serialize)]
pub struct MotionReport {
    /// The motion file.
    pub file: String,
    /// The joint mapping used.
    pub mapping: MappingReport,
    /// Whether `--retarget` was used.
    pub retargeted: bool,
    /// With `--retarget`: ratio of the leg chain lengths, rig over motion (informational; the root
    /// translation is scaled by `root_scale`).
    pub leg_scale: Option<f32>,
    /// With `--retarget`: factor applied to the root translation (hip heights, or `--root-scale`).
    pub root_scale: Option<f32>,
    /// With `--retarget`: how the root translation was scaled and grounded.
    pub root: Option<RootScaleReport>,
    /// Without `--retarget`: bound pairs whose orientations differ by more than the threshold.
    pub rest_differences: Vec<RestDifferenceReport>,
    /// Names of the clips added to the output.
    pub clips: Vec<String>,
}

/// How `--retarget` moved the root (docs/mapping.md).
#[derive(Debug, Clone, Serialize)]
pub struct RootScaleReport {
    /// Factor applied to the root translation.
    pub root_scale: f32,
    /// `hip-height`, `lowest-joint`, `override` or `none`.
    pub source: &'static str,
    /// Hip heights `[motion, rig]` above the feet (or lowest joint), each in its own units.
    pub hip_heights: Option<[f32; 2]>,
    /// The motion's standing shift, motion units (0 when its rest pose stands on its floor).
    pub standing_shift: f32,
    /// Height added to the root to put the rig's feet on its bind-pose floor, rig units (0 when the
    /// standing shift is 0).
    pub grounding: f32,
    /// Rig joints whose translation was transferred.
    pub root_joints: Vec<String>,
}

/// One clip made by a split.
#[derive(Debug, Clone, Serialize)]
pub struct PartReport {
    /// Clip name (`walk.upper`).
    pub name: String,
    /// Joints the clip drives, in track order.
    pub joints: Vec<String>,
}

/// What a split did to one source clip.
#[derive(Debug, Clone, Serialize)]
pub struct SplitReport {
    /// The source clip.
    pub clip: String,
    /// The clips made from it.
    pub parts: Vec<PartReport>,
}
/// The whole report of `sinew convert --json`.
#[derive(Debug, Serialize)]
pub struct ConvertReport {
    /// Inputs given.
    pub inputs: usize,
    /// Outputs written.
    pub converted: usize,
    /// Inputs that failed.
    pub failed: usize,
    /// One entry per input, in command-line order.
    pub files: Vec<FileReport>,
}

/// One input of a convert run.
#[derive(Debug, Serialize)]
pub struct FileReport {
    /// The input path as given.
    pub input: String,
    /// The output path.
    pub output: String,
    /// `converted` or `failed`.
    pub status: &'static str,
    /// The error (one line) when failed, else `null`.
    pub error: Option<String>,
    /// What was written (absent when failed).
    #[serde(flatten)]
    pub details: Option<OutputDetails>,
}

/// What one written `.sinew` holds and how it was made.
#[derive(Debug, Serialize)]
pub struct OutputDetails {
    /// Size of the written file, bytes.
    pub bytes: u64,
    /// Source format of the input.
    pub format: &'static str,
    /// Joints in the skeleton (0 without one).
    pub joints: usize,
    /// Meshes with their LODs.
    pub meshes: Vec<MeshOut>,
    /// Clips as written.
    pub clips: Vec<ClipOut>,
    /// One entry per `--anim` file.
    pub motions: Vec<MotionReport>,
    /// Clips made by `--clips` (empty without it).
    pub cuts: Vec<String>,
    /// What `--at`/`--mask` did to each clip (empty without them).
    pub splits: Vec<SplitReport>,
    /// Every diagnostic raised on the way: importer, mapping, retargeting.
    pub diagnostics: Vec<DiagnosticReport>,
    /// PNG files written beside the output for the textures the source carried (Half-Life).
    pub textures: Vec<String>,
}

/// One mesh of the output.
#[derive(Debug, Serialize)]
pub struct MeshOut {
    /// Mesh name.
    pub name: String,
    /// Vertices of LOD 0.
    pub vertices: usize,
    /// Triangles of LOD 0.
    pub triangles: usize,
    /// Generated LODs, most detailed first (same fields as `inspect`).
    pub lods: Vec<LodReport>,
    /// LOD levels asked for and not written, and why.
    pub lods_not_built: Vec<NotBuiltReport>,
}

/// A LOD level that was asked for and not written (instead of a copy of the level before it).
#[derive(Debug, Serialize)]
pub struct NotBuiltReport {
    /// The level it would have had.
    pub level: usize,
    /// Requested fraction of LOD 0's triangles.
    pub target_ratio: f32,
    /// Triangles of the level it would have been simplified from.
    pub previous_triangles: usize,
    /// Triangles simplification stopped at; `null` when it was not attempted.
    pub reached_triangles: Option<usize>,
    /// `error-limit`, `no-collapse` or `previous-not-built`.
    pub reason: &'static str,
}

/// One clip of the output.
#[derive(Debug, Serialize)]
pub struct ClipOut {
    /// Clip name.
    pub name: String,
    /// Duration, seconds.
    pub duration: f32,
    /// Nominal frames per second.
    pub sample_rate: f32,
    /// Distinct key times.
    pub key_times: usize,
    /// Key counts.
    pub keys: KeyCounts,
    /// Number of joints the clip drives.
    pub driven_joints: usize,
    /// What compressing the clip reached; `null` with `--no-compress`.
    pub compression: Option<ClipCompressionReport>,
}
