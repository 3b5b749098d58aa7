//! The `sinew` binary; everything lives in the `sinew_cli` library (see its docs and docs/cli.md).

fn main() -> std::process::ExitCode {
    if std::env::var_os("SINEW_NO_WARM_HEAP").is_none() {
        sinew_pipeline::warm_heap();
    }
    sinew_cli::main_entry()
}
