//! The house rules of the source tree, checked on every test run (docs/architecture.md):
//! - no two source files of a crate use each other (no import circles, counting `crate::`, `super::`
//!   and child-module paths anywhere in the file, not only in `use` lines);
//! - no source file over 1,000 lines unless its head comment says why it is kept as one file;
//! - crates depend only down the chain `cli -> pipeline, import -> scene -> core`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const CRATE_SOURCES: [&str; 6] = [
    "crates/core/src",
    "crates/scene/src",
    "crates/import/src",
    "crates/pipeline/src",
    "cli/src",
    "tests/src",
];

fn root() -> PathBuf {
    sinew_testdata::workspace_root()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            if p.file_name().is_some_and(|n| n == "target") {
                continue;
            }
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The module path of a file relative to its crate's `src` (`clip/mod.rs` -> `["clip"]`).
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// Text without `//` comments (doc links are not uses) and without string literals' contents.
fn code_of(text: &str) -> String {
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Every `prefix::a::b::{c, d::e}` path in `code`, as segment lists after the prefix.
fn paths_after(code: &str, prefix: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    let mut start = 0;
    while let Some(i) = code[start..].find(prefix) {
        let at = start + i;
        start = at + prefix.len();
        if at > 0 && (is_ident(bytes[at - 1] as char) || bytes[at - 1] == b':') {
            continue;
        }
        let rest = &code[start..];
        let mut segs = Vec::new();
        let mut chars = rest.char_indices().peekable();
        let mut cur = String::new();
        let mut group_at = None;
        while let Some((k, c)) = chars.next() {
            if is_ident(c) {
                cur.push(c);
            } else if c == ':' && chars.peek().map(|p| p.1) == Some(':') {
                chars.next();
                if !cur.is_empty() {
                    segs.push(std::mem::take(&mut cur));
                }
            } else if c == '{' && cur.is_empty() {
                group_at = Some(k + 1);
                break;
            } else {
                break;
            }
        }
        if !cur.is_empty() {
            segs.push(cur);
        }
        match group_at {
            Some(g) => {
                let inner = &rest[g..];
                let end = inner.find('}').unwrap_or(inner.len());
                for item in inner[..end].split(',') {
                    let item: Vec<String> = item
                        .trim()
                        .split("::")
                        .map(|s| s.trim().trim_start_matches('{').to_string())
                        .filter(|s| !s.is_empty() && s.chars().all(is_ident))
                        .collect();
                    let mut full = segs.clone();
                    full.extend(item);
                    out.push(full);
                }
            }
            None => out.push(segs),
        }
    }
    out
}

/// The files of one crate and, for each, the other files of the crate it refers to.
fn crate_graph(src: &Path) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let by_module: BTreeMap<Vec<String>, PathBuf> = files
        .iter()
        .map(|f| (module_path(src, f), f.clone()))
        .collect();
    let resolve = |path: &[String]| -> Option<&PathBuf> {
        (1..=path.len())
            .rev()
            .find_map(|k| by_module.get(&path[..k]))
    };
    let mut graph = BTreeMap::new();
    for f in &files {
        let me = module_path(src, f);
        let code = code_of(&std::fs::read_to_string(f).unwrap());
        let mut targets = BTreeSet::new();
        let mut refer = |full: Vec<String>| {
            if let Some(t) = resolve(&full) {
                if t != f {
                    targets.insert(t.clone());
                }
            }
        };
        for p in paths_after(&code, "crate::") {
            refer(p);
        }
        // `super::` from `a/b.rs` (module a::b) names module `a`'s items.
        let parent: Vec<String> = me[..me.len().saturating_sub(1)].to_vec();
        for p in paths_after(&code, "super::") {
            let mut full = parent.clone();
            full.extend(p);
            refer(full);
        }
        // Child modules declared here and used by their relative name.
        for line in code.lines() {
            let t = line.trim_start();
            let t = t
                .strip_prefix("pub(crate) ")
                .or_else(|| t.strip_prefix("pub(super) "))
                .or_else(|| t.strip_prefix("pub "))
                .unwrap_or(t);
            if let Some(name) = t.strip_prefix("mod ").and_then(|r| r.strip_suffix(';')) {
                for p in paths_after(&code, &format!("{name}::")) {
                    let mut full = me.clone();
                    full.push(name.to_string());
                    full.extend(p);
                    refer(full);
                }
            }
        }
        graph.insert(f.clone(), targets);
    }
    graph
}

#[test]
fn no_two_files_of_a_crate_use_each_other() {
    let root = root();
    let mut circles = Vec::new();
    for src in CRATE_SOURCES {
        let graph = crate_graph(&root.join(src));
        for (a, targets) in &graph {
            for b in targets {
                if a < b && graph.get(b).is_some_and(|t| t.contains(a)) {
                    circles.push(format!(
                        "{} <-> {}",
                        a.strip_prefix(&root).unwrap().display(),
                        b.strip_prefix(&root).unwrap().display()
                    ));
                }
            }
        }
    }
    assert!(
        circles.is_empty(),
        "import circles:\n{}",
        circles.join("\n")
    );
}

#[test]
fn the_circle_check_sees_a_circle() {
    // The checker itself, on a made-up crate: a.rs uses b through `crate::`, b.rs uses a in a body.
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    std::fs::write(src.join("lib.rs"), "mod a;\nmod b;\n").unwrap();
    std::fs::write(src.join("a.rs"), "use crate::b::Thing;\n").unwrap();
    std::fs::write(src.join("b.rs"), "fn f() { crate::a::g(); }\n").unwrap();
    let graph = crate_graph(src);
    assert!(graph[&src.join("a.rs")].contains(&src.join("b.rs")));
    assert!(graph[&src.join("b.rs")].contains(&src.join("a.rs")));
    // A facade that re-exports its children, and children that use each other one way only.
    std::fs::write(
        src.join("b.rs"),
        "// crate::a::g() in a comment is no use\n",
    )
    .unwrap();
    let graph = crate_graph(src);
    assert!(!graph[&src.join("b.rs")].contains(&src.join("a.rs")));
    assert!(graph[&src.join("lib.rs")].is_empty());
}

#[test]
fn no_source_file_over_a_thousand_lines_without_a_reason() {
    let root = root();
    let mut files = Vec::new();
    for dir in ["crates", "cli", "tests", "fixtures"] {
        rust_files(&root.join(dir), &mut files);
    }
    assert!(files.len() > 50, "found only {} files", files.len());
    let long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            let lines = text.lines().count();
            let head: String = text
                .lines()
                .take_while(|l| l.starts_with("//"))
                .collect::<Vec<_>>()
                .join("\n");
            (lines > 1000 && !head.contains("Kept as one file")).then(|| {
                format!(
                    "{} ({lines} lines)",
                    f.strip_prefix(&root).unwrap().display()
                )
            })
        })
        .collect();
    assert!(
        long.is_empty(),
        "files over 1,000 lines without a `Kept as one file` head comment:\n{}",
        long.join("\n")
    );
}

