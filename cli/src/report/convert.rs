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
    /// Inputs whose outputs were kept from an earlier run (`--incremental`).
    pub reused: usize,
    /// Inputs that failed.
    pub failed: usize,
    /// Warnings over every input (converted, reused or failed by `--strict`).
    pub warnings: usize,
    /// Inputs with at least one warning.
    pub inputs_with_warnings: usize,
    /// Warnings by code, over every input.
    pub warning_codes: std::collections::BTreeMap<String, usize>,
    /// Whether `--strict` was given: any warning fails its input.
    pub strict: bool,
    /// Companion files whose model is missing (each fails the batch).
    pub orphans: usize,
    /// With `--incremental`: the record and what was made of it; `null` without.
    pub incremental: Option<IncrementalReport>,
    /// One entry per input, in command-line order.
    pub files: Vec<FileReport>,
    /// Every file a folder walk passed over without converting it, by path, with the reason.
    pub skipped: Vec<SkippedReport>,
}

/// What `--incremental` made of the record it found.
#[derive(Debug, Clone, Serialize)]
pub struct IncrementalReport {
    /// The record's folder (`OUT-DIR/.sinew-incremental`).
    pub record: String,
    /// `used` (records read and checked per input), `new` (no record yet: every input converted),
    /// `ignored` (a record was corrupt or not sinew's: a full run).
    pub state: &'static str,
    /// Why the record was ignored; `null` otherwise.
    pub reason: Option<String>,
}

/// A file a folder walk passed over.
#[derive(Debug, Clone, Serialize)]
pub struct SkippedReport {
    /// The file.
    pub file: String,
    /// `not-a-model`, `companion` (read by `model`) or `orphaned-companion` (a Half-Life texture or
    /// sequence-group file that no model reads; fails the batch).
    pub reason: &'static str,
    /// For `companion`: the input that reads it; else `null`.
    pub model: Option<String>,
    /// The reason in words.
    pub message: String,
}

/// One input of a convert run.
#[derive(Debug, Serialize)]
pub struct FileReport {
    /// The input path as given.
    pub input: String,
    /// The output path.
    pub output: String,
    /// `converted`, `reused` (kept from an earlier run, `--incremental`) or `failed`.
    pub status: &'static str,
    /// The error (one line) when failed, else `null`.
    pub error: Option<String>,
    /// Warnings among the diagnostics (0 when the input failed before any).
    pub warnings: usize,
    /// What was written (absent when failed; present for a failure by `--strict`, which writes
    /// nothing).
    #[serde(flatten)]
    pub details: Option<OutputDetails>,
    /// For `reused`: the same fields as recorded when the output was written.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub recorded: Option<RecordedFields>,
}

/// The report fields recorded for a kept output, in their order, each exactly as the JSON text it
/// was written as (so a number prints back digit for digit).
#[derive(Debug)]
pub struct RecordedFields(pub Vec<(String, Box<serde_json::value::RawValue>)>);

impl Serialize for RecordedFields {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

impl RecordedFields {
    /// The fields of a JSON object's text, in order; `None` when it is not an object.
    pub fn parse(text: &str) -> Option<RecordedFields> {
        struct Fields;
        impl<'de> serde::de::Visitor<'de> for Fields {
            type Value = RecordedFields;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a JSON object")
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<RecordedFields, A::Error> {
                let mut out = Vec::new();
                while let Some(entry) = map.next_entry()? {
                    out.push(entry);
                }
                Ok(RecordedFields(out))
            }
        }
        let mut de = serde_json::Deserializer::from_str(text);
        let fields = serde::Deserializer::deserialize_map(&mut de, Fields).ok()?;
        de.end().ok()?;
        Some(fields)
    }

