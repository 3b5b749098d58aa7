//! `sinew convert INPUT... (-o OUT | --out-dir DIR)`: import, bind motions, cut, split, LODs, compile,
//! write atomically. Several inputs run in parallel (rayon); one bad file does not stop the others.
//!
//! The JSON report is [`ConvertReport`]; the per-output part, [`OutputDetails`], is shared with `split`
//! and `lod`. Field names are a stable interface documented in docs/cli.md.

use crate::batch::{self, Job};
use crate::cli::ConvertArgs;
use crate::digest::Stamp;
use crate::incremental;
use crate::output::{check_output_path, write_atomic, Ctx};
use crate::report::{
    clip_report, diag_report, mesh_report, num, strict_error, warning_pairs, ClipOut, ClipTiming,
    ConvertReport, FileReport, IncrementalReport, MeshOut, MeshTimings, NotBuiltReport,
    OutputDetails, Timings,
};
use crate::report::{MotionReport, SplitReport};
use crate::steps::{self, MappingFile, SplitPlan};
use crate::Status;
use anyhow::{anyhow, bail};
use sinew_core::Skeleton;
use sinew_pipeline::compile::{
    compile_compressed, compress_clips_timed, CompileReport, CompressedClips,
};
use sinew_pipeline::compress::{CompressOptions, KeptPlain};
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
        timings: None,
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
    write_compressed(scene, input, output, compressed.map(|c| c.0))
}

/// The clip half of [`write_scene`]: a scene's clips compiled and compressed (`None` without
/// compression), with each clip's encoding time in seconds; `skeleton` is the scene's.
fn compress_scene_clips(
    clips: &[SceneClip],
    skeleton: Option<&Skeleton>,
    input: &str,
    compress: Option<&CompressOptions>,
) -> anyhow::Result<Option<(CompressedClips, Vec<f64>)>> {
    compress
        .map(|o| compress_clips_timed(clips, skeleton, o))
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
    let (bytes, report) = compile_bytes(scene, input, compressed)?;
    write_atomic(output, &bytes)?;
    Ok(Written {
        bytes: bytes.len() as u64,
        report,
    })
}

/// The `.sinew` bytes of a scene, with the clips [`compress_scene_clips`] gave for it.
fn compile_bytes(
    scene: &Scene,
    input: &str,
    compressed: Option<CompressedClips>,
) -> anyhow::Result<(Vec<u8>, CompileReport)> {
    let (asset, report) =
        compile_compressed(scene, compressed).map_err(|e| anyhow!("{input}: compiling: {e}"))?;
    let bytes = sinew_core::format::write(&asset).map_err(|e| anyhow!("{input}: writing: {e}"))?;
    Ok((bytes, report))
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
    /// The LOD builder's tuning (`--effort max` adds the plain builds).
    lod_tuning: sinew_pipeline::lod::LodTuning,
    compress: Option<CompressOptions>,
    textures: bool,
    /// `--strict`: an input with a warning fails and writes nothing.
    strict: bool,
    /// `--timings`: each step's wall time goes into the report.
    timings: bool,
    /// `--incremental`: the records and where they go.
    record: Option<RecordPlan>,
}

/// The incremental record of a run: its folder (the output folder), the options' fingerprint, and
/// per job the record found.
struct RecordPlan {
    root: std::path::PathBuf,
    options: String,
    loaded: incremental::Loaded,
}

/// A converted input, not yet written: its report and its files (texture PNGs, then the `.sinew`),
/// and the wall times of its steps (the import and writing are added by [`run_job`]).
struct Built {
    details: OutputDetails,
    files: Vec<(std::path::PathBuf, Vec<u8>)>,
    timings: Timings,
}

/// Milliseconds since `start`.
fn ms_since(start: std::time::Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1000.0
}

/// What became of one input.
enum Outcome {
    /// Written.
    Converted(OutputDetails),
    /// Kept from an earlier run (its record).
    Reused(Box<incremental::Record>),
    /// Converted but not written: `--strict` and a warning (the error line).
    Strict(OutputDetails, String),
    /// Failed.
    Failed(anyhow::Error),
}