/// The `sinew-*` packages a manifest depends on (normal dependencies only).
fn sinew_dependencies(manifest: &Path) -> BTreeSet<String> {
    let text = std::fs::read_to_string(manifest).unwrap();
    let mut in_deps = false;
    let mut out = BTreeSet::new();
    for line in text.lines() {
        let t = line.trim();
        if t.starts_with('[') {
            in_deps = t == "[dependencies]";
            continue;
        }
        if in_deps && t.starts_with("sinew-") {
            out.insert(t.split(['.', ' ', '=']).next().unwrap().to_string());
        }
    }
    out
}

#[test]
fn crates_depend_only_down_the_chain() {
    let root = root();
    let allowed: [(&str, &[&str]); 5] = [
        ("crates/core", &[]),
        ("crates/scene", &["sinew-core"]),
        ("crates/import", &["sinew-core", "sinew-scene"]),
        ("crates/pipeline", &["sinew-core", "sinew-scene"]),
        (
            "cli",
            &[
                "sinew-core",
                "sinew-scene",
                "sinew-import",
                "sinew-pipeline",
            ],
        ),
    ];
    for (dir, ok) in allowed {
        let deps = sinew_dependencies(&root.join(dir).join("Cargo.toml"));
        for d in &deps {
            assert!(ok.contains(&d.as_str()), "{dir} depends on {d}");
        }
    }
    // The runtime core has no dependency that does I/O or offline work.
    let core = std::fs::read_to_string(root.join("crates/core/Cargo.toml")).unwrap();
    for banned in [
        "gltf", "exr", "meshopt", "rayon", "serde", "clap", "tempfile",
    ] {
        let deps = core.split("[dev-dependencies]").next().unwrap();
        assert!(
            !deps.lines().any(|l| l.trim().starts_with(banned)),
            "sinew-core depends on {banned}"
        );
    }
}

/// Each package links its integration tests into one binary (`autotests = false`): a file in its
/// `tests/` that is neither a `mod` of that binary's root nor a `[[test]]` of its own would never be
/// compiled, and its tests would silently stop running.
#[test]
fn every_integration_test_file_is_compiled() {
    // Every workspace member with a `tests/` folder (the root manifest's `members = [...]`).
    let workspace = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let members_line = workspace
        .lines()
        .find(|l| l.starts_with("members = ["))
        .unwrap();
    let packages: Vec<&str> = members_line
        .split('"')
        .skip(1)
        .step_by(2)
        .filter(|m| root().join(m).join("tests").is_dir())
        .collect();
    assert!(packages.len() >= 5, "{packages:?}");
    let mut checked = 0;
    for package in packages {
        let dir = root().join(package);
        let manifest = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
        assert!(manifest.contains("autotests = false"), "{package}");
        // The roots: every `path = "tests/..."` of a [[test]].
        let roots: Vec<String> = manifest
            .lines()
            .filter_map(|l| l.trim().strip_prefix("path = \"tests/"))
            .map(|rest| rest.trim_end_matches('"').to_string())
            .collect();
        assert!(!roots.is_empty(), "{package} declares no [[test]]");
        let declared: BTreeSet<String> = roots
            .iter()
            .flat_map(|r| {
                let text = std::fs::read_to_string(dir.join("tests").join(r)).unwrap();
                text.lines()
                    .filter_map(|l| l.trim().strip_prefix("mod "))
                    .map(|m| m.trim_end_matches(';').to_string())
                    .collect::<Vec<_>>()
            })
            .collect();
        for entry in std::fs::read_dir(dir.join("tests")).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            let Some(stem) = name.strip_suffix(".rs") else {
                continue;
            };
            assert!(
                roots.contains(&name) || declared.contains(stem),
                "{package}/tests/{name} is not compiled: add `mod {stem};` to the package's test root"
            );
            checked += 1;
        }
    }
    // 6 + 17 + 8 + 6 + 28 files and the five roots, as of session 38.
    assert!(checked >= 70, "{checked} test files seen");
}
