//! The `sinew` command line. See docs/cli.md.

fn main() {
    eprintln!("sinew: no commands yet");
    std::process::exit(2);
}
