//! Builds the seed corpus of every fuzz target from the shared corpus (nothing of it is committed):
//! `seeds CORPUS OUT` writes `OUT/<target>/<file>` for each corpus file a target reads, with the
//! companion files the reader asks for appended in the order it asks (see `sinew_fuzz::SEPARATOR`).
//! Files over `MAX_SEED` bytes are left out: they slow every execution and add little a smaller file
//! of the same format does not. QC seeds are made here (the corpus holds no QC), around corpus SMDs.

use sinew_fuzz::SEPARATOR;
use std::cell::RefCell;
use std::path::{Path, PathBuf};

const MAX_SEED: u64 = 512 * 1024;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 3 {
        eprintln!("usage: seeds CORPUS OUT");
        std::process::exit(2);
    }
    let corpus = PathBuf::from(&args[1]);
    let out = PathBuf::from(&args[2]);
    let mut files = Vec::new();
    walk(&corpus, &mut files);
    files.sort();
    let mut written = 0;
    let mut smds = Vec::new();
    for path in &files {
        let Some(target) = target_of(path) else {
            continue;
        };
        let Ok(meta) = std::fs::metadata(path) else {
            continue;
        };
        if meta.len() > MAX_SEED {
            continue;
        }
        let Ok(bytes) = std::fs::read(path) else {
            continue;
        };
        if target == "smd" {
            smds.push(bytes.clone());
        }
        let seed = with_companions(path, &bytes);
        let rel = path.strip_prefix(&corpus).unwrap_or(path);
        let name = rel.to_string_lossy().replace(['/', '\\'], "_");
        write(&out.join(target).join(name), &seed);
        written += 1;
    }
    // QC: a script naming a reference and an animation, both corpus SMDs (asked for in that order).
    for (i, smd) in smds.iter().enumerate() {
        let mut seed = format!(
            "$modelname \"seed{i}.mdl\"\n$cd \".\"\n$scale 1.0\n$origin 0 0 0\n\
             $body studio \"ref\"\n$sequence idle \"ref\" fps 30 loop\n\
             $sequence walk \"anim\" LX fps 24\n$attachment 0 \"root\" 1 2 3\n\
             $hbox 0 \"root\" -1 -1 -1 1 1 1\n$eyeposition 0 0 60\n"
        )
        .into_bytes();
        seed.extend_from_slice(SEPARATOR);
        seed.extend_from_slice(smd);
        seed.extend_from_slice(SEPARATOR);
        seed.extend_from_slice(smd);
        write(&out.join("qc").join(format!("seed{i}.qc")), &seed);
        written += 1;
    }
    eprintln!("{written} seeds in {}", out.display());
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            walk(&path, out);
        } else {
            out.push(path);
        }
    }
}

fn target_of(path: &Path) -> Option<&'static str> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    let stem = path.file_stem()?.to_str()?.to_ascii_lowercase();
    Some(match ext.as_str() {
        "ms3d" => "ms3d",
        "gltf" => "gltf",
        "glb" => "glb",
        "obj" => "obj",
        "bvh" => "bvh",
        "sinew" => "sinew",
        // Companions (NAMET.mdl, NAME01.mdl) are read beside their model, not on their own.
        "mdl" if is_companion(path, &stem) => return None,
        "mdl" => "mdl",
        "smd" => "smd",
        "qc" => "qc",
        "pc2" => "pc2",
        "mdd" => "mdd",
        "exr" => "exr",
        _ => return None,
    })
}

/// `NAMET.mdl` or `NAMEnn.mdl` beside a `NAME.mdl`.
fn is_companion(path: &Path, stem: &str) -> bool {
    let base = stem.strip_suffix('t').or_else(|| {
        stem.strip_suffix(|c: char| c.is_ascii_digit())?
            .strip_suffix(|c: char| c.is_ascii_digit())
    });
    base.is_some_and(|b| path.with_file_name(format!("{b}.mdl")).exists())
}

/// The file followed by the companions its reader asks for, in the order it asks.
fn with_companions(path: &Path, bytes: &[u8]) -> Vec<u8> {
    let mut seed = bytes.to_vec();
    let Some(format) = sinew_import::Format::from_path(path) else {
        return seed;
    };
    let asked: RefCell<Vec<Vec<u8>>> = RefCell::new(Vec::new());
    let names: RefCell<Vec<String>> = RefCell::new(Vec::new());
    let beside = sinew_import::beside(path);
    let resolve = |name: &str| {
        let got = beside(name);
        if !names.borrow().iter().any(|n| n == name) {
            names.borrow_mut().push(name.to_string());
            asked
                .borrow_mut()
                .push(got.as_ref().map(|b| b.clone()).unwrap_or_default());
        }
        got
    };
    let name = path.display().to_string();
    // Every companion asked for, even past a missing one.
    let options = sinew_import::ImportOptions {
        allow_missing: true,
        ..Default::default()
    };
    let _ = sinew_import::import_bytes(format, &name, bytes, &resolve, &options);
    for companion in asked.into_inner() {
        seed.extend_from_slice(SEPARATOR);
        seed.extend_from_slice(&companion);
    }
    seed
}

fn write(path: &Path, bytes: &[u8]) {
    if let Some(dir) = path.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    if let Err(e) = std::fs::write(path, bytes) {
        eprintln!("{}: {e}", path.display());
        std::process::exit(1);
    }
}
