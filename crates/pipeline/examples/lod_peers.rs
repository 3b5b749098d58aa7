//! sinew's LODs against native gltfpack at equal triangle counts, per mesh, at rest and posed
//! (docs/lod.md, "Against gltfpack at equal triangle counts"; driven by tools/lod-compare.sh).
//!
//! `cargo run --release -p sinew-pipeline --example lod_peers -- --gltfpack PATH [--pose-at F]...
//! [--min-triangles N] [--plain] [--plain-work N] FILE.glb|FILE.gltf...` (`--plain`: with the
//! plain builds of `convert --effort max` on every mesh, `LodTuning::plain_candidate`;
//! `--plain-work N`: on the meshes whose `lod::plain_work` is at most N, default
//! `lod::PLAIN_WORK_BOUND`)
//!
//! For each glTF file (other formats: export them first with `sinew export FILE -o FILE.glb`, which
//! is then the reference for both tools) and each of its meshes of at least N triangles (default
//! 24) it prints one JSON object per line:
//! - `"tool":"sinew"`: sinew's default chain (`LodOptions::default()`): each level's triangles,
//!   reported error and measured distances;
//! - `"tool":"gltfpack"`: for each gltfpack setting (`-si 0.5` and `-si 0.25`: `si`; the same with
//!   `-sa`: `si-sa`; always `-kn -noq`, so that meshes are kept apart and unquantized), gltfpack's
//!   mesh at that level and sinew's chain of that mesh built at the triangle counts gltfpack reached
//!   (`matched_*`).
//!
//! Distances: the symmetric sampled Hausdorff distance of `sinew_testdata::geometry` (vertices,
//! centroids, edge midpoints of each mesh against the other's surface), in % of the mesh's LOD 0
//! bind-pose bounding-box diagonal; `posed` with both skinned by the reference's first clip at each
//! `--pose-at` fraction of its duration (default 0.5; `C.F`, C of 1 or more: clip C, counted from 0,
//! at fraction F, a pose of a clip the file lacks left out), with the reference's palette when
//! gltfpack's output has the same joints and inverse bind matrices, else with its own first clip at
//! the same time.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod lod_common;

use lod_common::{pose_palette, same_rig, soup};
use sinew_core::glam::{Mat4, Vec3};
use sinew_import::{import_path, ImportOptions};
use sinew_pipeline::lod::{
    generate_lods_tuned, largest_range_scale, plain_work, scene_motion, LodOptions, LodTuning,
};
use sinew_scene::Scene;
use sinew_testdata::geometry::{diagonal, hausdorff};
use std::path::{Path, PathBuf};
use std::process::Command;

fn triangles(scene: &Scene, level: Option<usize>) -> usize {
    soup(scene, level, None).1.len() / 3
}

/// A mesh (or soup) as positions and triangle indices.
type Soup = (Vec<Vec3>, Vec<u32>);

struct Reference {
    scene: Scene,
    rest: Soup,
    diag: f32,
    /// Per pose fraction: its palette and LOD 0 posed.
    poses: Vec<(f32, Vec<Mat4>, Soup)>,
}

impl Reference {
    /// Rest and posed distances (% of the diagonal) of `other`'s `level` (None: its LOD 0).
    fn measure(&self, other: &Scene, level: Option<usize>, own_rig: bool) -> (f32, Vec<f32>) {
        let pct = |h: f32| h / self.diag * 100.0;
        let (p, i) = soup(other, level, None);
        let rest = pct(hausdorff(&self.rest.0, &self.rest.1, &p, &i));
        let posed = self
            .poses
            .iter()
            .map(|(at, pal, (bp, bi))| {
                let own;
                let pal: &[Mat4] = if own_rig {
                    pal
                } else {
                    own = pose_palette(other, *at).map(|p| p.0).unwrap_or_default();
                    &own
                };
                let (p, i) = soup(other, level, Some(pal));
                pct(hausdorff(bp, bi, &p, &i))
            })
            .collect();
        (rest, posed)
    }
}

fn json_f(v: f32) -> String {
    if v.is_finite() {
        format!("{v:.4}")
    } else {
        "null".into()
    }
}

fn json_list(v: &[f32]) -> String {
    format!(
        "[{}]",
        v.iter().map(|x| json_f(*x)).collect::<Vec<_>>().join(",")
    )
}

/// Runs gltfpack; returns its output scene, or None when it failed.
fn gltfpack(exe: &Path, input: &Path, out: &Path, args: &[String]) -> Option<Scene> {
    let status = Command::new(exe)
        .arg("-i")
        .arg(input)
        .arg("-o")
        .arg(out)
        .args(args)
        .arg("-noq")
        .output()
        .ok()?;
    if !status.status.success() {
        eprintln!("gltfpack {args:?} failed on {}", input.display());
        return None;
    }
    import_path(out, &ImportOptions::default()).ok()
}

