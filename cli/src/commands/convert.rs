//! `sinew convert INPUT... (-o OUT | --out-dir DIR)`: import, bind motions, cut, split, LODs, compile,
//! write atomically. Several inputs run in parallel (rayon); one bad file does not stop the others.
//!
//! The JSON report is [`ConvertReport`]; the per-output part, [`OutputDetails`], is shared with `split`
//! and `lod`. Field names are a stable interface documented in docs/cli.md.

use crate::batch::{self, Job};
use crate::cli::ConvertArgs;
use crate::output::{check_output_path, write_atomic, Ctx};
use crate::report::{
    clip_report, diag_report, mesh_report, num, ClipOut, ConvertReport, FileReport, MeshOut,
    NotBuiltReport, OutputDetails,
};
use crate::report::{MotionReport, SplitReport};
use crate::steps::{self, MappingFile, SplitPlan};
use crate::Status;
use anyhow::{anyhow, bail};
use sinew_core::Skeleton;
use sinew_pipeline::compile::{compile_compressed, compress_clips, CompileReport, CompressedClips};
use sinew_pipeline::compress::CompressOptions;
use sinew_pipeline::lod::LodOptions;
use sinew_pipeline::retarget::RetargetOptions;
use sinew_scene::{NotBuiltReason, Scene, SceneClip};
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::Path;

/// Builds the details of an output from the final scene and what writing it reported.
pub fn details(
    scene: &Scene,
    written: Written,
    motions: Vec<MotionReport>,
    cuts: Vec<String>,
    splits: Vec<SplitReport>,
) -> OutputDetails {
    let Written { bytes, report } = written;
    let mut compression = report.clips.into_iter();
    OutputDetails {
        bytes,
        format: scene.source_format.name(),
        joints: scene.skeleton.as_ref().map_or(0, |s| s.len()),
        meshes: scene
            .meshes
            .iter()
            .map(|m| {
                let r = mesh_report(m);
                MeshOut {
                    name: r.name,
                    vertices: r.vertices,
                    triangles: r.triangles,
                    lods: r.lods,
                    lods_not_built: m.lods_not_built.iter().map(not_built_report).collect(),
                }
            })
            .collect(),
        clips: scene
            .clips
            .iter()
            .map(|c| {
                let r = clip_report(c, scene.skeleton.as_ref());
                ClipOut {
                    name: r.name,
                    duration: r.duration,
                    sample_rate: r.sample_rate,
                    key_times: r.key_times,
                    keys: r.keys,
                    driven_joints: r.driven_joints.len(),
                    compression: compression.next(),
                }
            })
            .collect(),
        motions,
        cuts,
        splits,
        diagnostics: scene.diagnostics.iter().map(diag_report).collect(),
        textures: Vec::new(),
    }
}

/// The report of a LOD level not built.
fn not_built_report(n: &sinew_scene::NotBuiltLod) -> NotBuiltReport {
    NotBuiltReport {
        level: n.level,
        target_ratio: n.target_ratio,
        previous_triangles: n.previous_triangles,
        reached_triangles: n.reached_triangles,
        reason: match n.reason {
            NotBuiltReason::ErrorLimit => "error-limit",
            NotBuiltReason::NoCollapse => "no-collapse",
            NotBuiltReason::PreviousNotBuilt => "previous-not-built",
        },
    }
}

/// What [`write_scene`] wrote.
#[derive(Debug, Default)]
pub struct Written {
    /// Size of the file, bytes.
    pub bytes: u64,
    /// Per-clip compression figures (empty without compression).
    pub report: CompileReport,
}

/// Compiles a scene (compressing its clips with `compress`, plain f32 clips for `None`) and writes it
/// atomically.
pub fn write_scene(
    scene: &Scene,
    input: &str,
    output: &Path,
    compress: Option<&CompressOptions>,
) -> anyhow::Result<Written> {
    let compressed = compress_scene_clips(&scene.clips, scene.skeleton.as_ref(), input, compress)?;
    write_compressed(scene, input, output, compressed)
}

