//! sinew-scene is the editable, in-memory asset model that importers produce and the pipeline consumes:
//! a [`Scene`] holds one skeleton, meshes, materials and clips whose keys are stored per joint *name*.
//!
//! It sits between the importers (`sinew-import`, bytes to Scene) and the pipeline (`sinew-pipeline`:
//! mapping, splitting, LODs, compression, compiling to `.sinew`, baking). Types that the runtime already
//! defines ([`Skeleton`], [`Lod`], [`TrackCurves`]) are reused from `sinew-core` rather than copied.
//!
//! Conventions every importer follows:
//! - Units and axes are the source's; nothing is rescaled or re-oriented on import.
//! - Clip curves hold *absolute* local transforms (not differences from the bind pose), linearly
//!   interpolated; importers turn step, cubic or Hermite source curves into linear keys themselves.
//! - Mesh joint indices refer to the scene skeleton's joint order.
//! - Every vertex of a mesh carries one normal and, when the source has them, one UV; vertices are split
//!   where the source gives one position several normals or UVs, and `source_vertex` maps back.

pub use sinew_core::format::{Axes, Axis};
use sinew_core::{Clip, ClipError, Lod, Skeleton, TrackCurves};

pub use sinew_core;

/// The file format a scene came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SourceFormat {
    /// Milkshape 3D `.ms3d`.
    Ms3d,
    /// glTF 2.0 (`.gltf` or `.glb`).
    Gltf,
    /// Wavefront `.obj`.
    Obj,
    /// Biovision `.bvh`.
    Bvh,
    /// sinew's own `.sinew`.
    Sinew,
    /// Half-Life (GoldSrc) compiled model `.mdl`, version 10.
    Mdl,
    /// Half-Life StudioMDL data `.smd`.
    Smd,
    /// Half-Life model source `.qc` (with the SMD files it names).
    Qc,
}

impl SourceFormat {
    /// The format's up axis and the way its models face (docs/formats/): glTF defines Y up, facing
    /// +Z; MS3D, OBJ and BVH follow the same convention. Half-Life models (MDL, QC) are Z up and face
    /// +X as the engine plays their sequences, while their bind pose is the reference as modelled,
    /// facing -Y (studiomdl turns every sequence by 90 degrees about Z, never the reference); an SMD
    /// alone is not turned: Z up, facing -Y. `None` for `.sinew`, whose file states its own.
    pub fn axes(self) -> Option<Axes> {
        let hl = |forward, bind_forward| Axes {
            up: Axis::PosZ,
            forward,
            bind_forward,
        };
        match self {
            SourceFormat::Ms3d | SourceFormat::Gltf | SourceFormat::Obj | SourceFormat::Bvh => {
                Some(Axes::Y_UP)
            }
            SourceFormat::Mdl | SourceFormat::Qc => Some(hl(Axis::PosX, Axis::NegY)),
            SourceFormat::Smd => Some(hl(Axis::NegY, Axis::NegY)),
            SourceFormat::Sinew => None,
        }
    }

    /// Short lowercase name, as reports print it.
    pub fn name(self) -> &'static str {
        match self {
            SourceFormat::Ms3d => "ms3d",
            SourceFormat::Gltf => "gltf",
            SourceFormat::Obj => "obj",
            SourceFormat::Bvh => "bvh",
            SourceFormat::Sinew => "sinew",
            SourceFormat::Mdl => "mdl",
            SourceFormat::Smd => "smd",
            SourceFormat::Qc => "qc",
        }
    }
}

/// How serious a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Level {
    /// A decision or fact worth reporting (which convention was chosen, what was skipped on purpose).
    Info,
    /// Something was wrong or lossy but the import went on.
    Warning,
}

/// A message an importer or pipeline step raised about the input.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    /// Severity.
    pub level: Level,
    /// Stable, kebab-case identifier scripts can match on (e.g. `ms3d-position-keys`).
    pub code: String,
    /// One human sentence.
    pub message: String,
    /// Named figures behind the message, in a fixed order (e.g. measurements behind a decision).
    pub figures: Vec<(String, f64)>,
}

impl Diagnostic {
    /// A warning without figures.
    pub fn warning(code: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            level: Level::Warning,
            code: code.into(),
            message: message.into(),
            figures: Vec::new(),
        }
    }
    /// An informational note without figures.
    pub fn info(code: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            level: Level::Info,
            code: code.into(),
            message: message.into(),
            figures: Vec::new(),
        }
    }
    /// Adds a named figure.
    pub fn with_figure(mut self, name: impl Into<String>, value: f64) -> Self {
        self.figures.push((name.into(), value));
        self
    }
}

/// A material, referenced by name from submeshes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Material {
    /// Unique name within the scene.
    pub name: String,
    /// Base colour RGBA, linear.
    pub base_color: [f32; 4],
    /// Path or URI of the colour texture as the source wrote it, if any.
    pub texture: Option<String>,
}

