//! Compares sinew's LODs with other simplified versions of the same file (gltfpack's, from
//! tools/lod-compare.sh): triangles reached, Hausdorff distance to the original, the same distance
//! with both posed mid-animation, and time.
//!
//! `cargo run --release -p sinew-pipeline --example lod_compare -- [--pose-at F] ORIGINAL [OTHER...]`
//!
//! Every file is read with sinew_import; the distance is the symmetric sampled Hausdorff distance of
//! the test helpers (tests/lod_common.rs), over all meshes of a file as one triangle soup, reported in
//! percent of the original's bounding-box diagonal. Sinew's LODs are built twice: at the nominal
//! targets (0.5, 0.25) and at the ratios the other files reached, so that rows compare equal
//! triangle counts.
//!
//! Posed distances: every file is skinned with its own skeleton and first clip at half the clip's
//! duration (`--pose-at F`: at F times it) ("own clip"; gltfpack resamples animation, so its own clip is not exactly the original's)
//! and, when its skeleton has the original's joint names and inverse bind matrices, also with the
//! original's palette ("original's clip"), which poses both files identically.
//!
//! Time: sinew's whole chain (`generate_lods`, LOD 0's optimisation included), in process, the
//! fastest of 10 runs, each checked to give the same LODs as the first.
//!
//! `--sweep` builds sinew's LODs with one quality knob changed at a time (docs/lod.md).
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod lod_common;

use lod_common::{level_of, same_rig, soup};
use sinew_core::glam::Mat4;
use sinew_import::{import_path, ImportOptions};
use sinew_pipeline::lod::{generate_lods_tuned, LodOptions, LodTuning};
use sinew_scene::Scene;
use sinew_testdata::geometry::{diagonal, hausdorff};
use std::path::Path;
use std::time::Instant;

fn triangles(scene: &Scene, level: Option<usize>) -> usize {
    scene
        .meshes
        .iter()
        .map(|m| level_of(m, level).triangle_count())
        .sum()
}

/// Chain builds timed per row; the fastest is reported.
const TIMING_RUNS: usize = 10;

struct Row {
    tool: String,
    triangles: usize,
    hausdorff: f32,
    posed: Option<f32>,
    /// Posed with the original's palette (sinew rows: the same as `posed`).
    posed_same: Option<f32>,
    seconds: f64,
}

