//! Argument definitions (clap derive). One struct per subcommand, named after it.

use clap::{Args, Parser, ValueEnum};
use std::path::PathBuf;

/// `cmd` with each subcommand added, its arguments (`Args::$augment`) deferred until it is parsed;
/// `about` set before the deferral too, since the parent's help lists the subcommand unbuilt.
macro_rules! deferred_subcommands {
    ($cmd:expr, $augment:ident, $(($args:ty, $name:literal, $about:literal, $after:literal))*) => {
        $cmd$(.subcommand(
            clap::Command::new($name).about($about).after_help($after).defer(|c| {
                <$args as clap::Args>::$augment(c)
                    .about($about)
                    .long_about(None)
                    .after_help($after)
            }),
        ))*
    };
}

/// The subcommand enum `Command`, its parsing and its clap definition, each subcommand's arguments
/// deferred until it is parsed: `Variant(Args) = "name", "about", "after_help";` per subcommand,
/// in the order help lists them.
macro_rules! lazy_subcommands {
    ($($variant:ident($args:ty) = $name:literal, $about:literal, $after:literal;)*) => {
        /// The subcommands.
        #[derive(Debug)]
        pub enum Command {
            $(#[doc = $about] $variant($args),)*
        }

        impl clap::FromArgMatches for Command {
            fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
                Self::from_arg_matches_mut(&mut m.clone())
            }
            fn from_arg_matches_mut(m: &mut clap::ArgMatches) -> Result<Self, clap::Error> {
                match m.remove_subcommand() {
                    $(Some((name, mut sub)) if name == $name => Ok(Self::$variant(
                        <$args as clap::FromArgMatches>::from_arg_matches_mut(&mut sub)?,
                    )),)*
                    Some((name, _)) => Err(clap::Error::raw(
                        clap::error::ErrorKind::InvalidSubcommand,
                        format!("the subcommand '{name}' wasn't recognized"),
                    )),
                    None => Err(clap::Error::raw(
                        clap::error::ErrorKind::MissingSubcommand,
                        "A subcommand is required but one was not provided.",
                    )),
                }
            }
            fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
                self.update_from_arg_matches_mut(&mut m.clone())
            }
            fn update_from_arg_matches_mut(
                &mut self,
                m: &mut clap::ArgMatches,
            ) -> Result<(), clap::Error> {
                *self = Self::from_arg_matches_mut(m)?;
                Ok(())
            }
        }

        impl clap::Subcommand for Command {
            fn augment_subcommands(cmd: clap::Command) -> clap::Command {
                deferred_subcommands!(cmd, augment_args, $(($args, $name, $about, $after))*)
            }
            fn augment_subcommands_for_update(cmd: clap::Command) -> clap::Command {
                deferred_subcommands!(
                    cmd,
                    augment_args_for_update,
                    $(($args, $name, $about, $after))*
                )
            }
            fn has_subcommand(name: &str) -> bool {
                [$($name),*].contains(&name)
            }
        }
    };
}