fn convert_one(job: &Job, plan: &Plan, mut scene: Scene) -> anyhow::Result<Built> {
    let (input, output) = (&job.input, &job.output);
    let label = input.display().to_string();
    steps::check_not_empty(&scene, &label)?;
    let prepared = std::time::Instant::now();
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
    let prepare_ms = ms_since(prepared);
    // LODs (meshes) and clip compression (clips) read and write different parts of the scene and
    // are the two costly steps: they run at the same time. Each gives what it gives alone; a LOD
    // error is reported first, as when they ran in turn.
    let (lods, compressed) = rayon::join(
        || {
            steps::mesh_lods(
                &mut scene.meshes,
                scene.skeleton.as_ref(),
                &scene.clips,
                &scene.materials,
                plan.lod.as_ref(),
                &plan.lod_tuning,
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
    let lod_times = lods?;
    let (compressed, encode_seconds) = match compressed? {
        Some((c, s)) => (Some(c), s),
        None => (None, Vec::new()),
    };
    let texturing = std::time::Instant::now();
    // Textures first: a written .sinew always has its textures beside it.
    let mut files = Vec::new();
    if plan.textures && !scene.images.is_empty() {
        let stem = output
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let textures = sinew_pipeline::texture::textures_for_output(&mut scene, &stem)
            .map_err(|e| anyhow!("{label}: {e}"))?;
        for (name, bytes) in textures {
            files.push((output.with_file_name(&name), bytes));
        }
    }
    let textures_ms = ms_since(texturing);
    let compiling = std::time::Instant::now();
    let (bytes, report) = compile_bytes(&scene, &label, compressed)?;
    let write_ms = ms_since(compiling);
    let written = Written {
        bytes: bytes.len() as u64,
        report,
    };
    let mut d = details(&scene, written, motions, cuts, splits);
    d.textures = files.iter().map(|(p, _)| p.display().to_string()).collect();
    files.push((output.clone(), bytes));
    let timings = Timings {
        prepare_ms,
        lods: scene
            .meshes
            .iter()
            .zip(lod_times)
            .map(|(m, t)| MeshTimings {
                mesh: m.name.clone(),
                optimize_ms: t.optimize * 1000.0,
                levels_ms: t.levels.iter().map(|s| s * 1000.0).collect(),
            })
            .collect(),
        clips: scene
            .clips
            .iter()
            .zip(encode_seconds)
            .map(|(c, s)| ClipTiming {
                clip: c.name.clone(),
                encode_ms: s * 1000.0,
            })
            .collect(),
        textures_ms,
        write_ms,
        ..Timings::default()
    };
    Ok(Built {
        details: d,
        files,
        timings,
    })
}

/// Converts job `i`, or keeps its output when its record still holds; with `--strict` a warning
/// fails it before anything is written. Returns what became of it and the files it read (or read
/// last time, when kept).
fn run_job(i: usize, job: &Job, plan: &Plan) -> (Outcome, Vec<Stamp>) {
    if let Some(r) = &plan.record {
        let record = r.loaded.records.get(i).and_then(Option::as_ref);
        if let Some(rec) = record.filter(|x| x.still_holds(&r.options, &job.input, &job.output)) {
            let reads = rec.reads.clone();
            return (Outcome::Reused(Box::new(rec.clone())), reads);
        }
    }
    let started = std::time::Instant::now();
    let (scene, reads) =
        crate::input::import_tracked(&job.input, job.format, &plan.import, plan.record.is_some());
    let import_ms = ms_since(started);
    let mut built = match scene.and_then(|scene| convert_one(job, plan, scene)) {
        Ok(b) => b,
        Err(e) => return (Outcome::Failed(e), reads),
    };
    let warnings = warning_pairs(&built.details);
    if plan.strict && !warnings.is_empty() {
        let line = strict_error(&job.input.display().to_string(), &warnings);
        return (Outcome::Strict(built.details, line), reads);
    }
    let writing = std::time::Instant::now();
    let written = write_built(job, plan, &built, &reads, warnings.len());
    // Timings go into the report after the incremental record was written: they are not part of
    // what a reused output reports.
    if plan.timings {
        let mut t = std::mem::take(&mut built.timings);
        t.import_ms = import_ms;
        t.write_ms += ms_since(writing);
        t.total_ms = ms_since(started);
        built.details.timings = Some(t);
    }
    match written {
        Ok(()) => (Outcome::Converted(built.details), reads),
        Err(e) => (Outcome::Failed(e), reads),
    }
}

/// Writes a built input's files (each atomically, the `.sinew` last) and, with `--incremental`, its
/// record.
fn write_built(
    job: &Job,
    plan: &Plan,
    built: &Built,
    reads: &[Stamp],
    warnings: usize,
) -> anyhow::Result<()> {
    if let Some(dir) = job.output.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow!("{}: cannot create the folder: {e}", dir.display()))?;
    }
    for (path, bytes) in &built.files {
        write_atomic(path, bytes)?;
    }
    let Some(r) = &plan.record else {
        return Ok(());
    };
    // As text, as the JSON report prints it (an f32 as its shortest digits).
    let report = serde_json::to_string(&built.details).map_err(|e| {
        anyhow!(
            "{}: encoding the incremental record: {e}",
            job.output.display()
        )
    })?;
    let writes = built
        .files
        .iter()
        .map(|(p, b)| Stamp::of(p, Some(b)))
        .collect();
    let record = incremental::Record::new(
        &r.options,
        (&job.input, &job.output),
        reads.to_vec(),
        writes,
        warnings,
        report,
    );
    incremental::store(&r.root, &record)
}

/// The report entry of one input.
fn file_report(job: &Job, outcome: Outcome, strict: bool) -> FileReport {
    let mut f = FileReport {
        input: job.input.display().to_string(),
        output: job.output.display().to_string(),
        status: "converted",
        error: None,
        warnings: 0,
        details: None,
        recorded: None,
    };
    match outcome {
        Outcome::Converted(d) => f.details = Some(d),
        Outcome::Strict(d, line) => {
            f.status = "failed";
            f.error = Some(line);
            f.details = Some(d);
        }
        Outcome::Reused(rec) => {
            f.status = "reused";
            f.recorded = rec.report_fields();
        }
        Outcome::Failed(e) => {
            f.status = "failed";
            f.error = Some(crate::output::one_line(&e));
        }
    }
    let list = f.warning_list();
    f.warnings = list.len();
    // A kept output with warnings fails under --strict like a converted one (nothing is written).
    if strict && f.status == "reused" && !list.is_empty() {
        f.status = "failed";
        f.error = Some(strict_error(&f.input, &list));
    }
    f
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
    if let Some(r) = &args.report {
        if !r
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("html"))
        {
            bail!("{}: the report must end in .html", r.display());
        }
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
    let (jobs, passed) = match (&args.output, &args.out_dir) {
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
            let job = Job {
                input: args.inputs[0].clone(),
                output: o.clone(),
                format: None,
            };
            (vec![job], Vec::new())
        }
        (None, Some(dir)) => {
            if dir.exists() && !dir.is_dir() {
                bail!("{}: --out-dir is a file, not a folder", dir.display());
            }
            let batch = batch::plan(&args.inputs, dir, &args.import)?;
            std::fs::create_dir_all(dir)
                .map_err(|e| anyhow!("{}: cannot create the output folder: {e}", dir.display()))?;
            (batch.jobs, batch.passed)
        }
        _ => bail!("convert: give -o OUT.sinew (one input) or --out-dir DIR"),
    };
    // The report may go into the output folder, which exists from here on.
    if let Some(r) = &args.report {
        check_output_path(r)?;
    }
    let map = args.map.as_deref().map(MappingFile::read).transpose()?;
    // What the --anim and --map files hold is part of the incremental record's fingerprint.
    let mut extra = Vec::new();
    let mut anims = Vec::with_capacity(args.anim.len());
    for a in &args.anim {
        let (scene, reads) = crate::input::import_tracked(a, None, &args.import, args.incremental);
        anims.push((a.display().to_string(), scene?));
        extra.extend(reads);
    }
    if let Some(m) = &map {
        extra.push(Stamp::of(Path::new(&m.path), Some(m.text.as_bytes())));
    }
    let record = args.incremental.then(|| {
        let root = match (&args.out_dir, &args.output) {
            (Some(dir), _) => dir.clone(),
            (None, Some(o)) => o
                .parent()
                .filter(|p| !p.as_os_str().is_empty())
                .map_or_else(|| Path::new(".").to_path_buf(), Path::to_path_buf),
            (None, None) => Path::new(".").to_path_buf(),
        };
        let outputs: Vec<&Path> = jobs.iter().map(|j| j.output.as_path()).collect();
        RecordPlan {
            options: incremental::options_fingerprint(args, &extra),
            loaded: incremental::load(&root, &outputs),
            root,
        }
    });
    let incremental_report = record.as_ref().map(|r| IncrementalReport {
        record: r.root.join(incremental::FOLDER).display().to_string(),
        state: r.loaded.state,
        reason: r.loaded.reason.clone(),
    });
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
        lod_tuning: steps::lod_tuning(args.compress.effort),
        compress,
        textures: !args.no_textures,
        strict: args.strict,
        timings: args.timings,
        record,
    };

    // One input with -o: an error is the command's error (exit 2, one line); a failure by
    // --strict is a failed check (exit 1) with its report.
    if args.output.is_some() {
        let job = &jobs[0];
        let file = match run_job(0, job, &plan).0 {
            Outcome::Failed(e) => return Err(e),
            outcome => file_report(job, outcome, plan.strict),
        };
        let report = ConvertReport::new(vec![file], Vec::new(), plan.strict, incremental_report);
        write_html(&report, args)?;
        emit(&report, ctx)?;
        return Ok(finish(&report, ctx));
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
    let pool = sinew_pipeline::warmed_pool_builder()
        .num_threads(args.jobs.unwrap_or(0))
        .build()
        .map_err(|e| anyhow!("--jobs: cannot start worker threads: {e}"))?;
    // Largest inputs first (by file size), each worker taking the next job when it is free, so one
    // long file starts early instead of serialising the end of the batch. Reports keep input order.
    let order = largest_first(&jobs);
    let next = std::sync::atomic::AtomicUsize::new(0);
    type Slot = std::sync::Mutex<Option<(FileReport, Vec<std::path::PathBuf>)>>;
    let slots: Vec<Slot> = jobs.iter().map(|_| std::sync::Mutex::new(None)).collect();
    let workers = pool.current_num_threads().min(jobs.len()).max(1);
    pool.scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|_| loop {
                let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let Some(&i) = order.get(k) else {
                    break;
                };
                let job = &jobs[i];
                let (outcome, reads) = run_job(i, job, &plan);
                if let Some(b) = &bar {
                    b.inc(1);
                }
                let report = file_report(job, outcome, plan.strict);
                let reads = reads.iter().map(|s| s.path.clone().into()).collect();
                if let Ok(mut slot) = slots[i].lock() {
                    *slot = Some((report, reads));
                }
            });
        }
    });
    let (files, reads): (Vec<FileReport>, Vec<Vec<std::path::PathBuf>>) = slots
        .into_iter()
        .zip(&jobs)
        .map(|(slot, job)| {
            slot.into_inner().ok().flatten().unwrap_or_else(|| {
                let e = anyhow!("{}: the worker converting it stopped", job.input.display());
                (file_report(job, Outcome::Failed(e), false), Vec::new())
            })
        })
        .unzip();
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let skipped = batch::skipped(&passed, &jobs, &reads);
    let report = ConvertReport::new(files, skipped, plan.strict, incremental_report);
    pool.install(|| write_html(&report, args))?;
    emit(&report, ctx)?;
    Ok(finish(&report, ctx))
}

