//! Batch inputs of `convert --out-dir`: folders walked for the models they hold (recognised by content,
//! not by name), companion files folded into the model that reads them (Half-Life texture and
//! sequence-group files, the SMDs a QC names), output paths that mirror each folder's tree under
//! the output folder, and every file the walk passed over with its reason (not a model, companion of
//! a model, companion whose model is missing). Everything is sorted, so the plan is the same on
//! every run.

use crate::cli::ImportArgs;
use crate::input::normal;
use crate::report::SkippedReport;
use anyhow::{anyhow, bail};
use sinew_import::{FileKind, Format};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::ffi::OsString;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// How deep a folder walk goes.
pub const MAX_DEPTH: usize = 64;

/// One model to convert.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Job {
    /// The input file.
    pub input: PathBuf,
    /// The `.sinew` to write.
    pub output: PathBuf,
    /// Its format: from the extension for files named on the command line, by content in folders.
    pub format: Option<Format>,
}

/// The first bytes of a file, enough to recognise it.
fn head(path: &Path) -> std::io::Result<Vec<u8>> {
    let mut buf = Vec::with_capacity(512);
    std::fs::File::open(path)?.take(512).read_to_end(&mut buf)?;
    Ok(buf)
}

/// The regular files under `dir`, sorted by path; symbolic links to folders are not followed.
fn walk(dir: &Path, depth: usize, out: &mut Vec<PathBuf>) -> anyhow::Result<()> {
    if depth > MAX_DEPTH {
        bail!("{}: folders nest deeper than {MAX_DEPTH}", dir.display());
    }
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| anyhow!("{}: cannot list the folder: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for p in entries {
        let meta = std::fs::symlink_metadata(&p).map_err(|e| anyhow!("{}: {e}", p.display()))?;
        if meta.is_dir() {
            walk(&p, depth + 1, out)?;
        } else if meta.is_file() || (meta.file_type().is_symlink() && p.is_file()) {
            out.push(p);
        }
    }
    Ok(())
}

/// The files a QC reads (its includes and SMDs), found by compiling it with a resolver that records
/// every name asked for.
fn qc_companions(qc: &Path, import: &ImportArgs) -> BTreeSet<PathBuf> {
    let dir = qc.parent().map(Path::to_path_buf).unwrap_or_default();
    let asked: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
    let inner = sinew_import::beside(qc);
    let resolve = |rel: &str| -> std::io::Result<Vec<u8>> {
        if let Ok(mut a) = asked.lock() {
            a.push(normal(&dir.join(rel.replace('\\', "/"))));
        }
        inner(rel)
    };
    if let Ok(bytes) = std::fs::read(qc) {
        let _ = sinew_import::import_bytes(
            Format::Qc,
            &qc.display().to_string(),
            &bytes,
            &resolve,
            // Every SMD asked for, also past a missing one.
            &sinew_import::ImportOptions {
                allow_missing: true,
                ..crate::input::import_options(import)
            },
        );
    }
    asked.into_inner().unwrap_or_default().into_iter().collect()
}

/// The files an MDL's header names beside it (texture file, sequence groups); none when it cannot
/// be read (its conversion will say why).
fn mdl_companions(mdl: &Path) -> BTreeSet<PathBuf> {
    let dir = mdl.parent().map(Path::to_path_buf).unwrap_or_default();
    let name = mdl.display().to_string();
    std::fs::read(mdl)
        .ok()
        .and_then(|b| sinew_import::halflife::mdl::companions(&name, &b).ok())
        .into_iter()
        .flatten()
        .map(|c| normal(&dir.join(c)))
        .collect()
}

