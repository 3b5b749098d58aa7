//! Where output goes: JSON reports on stdout, human text on stderr, files written atomically.

use anyhow::{bail, Context};
use serde::Serialize;
use std::io::Write;
use std::path::Path;

/// The global output settings of one run.
#[derive(Debug, Clone, Default)]
pub struct Ctx {
    /// `--json`: print the report as JSON on stdout, no human report.
    pub json: bool,
    /// `--quiet`: nothing on stderr but errors.
    pub quiet: bool,
    /// When set (library use, e.g. the Python package), JSON reports are collected here instead of
    /// printed, and nothing is written on stderr.
    pub capture: Option<std::sync::Arc<std::sync::Mutex<Vec<String>>>>,
}

impl Ctx {
    /// Whether the human-readable report should be written (to stderr).
    pub fn human(&self) -> bool {
        !self.json && !self.quiet && self.capture.is_none()
    }

    /// Whether errors of single files in a batch may be printed on stderr.
    pub fn stderr(&self) -> bool {
        self.capture.is_none()
    }

    /// The JSON report: printed on stdout, or kept when capturing.
    pub fn emit_json<T: Serialize>(&self, report: &T) -> anyhow::Result<()> {
        match &self.capture {
            Some(c) => {
                let text = serde_json::to_string(report).context("encoding the JSON report")?;
                if let Ok(mut list) = c.lock() {
                    list.push(text);
                }
                Ok(())
            }
            None => print_json(report),
        }
    }
}

/// Prints a report as pretty JSON on stdout, followed by a newline.
pub fn print_json<T: Serialize>(report: &T) -> anyhow::Result<()> {
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    serde_json::to_writer_pretty(&mut out, report).context("stdout: writing the JSON report")?;
    writeln!(out).context("stdout: writing the JSON report")?;
    out.flush().context("stdout: writing the JSON report")?;
    Ok(())
}

/// An error and its causes on one line (`outer: inner: innermost`), with any newline flattened and
/// other control characters (a file's bytes quoted in a message: form feeds, escapes) written escaped,
/// so that a log reader splitting lines gets one.
pub fn one_line(err: &anyhow::Error) -> String {
    let text = format!("{err:#}");
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\r' | '\n' => out.push(' '),
            c if c.is_control() => out.extend(c.escape_debug()),
            c => out.push(c),
        }
    }
    out
}

/// Checks that `path` can be an output file: its directory exists and it is not itself a directory.
/// Call this before any expensive work so a bad output path fails fast and writes nothing.
pub fn check_output_path(path: &Path) -> anyhow::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        bail!(
            "{}: output directory {} does not exist",
            path.display(),
            dir.display()
        );
    }
    if path.is_dir() {
        bail!("{}: output path is a directory", path.display());
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically: into a temporary file in the same directory, then renamed over
/// `path`. A failure at any point leaves no new file at `path` (and no temporary file behind); other
/// processes see the old file or the whole new one, never a part.
///
/// On Linux a regular file already at `path` is replaced by swapping the two names in one step
/// (`renameat2` with `RENAME_EXCHANGE`) and then removing the old file under the temporary name:
/// the same atomic replacement as a rename, without the write-back ext4 starts when a rename
/// replaces a file (its `auto_da_alloc`, 0.2-0.4 ms a file: docs/performance.md, session 28). That
/// write-back is a guard for programs that replace files without syncing them; sinew promises no
/// durability across a power cut either way (no fsync, docs/cli.md).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    check_output_path(path)?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    builder.prefix(".sinew-tmp-");
    // Created like any new file (mode 0666 less the umask: 0644 under the usual 022), so that the
    // rename leaves the permissions `cp` or a compiler would give; tempfile's default is 0600.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder
        .tempfile_in(dir)
        .with_context(|| format!("{}: creating a temporary file", path.display()))?;
    // No fsync: the rename makes the file appear whole or not at all to every other process, which
    // is the contract (docs/cli.md); surviving a power cut would cost a disk flush per file.
    tmp.write_all(bytes)
        .with_context(|| format!("{}: writing", path.display()))?;
    #[cfg(target_os = "linux")]
    if swapped_with_existing(tmp.path(), path) {
        // The temporary name now holds the old file.
        return tmp.close().with_context(|| {
            format!(
                "{}: written; removing the file it replaced (now at a temporary name)",
                path.display()
            )
        });
    }
    tmp.persist(path)
        .map_err(|e| e.error)
        .with_context(|| format!("{}: renaming the temporary file into place", path.display()))?;
    Ok(())
}

