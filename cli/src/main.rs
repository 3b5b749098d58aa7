//! The `sinew` binary; everything lives in the `sinew_cli` library (see its docs and docs/cli.md).

fn main() -> std::process::ExitCode {
    if sinew_pipeline::heap_warming() {
        sinew_pipeline::warm_heap();
    }
    sinew_cli::main_entry()
}