/// The clip half of [`write_scene`]: a scene's clips compiled and compressed (`None` without
/// compression); `skeleton` is the scene's.
fn compress_scene_clips(
    clips: &[SceneClip],
    skeleton: Option<&Skeleton>,
    input: &str,
    compress: Option<&CompressOptions>,
) -> anyhow::Result<Option<CompressedClips>> {
    compress
        .map(|o| compress_clips(clips, skeleton, o))
        .transpose()
        .map_err(|e| anyhow!("{input}: compiling: {e}"))
}

/// The rest of [`write_scene`], with the clips [`compress_scene_clips`] gave for this scene.
fn write_compressed(
    scene: &Scene,
    input: &str,
    output: &Path,
    compressed: Option<CompressedClips>,
) -> anyhow::Result<Written> {
    let (asset, report) =
        compile_compressed(scene, compressed).map_err(|e| anyhow!("{input}: compiling: {e}"))?;
    let bytes = sinew_core::format::write(&asset).map_err(|e| anyhow!("{input}: writing: {e}"))?;
    write_atomic(output, &bytes)?;
    Ok(Written {
        bytes: bytes.len() as u64,
        report,
    })
}

/// Everything prepared once for all inputs.
struct Plan {
    import: crate::cli::ImportArgs,
    anims: Vec<(String, Scene)>,
    map: Option<MappingFile>,
    retarget: Option<RetargetOptions>,
    clips: Option<String>,
    split: SplitPlan,
    lod: Option<LodOptions>,
    compress: Option<CompressOptions>,
    textures: bool,
}

fn convert_one(job: &Job, plan: &Plan) -> anyhow::Result<OutputDetails> {
    let (input, output) = (&job.input, &job.output);
    let label = input.display().to_string();
    let mut scene = match job.format {
        Some(format) => crate::input::import_as(input, format, &plan.import)?,
        None => crate::input::import(input, &plan.import)?,
    };
    let cuts = match &plan.clips {
        Some(spec) => steps::cut(&mut scene, spec, &label)?,
        None => Vec::new(),
    };
    let mut motions = Vec::new();
    for (motion_label, motion) in &plan.anims {
        motions.push(steps::bind_motion(
            &mut scene,
            &label,
            motion,
            motion_label,
            plan.map.as_ref(),
            plan.retarget.as_ref(),
        )?);
    }
    let splits = steps::split(&mut scene, &plan.split, &label)?;
    // LODs (meshes) and clip compression (clips) read and write different parts of the scene and
    // are the two costly steps: they run at the same time. Each gives what it gives alone; a LOD
    // error is reported first, as when they ran in turn.
    let (lods, compressed) = rayon::join(
        || {
            steps::mesh_lods(
                &mut scene.meshes,
                scene.skeleton.as_ref(),
                plan.lod.as_ref(),
                &label,
            )
        },
        || {
            compress_scene_clips(
                &scene.clips,
                scene.skeleton.as_ref(),
                &label,
                plan.compress.as_ref(),
            )
        },
    );
    lods?;
    let compressed = compressed?;
    if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow!("{}: cannot create the folder: {e}", dir.display()))?;
    }
    // Textures first: a written .sinew always has its textures beside it.
    let mut textures = Vec::new();
    if plan.textures && !scene.images.is_empty() {
        let stem = output
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let files = sinew_pipeline::texture::textures_for_output(&mut scene, &stem)
            .map_err(|e| anyhow!("{label}: {e}"))?;
        for (name, bytes) in files {
            let path = output.with_file_name(&name);
            write_atomic(&path, &bytes)?;
            textures.push(path.display().to_string());
        }
    }
    let written = write_compressed(&scene, &label, output, compressed)?;
    let mut d = details(&scene, written, motions, cuts, splits);
    d.textures = textures;
    Ok(d)
}

