//! One module per subcommand; [`run`] dispatches.

pub mod bake;
pub mod completions;
pub mod inspect;
pub mod verify;

use crate::cli::Command;
use crate::output::Ctx;
use crate::Status;

/// Runs one subcommand.
pub fn run(command: Command, ctx: &Ctx) -> anyhow::Result<Status> {
    match command {
        Command::Inspect(args) => inspect::run(&args, ctx),
        Command::Completions(args) => completions::run(&args),
        Command::Bake(args) => bake::run(&args, ctx),
        Command::Verify(args) => verify::run(&args, ctx),
    }
}