/// Output names in one folder: `<stem>.sinew`, or `<file name>.sinew` for inputs whose stems collide.
fn names_in(folder_inputs: &[&Path]) -> anyhow::Result<Vec<OsString>> {
    let mut stems: HashMap<OsString, usize> = HashMap::new();
    for i in folder_inputs {
        let stem = i
            .file_stem()
            .ok_or_else(|| anyhow!("{}: has no file name", i.display()))?;
        *stems.entry(stem.to_os_string()).or_default() += 1;
    }
    folder_inputs
        .iter()
        .map(|i| {
            let (Some(stem), Some(file_name)) = (i.file_stem(), i.file_name()) else {
                bail!("{}: has no file name", i.display());
            };
            let mut name = if stems.get(stem).copied().unwrap_or(0) > 1 {
                file_name.to_os_string()
            } else {
                stem.to_os_string()
            };
            name.push(".sinew");
            Ok(name)
        })
        .collect()
}

/// A file a folder walk found that is not converted on its own.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Passed {
    /// The file, as walked.
    pub path: PathBuf,
    /// What its content says it is.
    pub kind: FileKind,
    /// The QC or MDL that names it, when one does (found while planning).
    pub read_by: Option<PathBuf>,
}

/// A planned batch: the models to convert and the files the folder walks passed over.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Batch {
    /// One per model, command-line files first, then each folder's models by path.
    pub jobs: Vec<Job>,
    /// Every other file under the folders, by path.
    pub passed: Vec<Passed>,
}

/// Plans a batch: files as given, folders walked; each output under `out_dir`.
pub fn plan(inputs: &[PathBuf], out_dir: &Path, import: &ImportArgs) -> anyhow::Result<Batch> {
    // Files named on the command line go straight into out_dir.
    let mut direct: Vec<&Path> = Vec::new();
    let mut jobs: Vec<Job> = Vec::new();
    let mut folder_jobs: Vec<Job> = Vec::new();
    let mut passed: Vec<Passed> = Vec::new();
    for input in inputs {
        if !input.is_dir() {
            direct.push(input);
            continue;
        }
        let mut files = Vec::new();
        walk(input, 0, &mut files)?;
        let mut models: Vec<(PathBuf, Format)> = Vec::new();
        let mut others: Vec<(PathBuf, FileKind)> = Vec::new();
        for f in &files {
            let kind = match head(f) {
                Ok(h) => FileKind::sniff(f, &h),
                Err(_) => FileKind::Other,
            };
            match kind {
                FileKind::Model(format) => models.push((f.clone(), format)),
                other => others.push((f.clone(), other)),
            }
        }
        let mut companions: BTreeMap<PathBuf, PathBuf> = BTreeMap::new();
        for (f, format) in &models {
            let named = match format {
                Format::Qc => qc_companions(f, import),
                Format::Mdl => mdl_companions(f),
                _ => continue,
            };
            for c in named {
                companions.entry(c).or_insert_with(|| f.clone());
            }
        }
        let mut kept = Vec::with_capacity(models.len());
        for (f, format) in models {
            match companions.get(&normal(&f)) {
                Some(_) if format != Format::Qc => others.push((f, FileKind::Model(format))),
                _ => kept.push((f, format)),
            }
        }
        let models = kept;
        for (f, kind) in others {
            let read_by = companions.get(&normal(&f)).cloned();
            passed.push(Passed {
                path: f,
                kind,
                read_by,
            });
        }
        // Mirror the tree: group by folder, name within each folder.
        let mut by_folder: BTreeMap<PathBuf, Vec<(PathBuf, Format)>> = BTreeMap::new();
        for (f, format) in models {
            let rel = f
                .parent()
                .and_then(|p| p.strip_prefix(input).ok())
                .map(Path::to_path_buf)
                .unwrap_or_default();
            by_folder.entry(rel).or_default().push((f, format));
        }
        for (rel, list) in by_folder {
            let paths: Vec<&Path> = list.iter().map(|(p, _)| p.as_path()).collect();
            let names = names_in(&paths)?;
            for ((f, format), name) in list.iter().zip(names) {
                folder_jobs.push(Job {
                    input: f.clone(),
                    output: out_dir.join(&rel).join(name),
                    format: Some(*format),
                });
            }
        }
    }
    let names = names_in(&direct)?;
    for (i, name) in direct.iter().zip(names) {
        jobs.push(Job {
            input: i.to_path_buf(),
            output: out_dir.join(name),
            format: None,
        });
    }
    jobs.extend(folder_jobs);
    passed.sort_by(|a, b| a.path.cmp(&b.path));
    let mut seen: HashMap<&Path, &Path> = HashMap::new();
    for j in &jobs {
        if let Some(prev) = seen.insert(&j.output, &j.input) {
            bail!(
                "{} and {} would both be written to {}",
                prev.display(),
                j.input.display(),
                j.output.display()
            );
        }
    }
    Ok(Batch { jobs, passed })
}

