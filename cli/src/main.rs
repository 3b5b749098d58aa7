//! The `sinew` binary; everything lives in the `sinew_cli` library (see its docs and docs/cli.md).

fn main() -> std::process::ExitCode {
    sinew_cli::main_entry()
}