/// Runs `sinew convert`.
pub fn run(args: &ConvertArgs, ctx: &Ctx) -> anyhow::Result<Status> {
    // Options first: anything wrong here is a usage error (exit 2) before any work.
    let lod = steps::lod_options(&args.lod)?;
    let split = SplitPlan::parse(&args.split)?;
    let compress = steps::compress_options(&args.compress)?;
    if let Some(spec) = &args.clips {
        sinew_pipeline::cut::parse_cut_spec(spec).map_err(|e| anyhow!("--clips: {e}"))?;
    }
    if args.jobs == Some(0) {
        bail!("--jobs: must be at least 1");
    }
    if args.map.is_some() && args.anim.is_empty() {
        bail!("--map: needs at least one --anim motion file to apply to");
    }
    if args.retarget && args.anim.is_empty() {
        bail!("--retarget: needs at least one --anim motion file");
    }
    if let Some(k) = args.root_scale {
        if !k.is_finite() || k <= 0.0 {
            bail!("--root-scale: {k} is not usable: it must be a finite number above 0");
        }
    }
    let jobs: Vec<Job> = match (&args.output, &args.out_dir) {
        (Some(o), None) => {
            if args.inputs.len() != 1 {
                bail!(
                    "-o/--output takes exactly one input ({} given); use --out-dir DIR for several",
                    args.inputs.len()
                );
            }
            if args.inputs[0].is_dir() {
                bail!(
                    "{}: is a folder; convert folders with --out-dir DIR",
                    args.inputs[0].display()
                );
            }
            check_output_path(o)?;
            vec![Job {
                input: args.inputs[0].clone(),
                output: o.clone(),
                format: None,
            }]
        }
        (None, Some(dir)) => {
            if dir.exists() && !dir.is_dir() {
                bail!("{}: --out-dir is a file, not a folder", dir.display());
            }
            let jobs = batch::plan(&args.inputs, dir, &args.import)?;
            std::fs::create_dir_all(dir)
                .map_err(|e| anyhow!("{}: cannot create the output folder: {e}", dir.display()))?;
            jobs
        }
        _ => bail!("convert: give -o OUT.sinew (one input) or --out-dir DIR"),
    };
    let map = args.map.as_deref().map(MappingFile::read).transpose()?;
    let mut anims = Vec::with_capacity(args.anim.len());
    for a in &args.anim {
        anims.push((
            a.display().to_string(),
            crate::input::import(a, &args.import)?,
        ));
    }
    let plan = Plan {
        import: args.import.clone(),
        anims,
        map,
        retarget: args.retarget.then_some(RetargetOptions {
            root_scale: args.root_scale,
        }),
        clips: args.clips.clone(),
        split,
        lod,
        compress,
        textures: !args.no_textures,
    };

    // One input with -o: an error is the command's error (exit 2, one line).
    if args.output.is_some() {
        let job = &jobs[0];
        let d = convert_one(job, &plan)?;
        let file = FileReport {
            input: job.input.display().to_string(),
            output: job.output.display().to_string(),
            status: "converted",
            error: None,
            details: Some(d),
        };
        let report = ConvertReport {
            inputs: 1,
            converted: 1,
            failed: 0,
            files: vec![file],
        };
        emit(&report, ctx)?;
        return Ok(Status::Success);
    }

    // Batch.
    let bar = (!ctx.quiet && std::io::stderr().is_terminal()).then(|| {
        let b = indicatif::ProgressBar::with_draw_target(
            Some(jobs.len() as u64),
            indicatif::ProgressDrawTarget::stderr(),
        );
        if let Ok(style) =
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} files, {elapsed} {msg}")
        {
            b.set_style(style);
        }
        b
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.jobs.unwrap_or(0))
        .build()
        .map_err(|e| anyhow!("--jobs: cannot start worker threads: {e}"))?;
    // Largest inputs first (by file size), each worker taking the next job when it is free, so one
    // long file starts early instead of serialising the end of the batch. Reports keep input order.
    let order = largest_first(&jobs);
    let next = std::sync::atomic::AtomicUsize::new(0);
    let slots: Vec<std::sync::Mutex<Option<FileReport>>> =
        jobs.iter().map(|_| std::sync::Mutex::new(None)).collect();
    let workers = pool.current_num_threads().min(jobs.len()).max(1);
    pool.scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|_| loop {
                let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(&i) = order.get(k) else {
                    break;
                };
                let job = &jobs[i];
                let result = convert_one(job, &plan);
                if let Some(b) = &bar {
                    b.inc(1);
                }
                let (status, error, details) = match result {
                    Ok(d) => ("converted", None, Some(d)),
                    Err(e) => ("failed", Some(crate::output::one_line(&e)), None),
                };
                let report = FileReport {
                    input: job.input.display().to_string(),
                    output: job.output.display().to_string(),
                    status,
                    error,
                    details,
                };
                if let Ok(mut slot) = slots[i].lock() {
                    *slot = Some(report);
                }
            });
        }
    });
    let files: Vec<FileReport> = slots
        .into_iter()
        .zip(&jobs)
        .map(|(slot, job)| {
            slot.into_inner()
                .ok()
                .flatten()
                .unwrap_or_else(|| FileReport {
                    input: job.input.display().to_string(),
                    output: job.output.display().to_string(),
                    status: "failed",
                    error: Some(format!(
                        "{}: the worker converting it stopped",
                        job.input.display()
                    )),
                    details: None,
                })
        })
        .collect();
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let failed = files.iter().filter(|f| f.error.is_some()).count();
    let report = ConvertReport {
        inputs: files.len(),
        converted: files.len() - failed,
        failed,
        files,
    };
    emit(&report, ctx)?;
    // Failures are errors: listed on stderr even with --quiet or --json (not when a library caller
    // collects the report: they are in it).
    for f in &report.files {
        if let (Some(e), true) = (&f.error, ctx.stderr()) {
            eprintln!("sinew: error: {e}");
        }
    }
    if failed > 0 {
        if !ctx.quiet && ctx.stderr() {
            eprintln!(
                "sinew: {failed} of {} files failed; {} converted",
                report.inputs, report.converted
            );
        }
        return Ok(Status::CheckFailed);
    }
    Ok(Status::Success)
}