/// sinew: convert, inspect and check skeletal animation assets.
#[derive(Debug, Parser)]
#[command(
    name = "sinew",
    version,
    about = "Convert, inspect and check skeletal animation assets (MS3D, glTF, OBJ, BVH, .sinew)",
    after_help = "Examples:\n  sinew convert zombie.ms3d -o zombie.sinew\n  sinew convert models/*.glb --out-dir out/ --json > report.json\n  sinew inspect fixtures/biped.sinew\n  sinew map scientist.ms3d walk.bvh --write map.json\n\nExit codes: 0 success, 1 a check or one of several files failed, 2 bad input or usage.\nSee docs/cli.md."
)]
pub struct Cli {
    /// Options every command accepts.
    #[command(flatten)]
    pub global: GlobalArgs,
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// Options shared by every command.
#[derive(Debug, Args)]
pub struct GlobalArgs {
    /// Print the command's report as JSON on stdout (schema in docs/cli.md).
    #[arg(long, global = true)]
    pub json: bool,
    /// Print nothing on stderr except errors.
    #[arg(long, short, global = true)]
    pub quiet: bool,
}

// The subcommands. Each one's arguments are built only when that subcommand is parsed (clap's
// `Command::defer`): a process builds and matches `convert`'s arguments, not all ten commands'
// (0.11 ms of a cold process's 0.24, docs/performance.md, session 28). The derive would build all.
lazy_subcommands! {
    Inspect(InspectArgs) = "inspect",
        "Show what a file holds: skeleton tree, clips, meshes, LODs, diagnostics",
        "Examples:\n  sinew inspect fixtures/biped.sinew\n  sinew inspect zombie.ms3d --ms3d-position-keys viewer\n  sinew inspect Fox.glb --json | jq '.clips[].name'\n  sinew inspect walk.bvh --pose walk@0.5\n  sinew inspect walk.bvh --pose walk@0..1 --fps 10 --json";
    Convert(ConvertArgs) = "convert",
        "Convert models and motions to .sinew (one file, or many in parallel with --out-dir)",
        "Examples:\n  sinew convert zombie.ms3d -o zombie.sinew\n  sinew convert scientist.ms3d --anim walk.bvh --retarget --at \"Bip01 Spine\" -o scientist.sinew\n  sinew convert scientist.ms3d --clips idle=1-30,walk=31-60 --lod 0.5,0.25 -o scientist.sinew\n  sinew convert models/*.glb models/*.ms3d --out-dir out/ --jobs 4 --json > report.json\n\nExit codes: 0 all converted, 1 some files of a batch failed (all are listed), 2 bad input or usage.";
    Map(MapArgs) = "map",
        "Show how a motion's joints bind to a rig's joints, and save the mapping",
        "Examples:\n  sinew map fixtures/biped.sinew walk.bvh\n  sinew map scientist.ms3d walk.bvh --write map.json\n  sinew map scientist.ms3d walk.bvh --map map.json --json";
    Split(SplitArgs) = "split",
        "Split every clip into partial-body clips (upper/lower at joints, or named joint masks)",
        "Examples:\n  sinew split scientist.sinew --at \"Bip01 Spine\" -o scientist_split.sinew\n  sinew split biped.sinew --mask \"arms=Bip01 L UpperArm,Bip01 R UpperArm\" -o out.sinew";
    Lod(LodCmdArgs) = "lod",
        "Regenerate the LODs of a .sinew file",
        "Examples:\n  sinew lod scientist.sinew -o scientist.sinew --lod 0.6,0.3\n  sinew lod scientist.sinew -o scientist_nolod.sinew --lod none";
    Completions(CompletionsArgs) = "completions",
        "Print a shell completion script on stdout",
        "Examples:\n  sinew completions bash > ~/.local/share/bash-completion/completions/sinew\n  sinew completions zsh > ~/.zfunc/_sinew";
    Bake(BakeArgs) = "bake",
        "Bake a skinned vertex cache (EXR VAT, PC2 or MDD) with sinew-core, plus sidecar and OBJ",
        "Examples:\n  sinew bake fixtures/biped.sinew --clip walk --format exr -o walk.exr\n  sinew bake fixtures/biped.sinew --layer walk --layer wave@upper:0.8 --format exr -o crowd.exr\n  sinew bake CesiumMan.glb --format pc2 --vertex-order source -o man.pc2\n\nWrites OUT, its sidecar (<stem>-remap_info.json for EXR, OUT.json otherwise), OUT.obj and,\nfor EXR with --normals file, <stem>_normals.exr. Layout: docs/formats/vat.md.";
    Verify(VerifyArgs) = "verify",
        "Check a baked cache bit for bit against a re-bake through sinew-core (exit 1 on a difference)",
        "Examples:\n  sinew verify walk.exr --against fixtures/biped.sinew\n  sinew verify man.pc2 --against man.sinew --json";
    Export(ExportArgs) = "export",
        "Export to glTF 2.0 (.glb or .gltf): skeleton, skin, meshes, LODs, textures, every clip sampled",
        "Examples:\n  sinew export fixtures/biped.sinew -o biped.glb\n  sinew export man.mdl -o man.gltf\n  sinew export zombie.ms3d --lod 0.5,0.25 -o zombie.glb --json\n\nDecisions (axes, units, extras, MSFT_lod): docs/export.md.";
    Preview(PreviewArgs) = "preview",
        "Draw a contact sheet PNG: rest pose front and side with the skeleton, clip poses, LODs",
        "Examples:\n  sinew preview fixtures/biped.sinew -o biped.png\n  sinew preview man.mdl --clip walk --frames 8 -o walk.png\n  sinew preview zombie.ms3d --lod 0.5,0.25 --names -o zombie.png\n\nLayout and sizes: docs/cli.md.";
}

/// Import options shared by every command that reads source files.
#[derive(Debug, Args, Clone, Default)]
pub struct ImportArgs {
    /// MS3D: how position keys combine with the bind pose.
    #[arg(long, value_enum, default_value_t = PositionKeys::Auto, value_name = "RULE")]
    pub ms3d_position_keys: PositionKeys,
    /// glTF: index of the skin that becomes the skeleton (default: the first, with a note).
    #[arg(long, value_name = "N")]
    pub gltf_skin: Option<usize>,
    /// Half-Life: convert without a file the model names that is missing (a QC's SMD, an MDL's
    /// texture or sequence-group file), with a warning, instead of stopping with an error.
    #[arg(long)]
    pub allow_missing: bool,
}

/// `--ms3d-position-keys` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum PositionKeys {
    /// Milkshape's viewer: key rotated by the bind rotation, then added.
    Viewer,
    /// Key added in the parent's space.
    Parent,
    /// Decide per file.
    #[default]
    Auto,
}