/// Swaps `tmp` and `path` when `path` is a regular file (not a link, folder or anything else), on
/// a file system that can swap names; false when nothing was swapped, and the caller renames.
#[cfg(target_os = "linux")]
fn swapped_with_existing(tmp: &Path, path: &Path) -> bool {
    use rustix::fs::{renameat_with, RenameFlags, CWD};
    let regular = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_file());
    // Fails without swapping when the file has gone meanwhile (ENOENT) or the file system cannot
    // swap (EINVAL): then a rename does the job.
    regular && renameat_with(CWD, tmp, CWD, path, RenameFlags::EXCHANGE).is_ok()
}

#[cfg(test)]
mod one_line_tests {
    #[test]
    fn newlines_become_spaces_and_other_controls_are_escaped() {
        let e = anyhow::anyhow!("a\nb\u{c}c\u{1b}d").context("m.gltf");
        assert_eq!(super::one_line(&e), "m.gltf: a b\\u{c}c\\u{1b}d");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The permission bits of `p`.
    #[cfg(unix)]
    fn mode(p: &Path) -> u32 {
        use std::os::unix::fs::PermissionsExt;
        std::fs::metadata(p).unwrap().permissions().mode() & 0o777
    }

    /// The mode a plain new file gets in `dir` (0666 less this process's umask), from a file
    /// `probe` written there.
    #[cfg(unix)]
    fn new_file_mode(dir: &Path) -> u32 {
        let probe = dir.join("probe");
        std::fs::write(&probe, b"x").unwrap();
        mode(&probe)
    }

    #[test]
    fn atomic_write_replaces_content_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.bin");
        write_atomic(&out, b"first").unwrap();
        write_atomic(&out, b"second!").unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"second!");
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("a.bin")]);
    }

    #[cfg(unix)]
    #[test]
    fn written_files_get_the_mode_a_new_file_gets() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.bin");
        write_atomic(&out, b"x").unwrap();
        assert_eq!(mode(&out), new_file_mode(dir.path()));
        assert_ne!(mode(&out), 0o600, "umask 0177 would be unusual here");
    }

    #[cfg(unix)]
    #[test]
    fn a_replaced_file_is_a_new_file_as_after_a_rename() {
        use std::os::unix::fs::{MetadataExt, PermissionsExt};
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.bin");
        std::fs::write(&out, b"old contents").unwrap();
        std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o600)).unwrap();
        // A second name for the old file, and a reader holding it open: neither sees the new bytes.
        let other = dir.path().join("other-name");
        std::fs::hard_link(&out, &other).unwrap();
        let old_inode = std::fs::metadata(&out).unwrap().ino();
        let held = std::fs::File::open(&out).unwrap();
        write_atomic(&out, b"new").unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"new");
        assert_eq!(std::fs::read(&other).unwrap(), b"old contents");
        assert_eq!(std::io::read_to_string(held).unwrap(), "old contents");
        assert_ne!(std::fs::metadata(&out).unwrap().ino(), old_inode);
        // The new file's mode, not the old one's (0600), as a rename leaves it.
        assert_eq!(mode(&out), new_file_mode(dir.path()));
        let mut names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        names.sort();
        assert_eq!(names, ["a.bin", "other-name", "probe"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_link_at_the_output_is_replaced_and_its_target_kept() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("target.bin");
        std::fs::write(&target, b"target").unwrap();
        let out = dir.path().join("a.bin");
        std::os::unix::fs::symlink(&target, &out).unwrap();
        write_atomic(&out, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&out)
            .unwrap()
            .file_type()
            .is_file());
        assert_eq!(std::fs::read(&out).unwrap(), b"new");
        assert_eq!(std::fs::read(&target).unwrap(), b"target");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }

    #[test]
    fn missing_directory_is_an_error_naming_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("nope/a.bin");
        let err = write_atomic(&out, b"x").unwrap_err();
        let msg = one_line(&err);
        assert!(msg.contains("nope/a.bin"), "{msg}");
        assert!(msg.contains("does not exist"), "{msg}");
        assert!(!dir.path().join("nope").exists());
    }

    #[test]
    fn directory_as_output_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        let err = write_atomic(dir.path(), b"x").unwrap_err();
        assert!(one_line(&err).contains("is a directory"));
    }
}