/// A texture image carried in the source (Half-Life models embed theirs), as 8-bit RGBA rows from the
/// top. Writers put it beside the output as PNG; a material names it in `texture`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Image {
    /// The name materials use for it (the source's texture name, e.g. `skin.bmp`).
    pub name: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 4` bytes, RGBA, rows from the top.
    pub rgba: Vec<u8>,
}

/// A generated level of detail and what the simplifier reached.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GeneratedLod {
    /// The simplified geometry.
    pub lod: Lod,
    /// Requested fraction of LOD 0's triangles.
    pub target_ratio: f32,
    /// Fraction of LOD 0's triangles actually kept.
    pub reached_ratio: f32,
    /// Simplifier error relative to the mesh extent.
    pub error_relative: f32,
    /// Simplifier error in model units.
    pub error_model: f32,
    /// True when an error limit was given and it stopped the simplifier before the target.
    pub stopped_by_error_limit: bool,
    /// True when the level could only be built by letting collapses cross UV seams (some of its
    /// triangles may join two UV charts); not stored in `.sinew` files.
    pub uv_seams_opened: bool,
}

/// Why a LOD level was not built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NotBuiltReason {
    /// Simplification stopped before removing half of the triangles this level asks of the
    /// previous one, because of the error limit given.
    ErrorLimit,
    /// Simplification stopped before removing half of the triangles this level asks of the
    /// previous one: no collapse was left that the simplifier may make (UV and material seams
    /// and locked vertices hold the rest).
    NoCollapse,
    /// An earlier level was not built (each level is simplified from the one before).
    PreviousNotBuilt,
}

/// A LOD level that was asked for and not written, instead of a copy of the level before it.
#[derive(Debug, Clone, PartialEq)]
pub struct NotBuiltLod {
    /// The level it would have had (1 for the first generated LOD).
    pub level: usize,
    /// Requested fraction of LOD 0's triangles.
    pub target_ratio: f32,
    /// Triangles of the level it would have been simplified from.
    pub previous_triangles: usize,
    /// Triangles simplification stopped at (`None` when it was not attempted).
    pub reached_triangles: Option<usize>,
    /// Why it was not built.
    pub reason: NotBuiltReason,
}

/// A mesh: LOD 0 as imported, the map back to the source's vertices, and generated LODs.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    /// Mesh name (group, object or glTF mesh name).
    pub name: String,
    /// The imported geometry. `joints`/`weights` are empty for a static mesh.
    pub geometry: Lod,
    /// For each vertex of `geometry`, the index of the source file's vertex it came from.
    pub source_vertex: Vec<u32>,
    /// Number of vertices in the source file's own vertex list for this mesh.
    pub source_vertex_count: u32,
    /// Generated lower-detail versions, most detailed first.
    pub lods: Vec<GeneratedLod>,
    /// Levels asked for that the LOD builder did not write (`lods` holds the levels before the
    /// first of them); not stored in `.sinew` files.
    pub lods_not_built: Vec<NotBuiltLod>,
}

impl Mesh {
    /// A mesh whose vertices are the source's own, one for one and in order (`source_vertex` the
    /// identity), with no LODs yet.
    pub fn unsplit(name: impl Into<String>, geometry: Lod) -> Mesh {
        let n = geometry.positions.len() as u32;
        Mesh {
            name: name.into(),
            geometry,
            source_vertex: (0..n).collect(),
            source_vertex_count: n,
            lods: Vec::new(),
            lods_not_built: Vec::new(),
        }
    }
}

/// An animation clip as importers produce it: linear curves per joint name, absolute local transforms.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SceneClip {
    /// Clip name (unique within a scene).
    pub name: String,
    /// Duration, seconds; at least the last key time.
    pub duration: f32,
    /// Nominal frames per second of the source.
    pub sample_rate: f32,
    /// Whether the clip loops.
    pub looping: bool,
    /// Whether the curves are differences from a reference pose.
    pub additive: bool,
    /// One entry per driven joint name.
    pub tracks: Vec<TrackCurves>,
}

impl SceneClip {
    /// The runtime clip of these curves ([`Clip::from_curves`]).
    pub fn to_clip(&self) -> Result<Clip, ClipError> {
        Clip::from_curves(
            self.name.clone(),
            self.duration,
            self.sample_rate,
            self.looping,
            self.additive,
            self.tracks.clone(),
        )
    }
}

/// A named per-joint weight mask: `(joint name, weight)` pairs, unlisted joints weigh 0.
pub use sinew_core::format::Mask;

/// Game data a source carries beyond skeleton, meshes and clips (see [`sinew_core::format::game`]).
pub use sinew_core::format::game::{self, GameData};

/// An imported asset: at most one skeleton, any number of meshes and clips.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The format the scene was read from.
    pub source_format: SourceFormat,
    /// The skeleton, if the source has one.
    pub skeleton: Option<Skeleton>,
    /// Meshes; joint indices refer to `skeleton`.
    pub meshes: Vec<Mesh>,
    /// Materials referenced by name from submeshes.
    pub materials: Vec<Material>,
    /// Clips; their tracks name joints, which need not all exist in `skeleton`.
    pub clips: Vec<SceneClip>,
    /// Everything the importer and later steps noticed.
    pub diagnostics: Vec<Diagnostic>,
    /// Named joint masks (from `split` or `--mask`), carried into the `.sinew` MASK section.
    pub masks: Vec<Mask>,
    /// Texture images the source carried (Half-Life); materials name them.
    pub images: Vec<Image>,
    /// Game data kept from the source (attachments, hit boxes, events...), carried into `GAME`.
    pub game: GameData,
    /// Up and facing axes of the source ([`SourceFormat::axes`]), carried into `AXES`.
    pub axes: Option<Axes>,
}

impl Scene {
    /// An empty scene of the given source format.
    pub fn new(source_format: SourceFormat) -> Self {
        Self {
            source_format,
            skeleton: None,
            meshes: Vec::new(),
            materials: Vec::new(),
            clips: Vec::new(),
            diagnostics: Vec::new(),
            masks: Vec::new(),
            images: Vec::new(),
            game: GameData::default(),
            axes: source_format.axes(),
        }
    }

    /// Diagnostics at warning level.
    pub fn warnings(&self) -> impl Iterator<Item = &Diagnostic> {
        self.diagnostics
            .iter()
            .filter(|d| d.level == Level::Warning)
    }

    /// The clip with this name.
    pub fn clip(&self, name: &str) -> Option<&SceneClip> {
        self.clips.iter().find(|c| c.name == name)
    }
}