    /// One field, decoded.
    pub fn get(&self, key: &str) -> Option<serde_json::Value> {
        let (_, raw) = self.0.iter().find(|(k, _)| k == key)?;
        serde_json::from_str(raw.get()).ok()
    }
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
    /// Wall times of the steps (`convert --timings` only; absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timings: Option<Timings>,
}

/// Wall times of one input's conversion, milliseconds (`convert --timings`). The LODs and the clip
/// encoder run at the same time, and meshes and clips each in parallel, so these times overlap:
/// `total_ms` is the input's whole conversion.
#[derive(Debug, Clone, Serialize, Default)]
pub struct Timings {
    /// Reading and importing the input (and its companions).
    pub import_ms: f64,
    /// Binding `--anim` motions, `--clips` cuts and partial-body splits.
    pub prepare_ms: f64,
    /// Per mesh: its LOD work.
    pub lods: Vec<MeshTimings>,
    /// Per clip: its encoding (compression); empty with `--no-compress`.
    pub clips: Vec<ClipTiming>,
    /// Writing textures beside the output.
    pub textures_ms: f64,
    /// Compiling the scene, encoding the `.sinew` bytes and writing the file.
    pub write_ms: f64,
    /// The whole conversion of this input.
    pub total_ms: f64,
}

/// One mesh's LOD wall times.
#[derive(Debug, Clone, Serialize)]
pub struct MeshTimings {
    /// Mesh name.
    pub mesh: String,
    /// Vertex-cache optimisation of LOD 0.
    pub optimize_ms: f64,
    /// Each LOD level tried (simplification, repair, error measurement), LOD 1 first: the
    /// generated ones, then a level not built when simplification was tried for it.
    pub levels_ms: Vec<f64>,
}

/// One clip's encoding wall time.
#[derive(Debug, Clone, Serialize)]
pub struct ClipTiming {
    /// Clip name.
    pub clip: String,
    /// Compression of the clip.
    pub encode_ms: f64,
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

impl FileReport {
    /// `(code, message)` of each warning, from what was converted or what was recorded.
    pub fn warning_list(&self) -> Vec<(String, String)> {
        if let Some(d) = &self.details {
            return warning_pairs(d);
        }
        let recorded = self.recorded.as_ref().and_then(|r| r.get("diagnostics"));
        let list = recorded.as_ref().and_then(|d| d.as_array());
        list.into_iter()
            .flatten()
            .filter(|x| x.get("level").and_then(|l| l.as_str()) == Some("warning"))
            .map(|x| {
                let text = |k: &str| x.get(k).and_then(|v| v.as_str()).unwrap_or("").to_string();
                (text("code"), text("message"))
            })
            .collect()
    }
}

impl ConvertReport {
    /// The report of a run: the per-input entries, the files the walk passed over, and the
    /// summary counted from them.
    pub fn new(
        files: Vec<FileReport>,
        skipped: Vec<SkippedReport>,
        strict: bool,
        incremental: Option<IncrementalReport>,
    ) -> ConvertReport {
        let count = |s: &str| files.iter().filter(|f| f.status == s).count();
        let mut warning_codes = std::collections::BTreeMap::new();
        for f in &files {
            for (code, _) in f.warning_list() {
                *warning_codes.entry(code).or_insert(0) += 1;
            }
        }
        ConvertReport {
            inputs: files.len(),
            converted: count("converted"),
            reused: count("reused"),
            failed: count("failed"),
            warnings: files.iter().map(|f| f.warnings).sum(),
            inputs_with_warnings: files.iter().filter(|f| f.warnings > 0).count(),
            warning_codes,
            strict,
            orphans: skipped
                .iter()
                .filter(|s| s.reason == "orphaned-companion")
                .count(),
            incremental,
            files,
            skipped,
        }
    }
}

/// `(code, message)` of each warning of a converted input.
pub fn warning_pairs(d: &OutputDetails) -> Vec<(String, String)> {
    d.diagnostics
        .iter()
        .filter(|x| x.level == "warning")
        .map(|x| (x.code.clone(), x.message.clone()))
        .collect()
}

/// The one-line error of an input failed by `--strict`: how many warnings, and the first.
pub fn strict_error(input: &str, warnings: &[(String, String)]) -> String {
    let n = warnings.len();
    let first = warnings
        .first()
        .map(|(code, message)| format!(", the first [{code}] {message}"))
        .unwrap_or_default();
    let s = if n == 1 { "" } else { "s" };
    format!("{input}: --strict: {n} warning{s}{first}")
}
