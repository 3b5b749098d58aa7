//! The record of `convert --incremental`: one JSON file per output under `OUT/.sinew-incremental/`,
//! saying what the output was made from (every file read, with its size and BLAKE3 digest), with
//! which options and sinew version, what was written (each file's digest again) and the report of
//! that run. An output is reused only when all of it still holds; a record that is corrupt or not
//! sinew's makes the whole run a full one. Layout: docs/cli.md, "Incremental batches".

use crate::cli::ConvertArgs;
use crate::digest::{hex, Stamp};
use crate::output::write_atomic;
use anyhow::{anyhow, Context};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The record's folder, inside the output folder.
pub const FOLDER: &str = ".sinew-incremental";
/// The `format` field of every record.
pub const FORMAT: &str = "sinew-incremental-record";
/// The record layout this sinew writes and reads.
pub const VERSION: u32 = 1;
/// The sinew version an output was written by.
pub const SINEW_VERSION: &str = env!("CARGO_PKG_VERSION");

/// What one output was made from and what it holds (one file, `<output>.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Record {
    /// Always [`FORMAT`].
    pub format: String,
    /// Always [`VERSION`].
    pub version: u32,
    /// The sinew version that wrote the output.
    pub sinew: String,
    /// The options' fingerprint ([`options_fingerprint`]).
    pub options: String,
    /// The input path as given.
    pub input: String,
    /// The output path as written.
    pub output: String,
    /// Every file the conversion read: the input first, then what it asked for (missing ones too).
    pub reads: Vec<Stamp>,
    /// Every file written: texture PNGs, then the `.sinew`.
    pub writes: Vec<Stamp>,
    /// Warnings among the diagnostics.
    pub warnings: usize,
    /// The fields of the input's entry in the JSON report (`files[]`) from `bytes` on, as compact
    /// JSON text (text, so that the record reads back exactly as written and its numbers print
    /// back as they were).
    pub report: String,
    /// BLAKE3 of the record serialised compactly with this field empty.
    pub checksum: String,
}

impl Record {
    /// A record with its checksum.
    pub fn new(
        options: &str,
        job: (&Path, &Path),
        reads: Vec<Stamp>,
        writes: Vec<Stamp>,
        warnings: usize,
        report: String,
    ) -> Record {
        let mut r = Record {
            format: FORMAT.to_string(),
            version: VERSION,
            sinew: SINEW_VERSION.to_string(),
            options: options.to_string(),
            input: job.0.display().to_string(),
            output: job.1.display().to_string(),
            reads,
            writes,
            warnings,
            report,
            checksum: String::new(),
        };
        r.checksum = r.digest();
        r
    }

    fn digest(&self) -> String {
        let mut body = self.clone();
        body.checksum.clear();
        hex(&serde_json::to_vec(&body).unwrap_or_default())
    }

    /// Whether the output can be kept: same sinew, options, input and output, and every file read
    /// and written still holds what it held.
    pub fn still_holds(&self, options: &str, input: &Path, output: &Path) -> bool {
        self.sinew == SINEW_VERSION
            && self.options == options
            && self.input == input.display().to_string()
            && self.output == output.display().to_string()
            && !self.reads.is_empty()
            && !self.writes.is_empty()
            && self.reads.iter().all(Stamp::is_current)
            && self.writes.iter().all(Stamp::is_current)
    }

    /// Parses a record file; the error says why it cannot be trusted.
    pub fn parse(bytes: &[u8]) -> Result<Record, String> {
        let v: serde_json::Value =
            serde_json::from_slice(bytes).map_err(|e| format!("corrupt: not JSON ({e})"))?;
        match v.get("format").and_then(|f| f.as_str()) {
            Some(FORMAT) => {}
            _ => return Err(format!("not a sinew record (no \"format\": \"{FORMAT}\")")),
        }
        match v.get("version").and_then(|f| f.as_u64()) {
            Some(n) if n == u64::from(VERSION) => {}
            other => {
                return Err(format!(
                    "record layout version {other:?}, this sinew reads {VERSION}"
                ))
            }
        }
        let r: Record = serde_json::from_value(v).map_err(|e| format!("corrupt: {e}"))?;
        if r.checksum != r.digest() {
            return Err("corrupt: its checksum does not match its content".to_string());
        }
        if r.report_fields().is_none() {
            return Err("corrupt: its report is not a JSON object".to_string());
        }
        Ok(r)
    }

