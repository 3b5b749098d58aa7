//! The `sinew` command line, built inside the end-to-end test package so that its tests can run it as
//! a subprocess (`CARGO_BIN_EXE_sinew-e2e`). Same code as the `sinew` binary: `sinew_cli::main_entry`.

fn main() -> std::process::ExitCode {
    sinew_cli::main_entry()
}
