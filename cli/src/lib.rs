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
pub mod digest;
pub mod incremental;
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
    if sinew_pipeline::heap_warming() {
        // The global pool (a single input's work runs in it), each worker's heap warmed when it
        // starts, as a batch's own pool does (`convert`); after the arguments, so that `--help`
        // and `--version` start no thread. If it cannot be built here, rayon builds it on first
        // use as before.
        let _ = sinew_pipeline::warmed_pool_builder().build_global();
    }
    let ctx = output::Ctx {
        json: args.global.json,
        quiet: args.global.quiet,
        capture: None,
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

/// What [`run_captured`] returns: the exit code the command would have, its JSON report, or its
/// one-line error.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Captured {
    /// 0 success, 1 a check failed (or one file of a batch), 2 bad input or usage.
    pub code: u8,
    /// The JSON report (as `--json` prints it), when the command got as far as reporting.
    pub json: Option<String>,
    /// The error line (as printed after `sinew: error: `), for exit code 2.
    pub error: Option<String>,
    /// True when the arguments themselves were refused (unknown option, bad value) before any work.
    pub usage: bool,
}

/// Runs a command from its arguments (without the program name, e.g. `["convert", "a.ms3d", "-o",
/// "a.sinew"]`) as the `sinew` binary would, with `--json`, but returns the report instead of
/// printing it and writes nothing on stderr. Library callers (the Python package) use this, so they
/// get the same options, checks, outputs and report as the command line.
pub fn run_captured<I, S>(argv: I) -> Captured
where
    I: IntoIterator<Item = S>,
    S: Into<std::ffi::OsString> + Clone,
{
    let args =
        std::iter::once(std::ffi::OsString::from("sinew")).chain(argv.into_iter().map(Into::into));
    let args = match cli::Cli::try_parse_from(args) {
        Ok(a) => a,
        Err(e) => {
            let text = e.to_string();
            let line = text
                .lines()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("bad arguments")
                .trim_start_matches("error: ")
                .to_string();
            return Captured {
                code: 2,
                json: None,
                error: Some(line),
                usage: true,
            };
        }
    };
    let store = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let ctx = output::Ctx {
        json: true,
        quiet: true,
        capture: Some(store.clone()),
    };
    let result = commands::run(args.command, &ctx);
    let json = store.lock().ok().and_then(|mut v| v.pop());
    match result {
        Ok(Status::Success) => Captured {
            code: 0,
            json,
            error: None,
            usage: false,
        },
        Ok(Status::CheckFailed) => Captured {
            code: 1,
            json,
            error: None,
            usage: false,
        },
        Err(err) => Captured {
            code: 2,
            json: None,
            error: Some(output::one_line(&err)),
            usage: false,
        },
    }
}