fn print_rows(rows: &[Row], base_tris: usize) {
    println!(
        "| tool | triangles | ratio | Hausdorff (% diag) | posed, own clip (% diag) | posed, original's clip (% diag) | time (ms) |"
    );
    println!("|---|---|---|---|---|---|---|");
    let f = |h: Option<f32>| h.map_or("-".into(), |h| format!("{h:.3}"));
    for r in rows {
        println!(
            "| {} | {} | {:.3} | {:.3} | {} | {} | {:.1} |",
            r.tool,
            r.triangles,
            r.triangles as f64 / base_tris as f64,
            r.hausdorff,
            f(r.posed),
            f(r.posed_same),
            r.seconds * 1e3
        );
    }
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    // `--pose-at F`: pose at F times the clip's duration instead of half of it.
    let mut at = 0.5f32;
    if args.first().map(String::as_str) == Some("--pose-at") {
        match args.get(1).and_then(|f| f.parse::<f32>().ok()) {
            Some(f) if (0.0..=1.0).contains(&f) => at = f,
            _ => {
                eprintln!("--pose-at takes a fraction of the clip's duration, 0 to 1");
                std::process::exit(2);
            }
        }
        args.drain(..2);
    }
    let Some((original, others)) = args.split_first() else {
        eprintln!("usage: lod_compare [--pose-at F] ORIGINAL [OTHER... | --sweep]");
        std::process::exit(2);
    };
    let options = ImportOptions::default();
    let scene = import_path(Path::new(original), &options).expect("import original");
    let (base_p, base_i) = soup(&scene, None, None);
    let diag = diagonal(&base_p);
    let base_tris = base_i.len() / 3;
    let pose = lod_common::pose_palette(&scene, at);
    let posed_base = pose
        .as_ref()
        .map(|(pal, _, _)| soup(&scene, None, Some(pal)));
    println!(
        "{original}: {} meshes, {} vertices, {base_tris} triangles, diagonal {diag:.4}",
        scene.meshes.len(),
        base_p.len()
    );
    if let Some((_, name, t)) = &pose {
        println!("posed: clip {name:?} at t = {t:.3} s");
    }
    let pct = |h: f32| h / diag * 100.0;
    let measure = |s: &Scene, level: Option<usize>, pal: Option<&[Mat4]>| -> (f32, Option<f32>) {
        let (p, i) = soup(s, level, None);
        let h = pct(hausdorff(&base_p, &base_i, &p, &i));
        let posed = match (pal, &posed_base) {
            (Some(pal), Some((bp, bi))) => {
                let (p, i) = soup(s, level, Some(pal));
                Some(pct(hausdorff(bp, bi, &p, &i)))
            }
            _ => None,
        };
        (h, posed)
    };
    let sinew_tuned = |ratios: Vec<f32>,
                       label: &str,
                       tuning: LodTuning,
                       max_error: Option<f32>|
     -> Vec<Row> {
        let mut s = scene.clone();
        let lod_options = LodOptions {
            ratios,
            max_error,
            ..Default::default()
        };
        let reports = generate_lods_tuned(&mut s, &lod_options, &tuning).expect("LODs");
        // Time: the fastest of TIMING_RUNS builds of the whole chain (the machine is shared; the
        // minimum is the least disturbed run). The outputs are identical every run (deterministic).
        let seconds = (0..TIMING_RUNS)
            .map(|_| {
                let mut t = scene.clone();
                let start = Instant::now();
                generate_lods_tuned(&mut t, &lod_options, &tuning).expect("LODs");
                let elapsed = start.elapsed().as_secs_f64();
                assert!(t == s, "LODs differ between runs");
                elapsed
            })
            .fold(f64::INFINITY, f64::min);
        for r in &reports {
            for g in &r.lods {
                println!(
                    "  {label} {}: target {:.3} reached {:.3} error {:.4} (model {:.4}) stopped_by_error_limit {}",
                    r.mesh, g.target_ratio, g.reached_ratio, g.error_relative, g.error_model,
                    g.stopped_by_error_limit
                );
            }
        }
        let pal = pose.as_ref().map(|(p, _, _)| p.as_slice());
        (0..lod_options.ratios.len())
            .map(|k| {
                let (h, posed) = measure(&s, Some(k), pal);
                Row {
                    tool: format!("sinew {label} LOD{}", k + 1),
                    triangles: triangles(&s, Some(k)),
                    hausdorff: h,
                    posed,
                    posed_same: posed,
                    seconds,
                }
            })
            .collect()
    };
    let sinew_rows =
        |ratios: Vec<f32>, label: &str| sinew_tuned(ratios, label, LodTuning::default(), None);
    if others.first().map(String::as_str) == Some("--sweep") {
        // The quality knobs one at a time against the defaults (docs/lod.md).
        let d = LodTuning::default();
        let with = |f: &dyn Fn(&mut LodTuning)| {
            let mut t = d;
            f(&mut t);
            t
        };
        let variants: Vec<(&str, LodTuning, Option<f32>)> = vec![
            ("default", d, None),
            (
                "no-part-anchors",
                with(&|t| t.anchor_part_extremes = false),
                None,
            ),
            ("no-repair", with(&|t| t.repair_far_vertices = false), None),
            ("plain", with(&|t| t.plain_candidate = true), None),
            ("not-permissive", with(&|t| t.permissive = false), None),
            ("from-lod0", with(&|t| t.chain = false), None),
            ("no-regularize", with(&|t| t.regularize = false), None),
            ("pose-0", with(&|t| t.pose_weight = 0.0), None),
            ("pose-1", with(&|t| t.pose_weight = 1.0), None),
            ("pose-8", with(&|t| t.pose_weight = 8.0), None),
            ("normal-0", with(&|t| t.normal_weight = 0.0), None),
            ("normal-0.5", with(&|t| t.normal_weight = 0.5), None),
            ("uv-0", with(&|t| t.uv_weight = 0.0), None),
            ("uv-2", with(&|t| t.uv_weight = 2.0), None),
            (
                "attrs-0",
                with(&|t| {
                    t.normal_weight = 0.0;
                    t.uv_weight = 0.0;
                    t.pose_weight = 0.0;
                }),
                None,
            ),
            (
                "previous-default",
                with(&|t| {
                    t.normal_weight = 0.5;
                    t.pose_weight = 1.0;
                    t.permissive = false;
                }),
                None,
            ),
            ("per-material", with(&|t| t.whole_mesh = false), None),
            ("max-error-0.02", d, Some(0.02)),
            ("max-error-0.1", d, Some(0.1)),
        ];
        let mut rows = Vec::new();
        for (label, tuning, max_error) in variants {
            rows.extend(sinew_tuned(vec![0.5, 0.25], label, tuning, max_error));
        }
        print_rows(&rows, base_tris);
        return;
    }
    let mut rows = sinew_rows(vec![0.5, 0.25], "nominal");
    let mut reached = Vec::new();
    for other in others {
        let o = import_path(Path::new(other), &options).expect("import other");
        let tris = triangles(&o, None);
        let opose = lod_common::pose_palette(&o, at);
        let (h, posed) = measure(&o, None, opose.as_ref().map(|(p, _, _)| p.as_slice()));
        let posed_same = match (&pose, same_rig(&scene, &o, 1e-5)) {
            (Some((pal, _, _)), true) => measure(&o, None, Some(pal)).1,
            _ => None,
        };
        let name = Path::new(other)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        rows.push(Row {
            tool: format!("other {name}"),
            triangles: tris,
            hausdorff: h,
            posed,
            posed_same,
            seconds: f64::NAN,
        });
        reached.push(tris as f32 / base_tris as f32);
    }
    if !reached.is_empty() {
        let mut ratios = reached.clone();
        ratios.sort_by(|a, b| b.total_cmp(a));
        let ratios: Vec<f32> = ratios.into_iter().map(|r| r.clamp(1e-4, 1.0)).collect();
        rows.extend(sinew_rows(ratios, "matched"));
    }
    print_rows(&rows, base_tris);
}
