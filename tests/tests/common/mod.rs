//! Helpers shared by the end-to-end tests: run the built `sinew` binary as a subprocess.
#![allow(dead_code, clippy::unwrap_used)]

use std::path::Path;
use std::process::{Command, Output};

/// The result of one run of the binary.
pub struct Run {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

impl Run {
    /// The non-empty lines of stderr.
    pub fn stderr_lines(&self) -> Vec<&str> {
        self.stderr
            .lines()
            .filter(|l| !l.trim().is_empty())
            .collect()
    }
}

/// Runs `sinew` with these arguments.
pub fn sinew<I, S>(args: I) -> Run
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    let out: Output = Command::new(env!("CARGO_BIN_EXE_sinew-e2e"))
        .args(args)
        .output()
        .expect("running the sinew binary");
    Run {
        code: out.status.code().expect("sinew was killed by a signal"),
        stdout: String::from_utf8(out.stdout).expect("stdout is UTF-8"),
        stderr: String::from_utf8(out.stderr).expect("stderr is UTF-8"),
    }
}

/// Asserts the run failed with exit 2 and exactly one stderr line that names `file`.
pub fn assert_one_line_error(run: &Run, file: &Path) {
    let shown = file.display().to_string();
    assert_eq!(run.code, 2, "exit code for {shown}; stderr: {}", run.stderr);
    let lines = run.stderr_lines();
    assert_eq!(
        lines.len(),
        1,
        "expected one error line for {shown}: {lines:?}"
    );
    assert!(
        lines[0].contains(&shown),
        "error line does not name {shown}: {}",
        lines[0]
    );
    assert!(run.stdout.is_empty(), "stdout not empty: {}", run.stdout);
}

/// `sinew inspect --json FILE [extra...]`, asserting success, parsed.
pub fn inspect_json(file: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args: Vec<std::ffi::OsString> = vec!["inspect".into(), "--json".into()];
    args.push(file.into());
    args.extend(extra.iter().map(|s| s.into()));
    let run = sinew(&args);
    assert_eq!(
        run.code,
        0,
        "inspect {} failed: {}",
        file.display(),
        run.stderr
    );
    serde_json::from_str(&run.stdout)
        .unwrap_or_else(|e| panic!("inspect {} printed invalid JSON: {e}", file.display()))
}
