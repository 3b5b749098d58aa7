//! `sinew completions SHELL`: a shell completion script on stdout.

use crate::cli::{Cli, CompletionsArgs};
use crate::Status;
use clap::CommandFactory;

/// Writes the completion script for the requested shell to stdout.
pub fn run(args: &CompletionsArgs) -> anyhow::Result<Status> {
    let mut cmd = Cli::command();
    clap_complete::generate(args.shell, &mut cmd, "sinew", &mut std::io::stdout());
    Ok(Status::Success)
}