/// `sinew inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The file to inspect (.ms3d, .gltf, .glb, .obj, .bvh, .sinew).
    pub file: PathBuf,
    /// Print the model-space transform of every joint at clip time TIME (seconds), or at every frame
    /// of START..END (both included), as the runtime computes it, instead of the file summary.
    #[arg(long, value_name = "CLIP@TIME|CLIP@START..END")]
    pub pose: Option<String>,
    /// Frame rate of a --pose range (default: the clip's sample rate).
    #[arg(long, value_name = "FPS", requires = "pose")]
    pub fps: Option<f32>,
    /// Import options.
    #[command(flatten)]
    pub import: ImportArgs,
}

/// `sinew completions`.
#[derive(Debug, Args)]
pub struct CompletionsArgs {
    /// The shell to write a completion script for.
    pub shell: clap_complete::Shell,
}

/// LOD options shared by `convert` and `lod`.
#[derive(Debug, Args, Clone)]
pub struct LodArgs {
    /// LOD ratios of LOD 0's triangles, decreasing (`0.5,0.25`), or `none` for no LODs.
    #[arg(long, value_name = "R1,R2|none", default_value = "0.5,0.25")]
    pub lod: String,
    /// Largest simplification error, relative to the mesh extent, accumulated along the chain
    /// (default: none; each LOD meets its triangle budget and reports the error it reached).
    #[arg(long, value_name = "E")]
    pub lod_max_error: Option<f32>,
    /// Influences per vertex kept in the lowest LOD (1 to 4).
    #[arg(long, value_name = "N", default_value_t = 4)]
    pub lod_influences: usize,
    /// Hold UV seams even on meshes whose materials have no texture (by default their UV seams do
    /// not hold: nothing draws them), for meshes to be textured later.
    #[arg(long)]
    pub lod_keep_uv_seams: bool,
}

/// Partial-body options shared by `convert` and `split`.
#[derive(Debug, Args, Clone, Default)]
pub struct SplitOpts {
    /// Split every clip into CLIP.upper (subtrees under JOINT) and CLIP.lower (repeatable).
    #[arg(long = "at", visible_alias = "split", value_name = "JOINT")]
    pub at: Vec<String>,
    /// Add CLIP.NAME holding only the tracks of the listed joints (repeatable).
    #[arg(long, value_name = "NAME=JOINT,...")]
    pub mask: Vec<String>,
}

/// Clip compression options shared by the commands that write `.sinew` (`convert`, `split`, `lod`).
#[derive(Debug, Args, Clone, Default)]
pub struct CompressArgs {
    /// Store clips as plain f32 keys (no quantization, no key reduction).
    #[arg(long, conflicts_with_all = ["tolerance", "error_distance"])]
    pub no_compress: bool,
    /// Largest allowed error, model units [default: 0.0005 x the skeleton's bind-pose extent].
    #[arg(long, value_name = "T")]
    pub tolerance: Option<f32>,
    /// Distance of the error points from their joint, model units [default: 0.05 x the extent].
    #[arg(long, value_name = "D")]
    pub error_distance: Option<f32>,
    /// How hard the clip encoder searches for small clips (every effort keeps the tolerance):
    /// `fast` tries fewer layouts and does not refine long clips' widths, `max` more (never
    /// larger than `default`); `max` also builds each LOD step the plain ways and keeps the
    /// closest (docs/lod.md).
    #[arg(long, value_enum, default_value_t = EffortArg::Default)]
    pub effort: EffortArg,
}

