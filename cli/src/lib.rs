//! The `sinew` command line: one binary whose subcommands share the same conventions.
//!
//! - `--json` prints the command's report as JSON on stdout; nothing else is ever written to stdout
//!   (except by `completions`, whose output *is* the script).
//! - Human-readable reports, warnings and progress go to stderr; `--quiet` silences all but errors.
//! - Exit codes: 0 success, 1 a check failed or one of several files failed, 2 bad input or usage.
//!   Every error from the command itself is one line on stderr naming the file and the problem.
//!
//! See docs/cli.md for every command, option and JSON field. The binary (`src/main.rs`) only calls
//! [`main_entry`]; each subcommand lives in its own module under [`commands`], argument definitions in
//! [`cli`], input checks in [`input`] and output helpers (JSON, atomic writes) in [`output`].

pub mod batch;
pub mod cli;
pub mod commands;
pub mod input;
pub mod output;
pub mod report;
pub mod steps;

use clap::Parser;
use std::process::ExitCode;

/// How a command that did not fail outright ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Everything succeeded: exit 0.
    Success,
    /// A check failed, or one of several files failed: exit 1.
    CheckFailed,
}

/// Parses the process arguments, runs the command and maps the outcome to an exit code.
pub fn main_entry() -> ExitCode {
    // Clap prints usage errors itself and exits 2 (0 for --help and --version).
    let args = cli::Cli::parse();
    let ctx = output::Ctx {
        json: args.global.json,
        quiet: args.global.quiet,
    };
    match commands::run(args.command, &ctx) {
        Ok(Status::Success) => ExitCode::SUCCESS,
        Ok(Status::CheckFailed) => ExitCode::from(1),
        Err(err) => {
            eprintln!("sinew: error: {}", output::one_line(&err));
            ExitCode::from(2)
        }
    }
}