/// Job indices, largest input file first (ties keep input order): the longest-processing-time-first
/// rule, which keeps one long file from running alone at the end of a batch.
fn largest_first(jobs: &[Job]) -> Vec<usize> {
    let size = |j: &Job| std::fs::metadata(&j.input).map_or(0, |m| m.len());
    let sizes: Vec<u64> = jobs.iter().map(size).collect();
    let mut order: Vec<usize> = (0..jobs.len()).collect();
    order.sort_by(|&a, &b| sizes[b].cmp(&sizes[a]).then(a.cmp(&b)));
    order
}

fn emit(report: &ConvertReport, ctx: &Ctx) -> anyhow::Result<()> {
    if ctx.json {
        ctx.emit_json(report)?;
    } else if ctx.human() {
        for f in &report.files {
            if let Some(d) = &f.details {
                eprint!("{}", human_details(&f.input, &f.output, d));
            }
        }
    }
    Ok(())
}

/// Prints the report of a command that writes one output (`split`, `lod`): a [`FileReport`] as JSON,
/// or its human summary.
pub fn emit_one(input: &str, output: &Path, d: OutputDetails, ctx: &Ctx) -> anyhow::Result<()> {
    let f = FileReport {
        input: input.to_string(),
        output: output.display().to_string(),
        status: "converted",
        error: None,
        details: Some(d),
    };
    if ctx.json {
        ctx.emit_json(&f)?;
    } else if ctx.human() {
        if let Some(d) = &f.details {
            eprint!("{}", human_details(&f.input, &f.output, d));
        }
    }
    Ok(())
}