/// `--effort`: the clip encoder's search effort.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum EffortArg {
    /// One key-reduction budget, the smallest candidate refined: a few times faster.
    Fast,
    /// The default search.
    #[default]
    Default,
    /// More key budgets, segment lengths and refined candidates; slower, never larger; and the
    /// LOD builder's plain candidate builds.
    Max,
}

/// `sinew convert`.
#[derive(Debug, Args, Clone)]
pub struct ConvertArgs {
    /// Input files (.ms3d, .gltf, .glb, .obj, .bvh, .mdl, .smd, .qc, .sinew), or folders (with
    /// --out-dir): every model in a folder is converted, recognised by content.
    #[arg(required = true, value_name = "INPUT")]
    pub inputs: Vec<PathBuf>,
    /// Do not write the textures a model carries (Half-Life) as PNG files beside the output.
    #[arg(long)]
    pub no_textures: bool,
    /// Output file (exactly one input).
    #[arg(short, long, value_name = "OUT.sinew", conflicts_with = "out_dir")]
    pub output: Option<PathBuf>,
    /// Output directory, created when missing: each input becomes DIR/<stem>.sinew, and a folder's
    /// models keep their place in its tree (batch mode).
    #[arg(long, value_name = "DIR")]
    pub out_dir: Option<PathBuf>,
    /// Worker threads for batch mode (default: all cores).
    #[arg(long, short = 'j', value_name = "N")]
    pub jobs: Option<usize>,
    /// Add each step's wall time (import, each LOD, each clip's encode, write) to the report.
    #[arg(long)]
    pub timings: bool,
    /// Fail an input that raises any warning (nothing is written for it; a batch exits 1).
    #[arg(long)]
    pub strict: bool,
    /// Keep the outputs of inputs whose files, options and sinew version are unchanged since they
    /// were written (a record in OUT-DIR/.sinew-incremental/); redo the rest.
    #[arg(long)]
    pub incremental: bool,
    /// Also write a static HTML page (one file, no server or network needed) with a row per input:
    /// a picture of its output, joints, meshes, triangles, LODs, clips, textures, warnings, errors.
    #[arg(long, value_name = "OUT.html")]
    pub report: Option<PathBuf>,
    /// Motion file whose clips are bound to the model's skeleton by joint name (repeatable).
    #[arg(long, value_name = "FILE")]
    pub anim: Vec<PathBuf>,
    /// Mapping file (from `sinew map --write`) used for every --anim instead of automatic matching.
    #[arg(long, value_name = "map.json")]
    pub map: Option<PathBuf>,
    /// Retarget --anim motion: transfer rotations as changes from the motion's rest pose.
    #[arg(long)]
    pub retarget: bool,
    /// With --retarget: factor for the root's translation instead of the ratio of hip heights.
    #[arg(long, value_name = "K", requires = "retarget")]
    pub root_scale: Option<f32>,
    /// Cut the model's single timeline into named clips by frame (`walk=1-30,run=31-50`).
    #[arg(long, value_name = "NAME=A-B,...")]
    pub clips: Option<String>,
    /// Partial-body clips.
    #[command(flatten)]
    pub split: SplitOpts,
    /// LOD generation.
    #[command(flatten)]
    pub lod: LodArgs,
    /// Clip compression.
    #[command(flatten)]
    pub compress: CompressArgs,
    /// Import options.
    #[command(flatten)]
    pub import: ImportArgs,
}

/// `sinew map`.
#[derive(Debug, Args)]
pub struct MapArgs {
    /// The rig: the model whose skeleton the motion should drive.
    pub rig: PathBuf,
    /// The motion file (BVH, glTF, MS3D, .sinew).
    pub motion: PathBuf,
    /// Check and show this mapping file instead of matching automatically.
    #[arg(long, value_name = "map.json")]
    pub map: Option<PathBuf>,
    /// Save the mapping as a file for `convert --map` (edit it freely).
    #[arg(long, value_name = "map.json")]
    pub write: Option<PathBuf>,
    /// Draw the two skeletons side by side with a line per matched pair, as PNG.
    #[arg(long, value_name = "OUT.png")]
    pub png: Option<PathBuf>,
    /// The up axis of both files for --png.
    #[arg(long, value_enum, default_value_t = UpArg::Auto)]
    pub up: UpArg,
    /// Import options.
    #[command(flatten)]
    pub import: ImportArgs,
}