/// `--report OUT.html`: the run's page (docs/cli.md), written atomically.
fn write_html(report: &ConvertReport, args: &ConvertArgs) -> anyhow::Result<()> {
    let Some(path) = &args.report else {
        return Ok(());
    };
    let json = serde_json::to_value(report)?;
    let thumbs = crate::report::html::thumbnails(report);
    let title = format!(
        "sinew convert: {}",
        args.inputs
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(" ")
    );
    write_atomic(
        path,
        crate::report::html::page(&json, &thumbs, &title).as_bytes(),
    )
}

/// Lists the failures and orphaned companions on stderr (also with --quiet or --json, not when a
/// library caller collects the report: they are in it) and gives the exit status: 1 when any.
fn finish(report: &ConvertReport, ctx: &Ctx) -> Status {
    if ctx.stderr() {
        for f in &report.files {
            if let Some(e) = &f.error {
                eprintln!("sinew: error: {e}");
            }
        }
        for s in report
            .skipped
            .iter()
            .filter(|s| s.reason == "orphaned-companion")
        {
            eprintln!("sinew: error: {}: {}", s.file, s.message);
        }
    }
    if report.failed == 0 && report.orphans == 0 {
        return Status::Success;
    }
    if !ctx.quiet && ctx.stderr() && (report.inputs > 1 || report.orphans > 0) {
        eprintln!(
            "sinew: {} of {} files failed; {} converted, {} reused{}",
            report.failed,
            report.inputs,
            report.converted,
            report.reused,
            match report.orphans {
                0 => String::new(),
                n => format!("; {n} companion files without their model"),
            }
        );
    }
    Status::CheckFailed
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
        if let Some(r) = report.incremental.as_ref().and_then(|i| i.reason.as_ref()) {
            eprintln!("sinew: incremental record ignored: {r}");
        }
        for f in &report.files {
            if f.status == "failed" {
                // Errors are listed by `finish`; a failure by --strict also shows its warnings.
                for (code, message) in f.warning_list().iter().filter(|_| f.details.is_some()) {
                    eprintln!(
                        "{}: not written (--strict): warning [{code}] {message}",
                        f.input
                    );
                }
            } else if let Some(d) = &f.details {
                eprint!("{}", human_details(&f.input, &f.output, d));
            } else if f.status == "reused" {
                eprintln!(
                    "{} -> {}: reused (its files, the options and sinew are unchanged), {} warnings",
                    f.input, f.output, f.warnings
                );
            }
        }
        eprint!("{}", human_summary(report));
    }
    Ok(())
}