/// Why each passed-over file was not converted: `companion` of the model that read it (found while
/// planning for a QC's files, else among `reads`: per job, the files its conversion read or, when
/// reused, read last time), `orphaned-companion` for a Half-Life texture or sequence-group file
/// that no model read, `not-a-model` for the rest.
pub fn skipped(passed: &[Passed], jobs: &[Job], reads: &[Vec<PathBuf>]) -> Vec<SkippedReport> {
    let mut reader: HashMap<PathBuf, &Path> = HashMap::new();
    for (job, list) in jobs.iter().zip(reads) {
        for r in list {
            if normal(r) != normal(&job.input) {
                reader.entry(normal(r)).or_insert(&job.input);
            }
        }
    }
    passed
        .iter()
        .map(|p| {
            let model = p
                .read_by
                .as_deref()
                .or_else(|| reader.get(&normal(&p.path)).copied());
            let (reason, message) = match (model, p.kind) {
                (Some(m), _) => ("companion", format!("read by {}", m.display())),
                (None, FileKind::MdlTextures | FileKind::MdlSequenceGroup) => {
                    let what = if p.kind == FileKind::MdlTextures {
                        "a Half-Life texture file"
                    } else {
                        "a Half-Life sequence-group file"
                    };
                    (
                        "orphaned-companion",
                        format!(
                            "{what} that no model reads: {}",
                            orphan_reason(&p.path, p.kind)
                        ),
                    )
                }
                (None, FileKind::Model(f)) => (
                    "not-a-model",
                    format!("recognised as {f:?} but not converted"),
                ),
                (None, _) => ("not-a-model", "not a format sinew converts".to_string()),
            };
            SkippedReport {
                file: p.path.display().to_string(),
                reason,
                model: model.map(|m| m.display().to_string()),
                message,
            }
        })
        .collect()
}

/// Why nobody reads an orphan: its model by the GoldSrc naming rule is missing, or is there and does
/// not name it (it keeps its own textures, or names other group files).
fn orphan_reason(path: &Path, kind: FileKind) -> String {
    match expected_model(path, kind) {
        Some(m) if path.with_file_name(&m).is_file() => format!(
            "{m} beside it does not name it (it keeps its own {})",
            if kind == FileKind::MdlTextures {
                "textures"
            } else {
                "sequences, or names other group files"
            }
        ),
        Some(m) => format!("its model ({m}) is missing"),
        None => "no model in the folder names it".to_string(),
    }
}