/// `sinew split`.
#[derive(Debug, Args)]
pub struct SplitArgs {
    /// The file whose clips are split (any supported input; usually .sinew).
    pub file: PathBuf,
    /// Output .sinew file.
    #[arg(short, long, value_name = "OUT.sinew")]
    pub output: PathBuf,
    /// Where to split.
    #[command(flatten)]
    pub split: SplitOpts,
    /// Clip compression.
    #[command(flatten)]
    pub compress: CompressArgs,
    /// Import options.
    #[command(flatten)]
    pub import: ImportArgs,
}

/// `sinew lod`.
#[derive(Debug, Args)]
pub struct LodCmdArgs {
    /// The file whose LODs are regenerated (usually .sinew).
    pub file: PathBuf,
    /// Output .sinew file (may be the input itself).
    #[arg(short, long, value_name = "OUT.sinew")]
    pub output: PathBuf,
    /// LOD options.
    #[command(flatten)]
    pub lod: LodArgs,
    /// Clip compression.
    #[command(flatten)]
    pub compress: CompressArgs,
    /// Import options.
    #[command(flatten)]
    pub import: ImportArgs,
}

/// `--format` of `sinew bake`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CacheFormatArg {
    /// OpenEXR vertex animation texture.
    Exr,
    /// PC2 point cache.
    Pc2,
    /// MDD point cache.
    Mdd,
}

/// `--vertex-order` of `sinew bake`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum VertexOrderArg {
    /// sinew's split vertex order.
    Split,
    /// The source file's vertex order (LOD 0).
    Source,
}

/// `--vat-encoding` of `sinew bake`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum VatEncodingArg {
    /// Absolute positions, f32 (lossless).
    AbsoluteF32,
    /// Offsets from the bind pose, f16.
    OffsetF16,
    /// Offsets from the bind pose, f32 (lossless).
    OffsetF32,
}

/// `--normals` of `sinew bake`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum NormalsArg {
    /// Layer `N` of the position file.
    Layer,
    /// A second file `<stem>_normals.exr`.
    File,
    /// No normals.
    None,
}

/// `sinew bake`.
#[derive(Debug, Args)]
pub struct BakeArgs {
    /// The file to bake (.sinew, or any source file sinew imports).
    pub file: PathBuf,
    /// Clip to bake (repeatable; default: every clip in file order).
    #[arg(long, value_name = "NAME")]
    pub clip: Vec<String>,
    /// Layer of a layered bake: CLIP[@MASK][:WEIGHT] (repeatable).
    #[arg(long, value_name = "SPEC")]
    pub layer: Vec<String>,
    /// Frames per second (default: the first clip's sample rate).
    #[arg(long, value_name = "N")]
    pub fps: Option<f32>,
    /// Cache format.
    #[arg(long, value_enum)]
    pub format: CacheFormatArg,
    /// Output cache file.
    #[arg(short = 'o', long = "output", value_name = "OUT")]
    pub output: PathBuf,
    /// Which meshes to bake.
    #[command(flatten)]
    pub body: BodyArgs,
    /// LOD to bake.
    #[arg(long, default_value_t = 0, value_name = "K")]
    pub lod: usize,
    /// Vertex order of the cache.
    #[arg(long, value_enum, default_value_t = VertexOrderArg::Split)]
    pub vertex_order: VertexOrderArg,
    /// EXR: largest texture width; wider meshes wrap into more rows per frame.
    #[arg(long, default_value_t = 4096, value_name = "W")]
    pub max_width: usize,
    /// EXR: how positions are stored.
    #[arg(long, value_enum, default_value_t = VatEncodingArg::OffsetF16)]
    pub vat_encoding: VatEncodingArg,
    /// EXR: where normals go.
    #[arg(long, value_enum, default_value_t = NormalsArg::File)]
    pub normals: NormalsArg,
    /// Also draw frames of the written cache (read back from its bytes) as PNG.
    #[arg(long, value_name = "OUT.png")]
    pub preview: Option<PathBuf>,
    /// The up axis for --preview.
    #[arg(long, value_enum, default_value_t = UpArg::Auto)]
    pub up: UpArg,
    /// Import options (source files).
    #[command(flatten)]
    pub import: ImportArgs,
}

/// `sinew verify`.
#[derive(Debug, Args)]
pub struct VerifyArgs {
    /// The cache to check (.exr, .pc2 or .mdd, with its sidecar beside it).
    pub cache: PathBuf,
    /// The file it was baked from.
    #[arg(long, value_name = "FILE")]
    pub against: PathBuf,
    /// Import options (source files).
    #[command(flatten)]
    pub import: ImportArgs,
}

