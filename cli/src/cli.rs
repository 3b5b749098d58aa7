//! Argument definitions (clap derive). One struct per subcommand, named after it.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// sinew: convert, inspect and check skeletal animation assets.
#[derive(Debug, Parser)]
#[command(
    name = "sinew",
    version,
    about = "Convert, inspect and check skeletal animation assets (MS3D, glTF, OBJ, BVH, .sinew)",
    after_help = "Examples:\n  sinew inspect fixtures/biped.sinew\n  sinew inspect walk.bvh --json > walk.json\n\nExit codes: 0 success, 1 a check or one of several files failed, 2 bad input or usage.\nSee docs/cli.md."
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

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Show what a file holds: skeleton tree, clips, meshes, LODs, diagnostics.
    #[command(
        after_help = "Examples:\n  sinew inspect fixtures/biped.sinew\n  sinew inspect zombie.ms3d --ms3d-position-keys viewer\n  sinew inspect Fox.glb --json | jq '.clips[].name'"
    )]
    Inspect(InspectArgs),
    /// Print a shell completion script on stdout.
    #[command(
        after_help = "Examples:\n  sinew completions bash > ~/.local/share/bash-completion/completions/sinew\n  sinew completions zsh > ~/.zfunc/_sinew"
    )]
    Completions(CompletionsArgs),
}

/// Import options shared by every command that reads source files.
#[derive(Debug, Args, Clone)]
pub struct ImportArgs {
    /// MS3D: how position keys combine with the bind pose.
    #[arg(long, value_enum, default_value_t = PositionKeys::Auto, value_name = "RULE")]
    pub ms3d_position_keys: PositionKeys,
    /// glTF: index of the skin that becomes the skeleton (default: the first, with a note).
    #[arg(long, value_name = "N")]
    pub gltf_skin: Option<usize>,
}

/// `--ms3d-position-keys` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PositionKeys {
    /// Milkshape's viewer: key rotated by the bind rotation, then added.
    Viewer,
    /// Key added in the parent's space.
    Parent,
    /// Decide per file.
    Auto,
}

/// `sinew inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The file to inspect (.ms3d, .gltf, .glb, .obj, .bvh, .sinew).
    pub file: PathBuf,
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