/// `NAME.mdl` for `NAMET.mdl` or `NAMEnn.mdl` by the GoldSrc naming rule.
fn expected_model(path: &Path, kind: FileKind) -> Option<String> {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let base = match kind {
        FileKind::MdlTextures => stem.strip_suffix(['T', 't']),
        _ => stem
            .len()
            .checked_sub(2)
            .filter(|&n| stem.is_char_boundary(n) && stem[n..].bytes().all(|b| b.is_ascii_digit()))
            .map(|n| &stem[..n]),
    };
    base.filter(|b| !b.is_empty()).map(|b| format!("{b}.mdl"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folders_fold_companions_and_mirror_the_tree() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("in");
        std::fs::create_dir_all(root.join("chars/man")).unwrap();
        std::fs::create_dir_all(root.join("props")).unwrap();
        // An MDL, its texture file (content: IDST with only textures) under a name that does not say so.
        let mut mdl = vec![0u8; 244];
        mdl[..4].copy_from_slice(b"IDST");
        mdl[140..144].copy_from_slice(&1i32.to_le_bytes());
        std::fs::write(root.join("chars/man/man.mdl"), &mdl).unwrap();
        let mut tex = vec![0u8; 244];
        tex[..4].copy_from_slice(b"IDST");
        tex[180..184].copy_from_slice(&2i32.to_le_bytes());
        std::fs::write(root.join("chars/man/skins.mdl"), &tex).unwrap();
        std::fs::write(root.join("chars/man/man01.mdl"), b"IDSQ\x0a\0\0\0").unwrap();
        // A QC and the SMDs it names; another SMD that no QC names.
        std::fs::write(
            root.join("props/box.qc"),
            "$body b \"box_ref\"\n$sequence idle \"box_idle\"\n",
        )
        .unwrap();
        std::fs::write(
            root.join("props/box_ref.smd"),
            "version 1\nnodes\n0 \"b\" -1\nend\n",
        )
        .unwrap();
        std::fs::write(
            root.join("props/box_idle.smd"),
            "version 1\nnodes\n0 \"b\" -1\nend\n",
        )
        .unwrap();
        std::fs::write(root.join("props/lone.smd"), "version 1\nnodes\nend\n").unwrap();
        std::fs::write(root.join("props/notes.txt"), "hello").unwrap();
        let out = dir.path().join("out");
        let batch = plan(std::slice::from_ref(&root), &out, &ImportArgs::default()).unwrap();
        let jobs = &batch.jobs;
        let got: Vec<(PathBuf, PathBuf, Option<Format>)> = jobs
            .iter()
            .map(|j| {
                (
                    j.input.strip_prefix(&root).unwrap().to_path_buf(),
                    j.output.strip_prefix(&out).unwrap().to_path_buf(),
                    j.format,
                )
            })
            .collect();
        assert_eq!(
            got,
            [
                (
                    "chars/man/man.mdl".into(),
                    "chars/man/man.sinew".into(),
                    Some(Format::Mdl)
                ),
                (
                    "props/box.qc".into(),
                    "props/box.sinew".into(),
                    Some(Format::Qc)
                ),
                (
                    "props/lone.smd".into(),
                    "props/lone.sinew".into(),
                    Some(Format::Smd)
                ),
            ]
        );
        // What was passed over, and why: the QC's SMDs are its companions (found while planning);
        // the texture file counts as man.mdl's when its conversion read it; the sequence group that
        // nobody read is an orphan, and so is the texture file when nobody read it.
        let rel = |p: &str| {
            p.strip_prefix(&format!("{}/", root.display()))
                .unwrap()
                .to_string()
        };
        let table = |reads: &[Vec<PathBuf>]| -> Vec<(String, &'static str, Option<String>)> {
            skipped(&batch.passed, jobs, reads)
                .into_iter()
                .map(|s| (rel(&s.file), s.reason, s.model.map(|m| rel(&m))))
                .collect()
        };
        let read_skins = vec![
            vec![
                root.join("chars/man/man.mdl"),
                root.join("chars/man/skins.mdl"),
            ],
            vec![],
            vec![],
        ];
        let qc = Some("props/box.qc".to_string());
        assert_eq!(
            table(&read_skins),
            [
                ("chars/man/man01.mdl".into(), "orphaned-companion", None),
                (
                    "chars/man/skins.mdl".into(),
                    "companion",
                    Some("chars/man/man.mdl".into())
                ),
                ("props/box_idle.smd".into(), "companion", qc.clone()),
                ("props/box_ref.smd".into(), "companion", qc.clone()),
                ("props/notes.txt".into(), "not-a-model", None),
            ]
        );
        let none = vec![vec![], vec![], vec![]];
        assert_eq!(
            table(&none)[1],
            ("chars/man/skins.mdl".into(), "orphaned-companion", None)
        );
        let orphan = skipped(&batch.passed, jobs, &none);
        assert!(
            orphan[0]
                .message
                .contains("man.mdl beside it does not name it"),
            "{}",
            orphan[0].message
        );
        assert!(
            orphan[1].message.contains("texture file"),
            "{}",
            orphan[1].message
        );
    }
}