/// `sinew export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The file to export (any supported input).
    pub file: PathBuf,
    /// Output file: `.glb` (binary) or `.gltf` (JSON with the buffer embedded).
    #[arg(short, long, value_name = "OUT.glb|OUT.gltf")]
    pub output: PathBuf,
    /// Generate LODs first (`0.5,0.25`), or `none` to drop them [default: keep the file's own].
    #[arg(long, value_name = "R1,R2|none")]
    pub lod: Option<String>,
    /// Which meshes make the model in the default scene.
    #[command(flatten)]
    pub body: BodyArgs,
    /// Also write every other mesh and every LOD, each in a glTF scene of its own (scene 0 stays the
    /// model at LOD 0; LODs behind MSFT_lod). Blender 3.4 imports all scenes into one.
    #[arg(long)]
    pub variants: bool,
    /// Import options.
    #[command(flatten)]
    pub import: ImportArgs,
}

/// Which meshes make the model (`bake`, `preview`, `export`); default: the default body.
#[derive(Debug, Args, Clone, Default)]
pub struct BodyArgs {
    /// Body number as Half-Life model viewers count it (each body group's choice; 0 is the default
    /// body). Default: the default body (submodel 0 of every body group; every mesh without groups).
    #[arg(long, value_name = "N", conflicts_with = "mesh")]
    pub body: Option<u64>,
    /// These meshes instead, by index or name, comma separated (`0,3` or `heads/einstein`).
    #[arg(long, value_name = "N|NAME,...")]
    pub mesh: Option<String>,
}

/// `--up` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum UpArg {
    /// Z for Half-Life sources (.mdl, .smd, .qc, or .sinew with game data), else Y.
    #[default]
    Auto,
    /// +Y is up (glTF, MS3D, BVH, OBJ).
    Y,
    /// +Z is up (Half-Life).
    Z,
}

/// `sinew preview`.
#[derive(Debug, Args)]
pub struct PreviewArgs {
    /// The file to draw (any supported input).
    pub file: PathBuf,
    /// Output PNG.
    #[arg(short, long, value_name = "OUT.png")]
    pub output: PathBuf,
    /// Draw only this clip's strip.
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Poses per clip strip (1 to 32).
    #[arg(long, value_name = "N", default_value_t = 6)]
    pub frames: usize,
    /// Write joint names beside the joints of the front rest view.
    #[arg(long)]
    pub names: bool,
    /// The model's up axis.
    #[arg(long, value_enum, default_value_t = UpArg::Auto)]
    pub up: UpArg,
    /// Generate LODs first (`0.5,0.25`), or `none` to drop them [default: keep the file's own].
    #[arg(long, value_name = "R1,R2|none")]
    pub lod: Option<String>,
    /// Which meshes to draw.
    #[command(flatten)]
    pub body: BodyArgs,
    /// Import options.
    #[command(flatten)]
    pub import: ImportArgs,
}

#[cfg(test)]
mod tests {
    use super::{Cli, Command};
    use clap::{CommandFactory, Parser, Subcommand};

    #[test]
    fn the_deferred_definitions_are_consistent_and_parse_each_subcommand() {
        // Builds every subcommand (the deferred arguments included) and runs clap's own checks.
        Cli::command().debug_assert();
        let names = [
            "inspect",
            "convert",
            "map",
            "split",
            "lod",
            "completions",
            "bake",
            "verify",
            "export",
            "preview",
        ];
        let listed: Vec<String> = Cli::command()
            .get_subcommands()
            .map(|c| c.get_name().to_owned())
            .collect();
        assert_eq!(listed, names);
        assert!(names.iter().all(|n| Command::has_subcommand(n)));
        assert!(!Command::has_subcommand("help"));
        let cli =
            Cli::try_parse_from(["sinew", "--json", "convert", "a.glb", "-o", "b.sinew"]).unwrap();
        assert!(cli.global.json);
        match cli.command {
            Command::Convert(a) => {
                assert_eq!(a.inputs, [std::path::PathBuf::from("a.glb")]);
            }
            other => panic!("{other:?}"),
        }
        let cli = Cli::try_parse_from(["sinew", "map", "rig.ms3d", "walk.bvh", "-q"]).unwrap();
        assert!(cli.global.quiet);
        assert!(matches!(cli.command, Command::Map(ref m) if m.motion.ends_with("walk.bvh")));
        let e = Cli::try_parse_from(["sinew", "nope"]).unwrap_err();
        assert_eq!(e.kind(), clap::error::ErrorKind::InvalidSubcommand);
    }
}