/// One mesh as a scene (the file's skeleton and clips kept), for per-mesh measurements.
fn only(scene: &Scene, mesh: usize) -> Scene {
    let mut s = scene.clone();
    s.meshes = vec![scene.meshes[mesh].clone()];
    s
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut exe = None;
    let mut ats = Vec::new();
    let mut files = Vec::new();
    let mut min_tris = 24usize;
    let mut tuning = LodTuning::default();
    while !args.is_empty() {
        let a = args.remove(0);
        match a.as_str() {
            "--gltfpack" => exe = Some(PathBuf::from(args.remove(0))),
            "--pose-at" => ats.push(args.remove(0).parse::<f32>().expect("--pose-at F")),
            "--min-triangles" => min_tris = args.remove(0).parse().expect("--min-triangles N"),
            "--plain" => tuning.plain_candidate = true,
            "--plain-work" => {
                tuning.plain_work_bound = args.remove(0).parse().expect("--plain-work N")
            }
            _ => files.push(PathBuf::from(a)),
        }
    }
    if ats.is_empty() {
        ats.push(0.5);
    }
    let exe = exe.expect("--gltfpack PATH");
    let tmp = std::env::temp_dir().join(format!("lod_peers_{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let settings: [(&str, [&str; 2], bool); 2] = [
        ("si", ["0.5", "0.25"], false),
        ("si-sa", ["0.5", "0.25"], true),
    ];
    for file in &files {
        let Ok(scene) = import_path(file, &ImportOptions::default()) else {
            eprintln!("{}: import failed", file.display());
            continue;
        };
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        // gltfpack's outputs, meshes kept apart (`-kn`), per setting and level.
        let mut outs: Vec<(String, Vec<Option<Scene>>)> = Vec::new();
        for (label, ratios, sa) in settings {
            let runs = ratios
                .iter()
                .enumerate()
                .map(|(k, r)| {
                    let mut a: Vec<String> = vec!["-si".into(), (*r).into(), "-kn".into()];
                    if sa {
                        a.push("-sa".into());
                    }
                    let out = tmp.join(format!("{label}_{k}.glb"));
                    gltfpack(&exe, file, &out, &a).filter(|o| o.meshes.len() == scene.meshes.len())
                })
                .collect();
            outs.push((label.into(), runs));
        }
        // The chains at gltfpack's counts are built one mesh apart from the file's others,
        // with the file's largest material range as the scene's, as in the file.
        let apart = LodTuning {
            scene_scale: Some(
                scene
                    .meshes
                    .iter()
                    .map(largest_range_scale)
                    .fold(0.0, f32::max),
            ),
            ..tuning
        };
        // sinew's default chain, every mesh.
        let mut s = scene.clone();
        generate_lods_tuned(&mut s, &LodOptions::default(), &tuning).expect("LODs");
        for (mi, mesh) in scene.meshes.iter().enumerate() {
            let base = mesh.geometry.triangle_count();
            if base < min_tris {
                continue;
            }
            let one = only(&scene, mi);
            let rest = soup(&one, None, None);
            let diag = diagonal(&rest.0);
            let poses = ats
                .iter()
                .filter_map(|&at| {
                    let pal = pose_palette(&scene, at)?.0;
                    let posed = soup(&one, None, Some(&pal));
                    Some((at, pal, posed))
                })
                .collect();
            let r = Reference {
                scene: one,
                rest,
                diag,
                poses,
            };
            let mname = mesh.name.replace('"', "'");
            let sinew_one = only(&s, mi);
            let motion = scene_motion(&scene.clips, scene.skeleton.as_ref());
            let work = plain_work(&mesh.geometry, scene.skeleton.as_ref(), &motion.poses);
            for k in 0..sinew_one.meshes[0].lods.len() {
                let (rest, posed) = r.measure(&sinew_one, Some(k), true);
                println!(
                    "{{\"file\":\"{name}\",\"mesh\":\"{mname}\",\"base\":{base},\"tool\":\"sinew\",\"plain_work\":{work},\"level\":{},\"triangles\":{},\"error\":{},\"rest\":{},\"posed\":{}}}",
                    k + 1,
                    sinew_one.meshes[0].lods[k].lod.triangle_count(),
                    json_f(sinew_one.meshes[0].lods[k].error_relative),
                    json_f(rest),
                    json_list(&posed)
                );
            }
            for (label, runs) in &outs {
                if runs.iter().any(Option::is_none) {
                    continue;
                }
                let g: Vec<Scene> = runs.iter().flatten().map(|o| only(o, mi)).collect();
                let counts: Vec<usize> = g.iter().map(|o| triangles(o, None)).collect();
                if counts.contains(&0) {
                    continue;
                }
                // sinew at gltfpack's counts: this mesh's chain with the error limit lifted.
                let mut ratios: Vec<f32> = counts
                    .iter()
                    .map(|&c| (c as f32 / base as f32).clamp(1e-4, 1.0))
                    .collect();
                for k in 1..ratios.len() {
                    ratios[k] = ratios[k].min(ratios[k - 1]);
                }
                let mut m = r.scene.clone();
                let options = LodOptions {
                    ratios,
                    max_error: None,
                    ..Default::default()
                };
                generate_lods_tuned(&mut m, &options, &apart).expect("matched LODs");
                for (k, o) in g.iter().enumerate() {
                    let rig = same_rig(&r.scene, o, 1e-4);
                    let (g_rest, g_posed) = r.measure(o, None, rig);
                    let (s_rest, s_posed) = r.measure(&m, Some(k), true);
                    let s_tris = m.meshes[0]
                        .lods
                        .get(k)
                        .or(m.meshes[0].lods.last())
                        .map_or(base, |l| l.lod.triangle_count());
                    println!(
                        "{{\"file\":\"{name}\",\"mesh\":\"{mname}\",\"base\":{base},\"tool\":\"gltfpack\",\"setting\":\"{label}\",\"level\":{},\"triangles\":{},\"rest\":{},\"posed\":{},\"same_rig\":{rig},\"matched_triangles\":{s_tris},\"matched_rest\":{},\"matched_posed\":{}}}",
                        k + 1,
                        counts[k],
                        json_f(g_rest),
                        json_list(&g_posed),
                        json_f(s_rest),
                        json_list(&s_posed)
                    );
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&tmp);
}