/// The human-readable summary of one output (stderr).
pub fn human_details(input: &str, output: &str, d: &OutputDetails) -> String {
    let mut o = String::new();
    let tris: usize = d.meshes.iter().map(|m| m.triangles).sum();
    let _ = writeln!(
        o,
        "{input} -> {output}: {} bytes, {} joints, {} meshes ({tris} triangles), {} clips",
        d.bytes,
        d.joints,
        d.meshes.len(),
        d.clips.len()
    );
    for m in &d.meshes {
        if m.lods.is_empty() && m.lods_not_built.is_empty() {
            continue;
        }
        let lods: Vec<String> = m
            .lods
            .iter()
            .map(|l| {
                format!(
                    "{} triangles ({}, error {}){}",
                    l.triangles,
                    num(l.reached_ratio),
                    num(l.error_relative),
                    match (l.stopped_by_error_limit, l.uv_seams_opened) {
                        (true, true) => " stopped by error limit, UV seams opened",
                        (true, false) => " stopped by error limit",
                        (false, true) => " UV seams opened",
                        (false, false) => "",
                    }
                )
            })
            .collect();
        let not_built: Vec<String> = m
            .lods_not_built
            .iter()
            .map(|n| match n.reached_triangles {
                Some(r) => format!(
                    "LOD {} not built ({}: stopped at {} of {} triangles)",
                    n.level, n.reason, r, n.previous_triangles
                ),
                None => format!("LOD {} not built ({})", n.level, n.reason),
            })
            .collect();
        let _ = writeln!(
            o,
            "  mesh \"{}\": {} triangles; LODs: {}{}",
            m.name,
            m.triangles,
            lods.join("; "),
            if not_built.is_empty() {
                String::new()
            } else {
                format!("; {}", not_built.join("; "))
            }
        );
    }
    for c in &d.clips {
        let compression = match &c.compression {
            Some(r) if r.compressed => format!(
                "; compressed {} -> {} bytes (ratio {:.1}), max error {} (p99 {}, tolerance {})",
                r.raw_bytes,
                r.compressed_bytes,
                r.ratio,
                sci(r.max_error),
                sci(r.p99_error),
                sci(r.tolerance)
            ),
            Some(_) => "; kept plain (compression did not make it smaller)".to_string(),
            None => String::new(),
        };
        let _ = writeln!(
            o,
            "  clip \"{}\": {} s, {} keys, drives {} joints{compression}",
            c.name,
            num(c.duration),
            c.keys.total,
            c.driven_joints
        );
    }
    for m in &d.motions {
        let _ = writeln!(
            o,
            "  motion {}: {} of {} rig joints bound{}; unmatched motion joints: {}",
            m.file,
            m.mapping.bound,
            m.mapping.entries.len(),
            match &m.root {
                Some(r) => format!(
                    ", retargeted (root scale {} from {}, standing shift {})",
                    num(r.root_scale),
                    r.source,
                    num(r.standing_shift)
                ),
                None if m.retargeted => ", retargeted".to_string(),
                None => String::new(),
            },
            if m.mapping.unmatched_motion.is_empty() {
                "none".to_string()
            } else {
                m.mapping.unmatched_motion.join(", ")
            }
        );
    }
    for s in &d.splits {
        for p in &s.parts {
            let _ = writeln!(
                o,
                "  split \"{}\" -> \"{}\": {} joints: {}",
                s.clip,
                p.name,
                p.joints.len(),
                p.joints.join(", ")
            );
        }
    }
    for diag in &d.diagnostics {
        if diag.level == "warning" {
            let _ = writeln!(o, "  warning [{}] {}", diag.code, diag.message);
        }
    }
    o
}

/// A small model-unit figure in scientific notation (`3.21e-4`).
fn sci(x: f32) -> String {
    format!("{x:.2e}")
}