    /// The recorded report fields.
    pub fn report_fields(&self) -> Option<crate::report::RecordedFields> {
        crate::report::RecordedFields::parse(&self.report)
    }
}

/// The fingerprint of everything besides the input's own files that decides an output's bytes: the
/// sinew version, every option of `args` (except the inputs, output paths, `--jobs`, `--strict`,
/// `--incremental`, `--timings` and `--report`, which do not change what is written), and `extra`, the stamps of the `--anim`
/// and `--map` files and what they read. A new option is part of it without being listed, so it can
/// only cause a rebuild, never a wrong reuse.
pub fn options_fingerprint(args: &ConvertArgs, extra: &[Stamp]) -> String {
    let mut a = args.clone();
    a.inputs.clear();
    a.output = None;
    a.out_dir = None;
    a.jobs = None;
    a.strict = false;
    a.incremental = false;
    a.timings = false;
    a.report = None;
    hex(format!("sinew {SINEW_VERSION}\n{a:?}\n{extra:?}").as_bytes())
}

/// Where the record of `output` lives: `root/.sinew-incremental/<output relative to root>.json`.
pub fn record_path(root: &Path, output: &Path) -> PathBuf {
    let rel = output
        .strip_prefix(root)
        .ok()
        .map(Path::to_path_buf)
        .or_else(|| output.file_name().map(PathBuf::from))
        .unwrap_or_default();
    let mut name = rel.into_os_string();
    name.push(".json");
    root.join(FOLDER).join(name)
}

/// The records found for a batch's outputs.
#[derive(Debug, Default)]
pub struct Loaded {
    /// Per output, its record when there is one to check.
    pub records: Vec<Option<Record>>,
    /// `used`, `new` or `ignored` (see [`crate::report::IncrementalReport`]).
    pub state: &'static str,
    /// Why the records were ignored.
    pub reason: Option<String>,
}

/// Reads the records of `outputs`. One that cannot be read, is corrupt or is not sinew's makes
/// every record ignored: a full run.
pub fn load(root: &Path, outputs: &[&Path]) -> Loaded {
    let mut records = Vec::with_capacity(outputs.len());
    for output in outputs {
        let path = record_path(root, output);
        let bytes = match std::fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                records.push(None);
                continue;
            }
            Err(e) => return ignored(&path, format!("cannot be read: {e}"), outputs.len()),
        };
        match Record::parse(&bytes) {
            Ok(r) => records.push(Some(r)),
            Err(why) => return ignored(&path, why, outputs.len()),
        }
    }
    let state = if records.iter().any(Option::is_some) {
        "used"
    } else {
        "new"
    };
    Loaded {
        records,
        state,
        reason: None,
    }
}

fn ignored(path: &Path, why: String, n: usize) -> Loaded {
    Loaded {
        records: vec![None; n],
        state: "ignored",
        reason: Some(format!("{}: {why}; every input converted", path.display())),
    }
}

