//! One module per subcommand; [`run`] dispatches.

pub mod bake;
pub mod completions;
pub mod convert;
pub mod export;
pub mod inspect;
pub mod lod;
pub mod map;
pub mod preview;
pub mod split;
pub mod verify;

use crate::cli::Command;
use crate::output::Ctx;
use crate::Status;

/// Runs one subcommand.
pub fn run(command: Command, ctx: &Ctx) -> anyhow::Result<Status> {
    match command {
        Command::Inspect(args) => inspect::run(&args, ctx),
        Command::Completions(args) => completions::run(&args),
        Command::Convert(args) => convert::run(&args, ctx),
        Command::Map(args) => map::run(&args, ctx),
        Command::Split(args) => split::run(&args, ctx),
        Command::Lod(args) => lod::run(&args, ctx),
        Command::Bake(args) => bake::run(&args, ctx),
        Command::Verify(args) => verify::run(&args, ctx),
        Command::Export(args) => export::run(&args, ctx),
        Command::Preview(args) => preview::run(&args, ctx),
    }
}