/// The batch lines of the human report: the files a folder walk passed over (companions and files
/// that are not models counted, orphans listed as errors by [`finish`]) and the warnings.
fn human_summary(report: &ConvertReport) -> String {
    let mut o = String::new();
    let count = |r: &str| report.skipped.iter().filter(|s| s.reason == r).count();
    if !report.skipped.is_empty() {
        let _ = writeln!(
            o,
            "skipped {} files: {} companions read by their model, {} not models, {} orphaned companions (--json lists each)",
            report.skipped.len(),
            count("companion"),
            count("not-a-model"),
            report.orphans
        );
    }
    if report.inputs > 1 && report.warnings > 0 {
        let codes: Vec<String> = report
            .warning_codes
            .iter()
            .map(|(c, n)| format!("{c} x{n}"))
            .collect();
        let _ = writeln!(
            o,
            "{} warnings in {} of {} inputs: {}",
            report.warnings,
            report.inputs_with_warnings,
            report.inputs,
            codes.join(", ")
        );
    }
    o
}

/// Prints the report of a command that writes one output (`split`, `lod`): a [`FileReport`] as JSON,
/// or its human summary.
pub fn emit_one(input: &str, output: &Path, d: OutputDetails, ctx: &Ctx) -> anyhow::Result<()> {
    let f = FileReport {
        input: input.to_string(),
        output: output.display().to_string(),
        status: "converted",
        error: None,
        warnings: warning_pairs(&d).len(),
        details: Some(d),
        recorded: None,
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
            Some(r) => match (r.kept_plain_because, r.error_limit) {
                (Some(KeptPlain::ToleranceNotHeld), limit) => format!(
                    "; kept plain: no encoding held the tolerance {} at every key time{}",
                    sci(r.tolerance),
                    match limit.filter(|l| *l < r.tolerance) {
                        Some(l) => format!(
                            " (f32 rounding of positions far from the origin left a joint a \
                             limit of {})",
                            sci(l)
                        ),
                        None => String::new(),
                    }
                ),
                _ => "; kept plain (compression did not make it smaller)".to_string(),
            },
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
    if let Some(t) = &d.timings {
        o.push_str(&human_timings(t));
    }
    o
}

/// The `--timings` lines of the human summary.
fn human_timings(t: &Timings) -> String {
    let ms = |x: f64| format!("{x:.1} ms");
    let mut o = String::new();
    let _ = writeln!(
        o,
        "  timings: total {}, import {}, prepare {}, textures {}, write {}",
        ms(t.total_ms),
        ms(t.import_ms),
        ms(t.prepare_ms),
        ms(t.textures_ms),
        ms(t.write_ms)
    );
    for m in &t.lods {
        let levels: Vec<String> = m
            .levels_ms
            .iter()
            .enumerate()
            .map(|(k, &x)| format!("LOD {} {}", k + 1, ms(x)))
            .collect();
        let _ = writeln!(
            o,
            "    mesh \"{}\": optimize {}, {}",
            m.mesh,
            ms(m.optimize_ms),
            levels.join(", ")
        );
    }
    for c in &t.clips {
        let _ = writeln!(o, "    clip \"{}\": encode {}", c.clip, ms(c.encode_ms));
    }
    o
}

/// A small model-unit figure in scientific notation (`3.21e-4`).
fn sci(x: f32) -> String {
    format!("{x:.2e}")
}