/// Writes `record` for its output under `root` (atomically).
pub fn store(root: &Path, record: &Record) -> anyhow::Result<()> {
    let path = record_path(root, Path::new(&record.output));
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow!("{}: cannot create the folder: {e}", dir.display()))?;
    }
    let mut text = serde_json::to_vec_pretty(record).context("encoding the incremental record")?;
    text.push(b'\n');
    write_atomic(&path, &text)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(dir: &Path) -> Record {
        let input = dir.join("in.smd");
        std::fs::write(&input, b"version 1\n").unwrap();
        let output = dir.join("out/in.sinew");
        std::fs::create_dir_all(output.parent().unwrap()).unwrap();
        std::fs::write(&output, b"SINEW").unwrap();
        let report = r#"{"bytes":5,"clips":[{"max_error":0.1}]}"#.to_string();
        Record::new(
            "opts",
            (&input, &output),
            vec![Stamp::read(&input), Stamp::read(&dir.join("gone.smd"))],
            vec![Stamp::read(&output)],
            0,
            report,
        )
    }

    #[test]
    fn a_record_round_trips_and_holds_until_a_file_changes() {
        let dir = tempfile::tempdir().unwrap();
        let r = sample(dir.path());
        let root = dir.path().join("out");
        store(&root, &r).unwrap();
        let path = root.join(FOLDER).join("in.sinew.json");
        let back = Record::parse(&std::fs::read(&path).unwrap()).unwrap();
        assert_eq!(back, r);
        let (input, output) = (dir.path().join("in.smd"), root.join("in.sinew"));
        assert!(back.still_holds("opts", &input, &output));
        assert!(!back.still_holds("other", &input, &output));
        // A file that was missing appears: the output is made again.
        std::fs::write(dir.path().join("gone.smd"), b"x").unwrap();
        assert!(!back.still_holds("opts", &input, &output));
        std::fs::remove_file(dir.path().join("gone.smd")).unwrap();
        assert!(back.still_holds("opts", &input, &output));
        // So does an output changed by someone else.
        std::fs::write(&output, b"SINEX").unwrap();
        assert!(!back.still_holds("opts", &input, &output));
    }

    #[test]
    fn corrupt_and_foreign_records_are_refused_with_the_reason() {
        let dir = tempfile::tempdir().unwrap();
        let r = sample(dir.path());
        let text = serde_json::to_string(&r).unwrap();
        // One digit of a stamp changed: the checksum catches it.
        let i = text.find("\"bytes\":10").unwrap() + 9;
        let mut bad = text.clone().into_bytes();
        bad[i] = b'2';
        assert!(Record::parse(&bad).unwrap_err().contains("checksum"));
        assert!(Record::parse(&text.as_bytes()[..text.len() / 2])
            .unwrap_err()
            .contains("not JSON"));
        let foreign = text.replace(FORMAT, "something-else");
        assert!(Record::parse(foreign.as_bytes())
            .unwrap_err()
            .contains("not a sinew record"));
        let newer = text.replace("\"version\":1", "\"version\":2");
        assert!(Record::parse(newer.as_bytes())
            .unwrap_err()
            .contains("version"));
        // load: one bad record ignores them all.
        let root = dir.path().join("out");
        store(&root, &r).unwrap();
        let out = root.join("in.sinew");
        let other = root.join("b.sinew");
        assert_eq!(load(&root, &[&out, &other]).state, "used");
        std::fs::create_dir_all(root.join(FOLDER)).unwrap();
        std::fs::write(root.join(FOLDER).join("b.sinew.json"), b"{").unwrap();
        let l = load(&root, &[&out, &other]);
        assert_eq!(l.state, "ignored");
        assert!(l.records.iter().all(Option::is_none));
        assert!(l.reason.unwrap().contains("b.sinew.json"));
    }

    fn convert_args(extra: &[&str]) -> ConvertArgs {
        use clap::Parser;
        let mut argv = vec!["sinew", "convert", "a.smd", "--out-dir", "out"];
        argv.extend_from_slice(extra);
        match crate::cli::Cli::try_parse_from(argv).unwrap().command {
            crate::cli::Command::Convert(a) => a,
            _ => unreachable!("convert parses as convert"),
        }
    }

    #[test]
    fn report_and_timings_leave_the_fingerprint_alone_and_other_options_change_it() {
        let plain = options_fingerprint(&convert_args(&[]), &[]);
        let watched = convert_args(&["--report", "out/index.html", "--timings", "--jobs", "2"]);
        assert_eq!(options_fingerprint(&watched, &[]), plain);
        let other = convert_args(&["--lod", "none"]);
        assert_ne!(options_fingerprint(&other, &[]), plain);
    }
}
