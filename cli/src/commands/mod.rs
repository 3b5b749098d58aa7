//! One module per subcommand; [`run`] dispatches.

pub mod completions;
pub mod inspect;

use crate::cli::Command;
use crate::output::Ctx;
use crate::Status;

/// Runs one subcommand.
pub fn run(command: Command, ctx: &Ctx) -> anyhow::Result<Status> {
    match command {
        Command::Inspect(args) => inspect::run(&args, ctx),
        Command::Completions(args) => completions::run(&args),
    }
}
