//! The pipeline steps the commands share (motion binding, timeline cuts, partial-body splits, LODs),
//! each a thin layer over `sinew-pipeline` that adds the file name to errors and returns its part of
//! the JSON report. Field names of the report structs are a stable interface (docs/cli.md).

use crate::cli::{CompressArgs, EffortArg, LodArgs, SplitOpts};
use crate::report::{
    diag_report, EntryReport, MappingReport, MotionReport, PartReport, RestDifferenceReport,
    RootScaleReport, SplitReport,
};
use anyhow::{anyhow, bail, Context};
use sinew_core::Skeleton;
use sinew_pipeline::compress::{CompressOptions, Effort};
use sinew_pipeline::lod::{LodOptions, LodTuning};
use sinew_pipeline::mapping::{self, JointSet, Mapping, MatchMethod, Side};
use sinew_pipeline::retarget::{self, RetargetOptions, REST_DIFFERENCE_WARN_DEGREES};
use sinew_pipeline::split::{self, MaskSpec};
use sinew_scene::{Diagnostic, Scene, SceneClip, SourceFormat};
use std::path::Path;

fn side_name(s: Side) -> &'static str {
    match s {
        Side::Centre => "centre",
        Side::Left => "left",
        Side::Right => "right",
    }
}

/// The report of a mapping.
pub fn mapping_report(m: &Mapping) -> MappingReport {
    let entries: Vec<EntryReport> = m
        .entries
        .iter()
        .map(|e| {
            let (method, slot, score) = match e.method {
                None => (None, None, None),
                Some(MatchMethod::Exact) => (Some("exact"), None, None),
                Some(MatchMethod::Normalised) => (Some("normalised"), None, None),
                Some(MatchMethod::Synonym { slot }) => (Some("synonym"), Some(slot.name()), None),
                Some(MatchMethod::Fuzzy { score }) => (Some("fuzzy"), None, Some(score)),
                Some(MatchMethod::File) => (Some("file"), None, None),
            };
            EntryReport {
                rig: e.rig.clone(),
                motion: e.motion.clone(),
                method,
                slot,
                score,
                side: side_name(e.side),
            }
        })
        .collect();
    MappingReport {
        rig: m.rig.clone(),
        motion: m.motion.clone(),
        rig_family: m.rig_family.name(),
        motion_family: m.motion_family.name(),
        bound: entries.iter().filter(|e| e.motion.is_some()).count(),
        entries,
        unmatched_rig: m.unmatched_rig().iter().map(|s| s.to_string()).collect(),
        unmatched_motion: m.unmatched_motion.clone(),
        warnings: m.warnings.iter().map(diag_report).collect(),
        picture: None,
    }
}

/// The joint set of a rig: its skeleton.
pub fn rig_joint_set(skeleton: &Skeleton, label: &str) -> JointSet {
    JointSet::from_skeleton(skeleton).with_label(label)
}

/// The joint set of a motion: its skeleton with keyed flags from its clips, or, without a skeleton,
/// the joint names its clips drive (in first-seen order).
pub fn motion_joint_set(scene: &Scene, label: &str) -> JointSet {
    match &scene.skeleton {
        Some(s) => JointSet::from_skeleton_and_clips(s, &scene.clips),
        None => {
            let mut names: Vec<String> = Vec::new();
            for c in &scene.clips {
                for t in &c.tracks {
                    if !names.contains(&t.joint) {
                        names.push(t.joint.clone());
                    }
                }
            }
            JointSet::from_names(&names)
        }
    }
    .with_label(label)
}

/// A mapping file's text with the path it came from.
#[derive(Debug, Clone)]
pub struct MappingFile {
    /// Path as given.
    pub path: String,
    /// Contents.
    pub text: String,
}

impl MappingFile {
    /// Reads a mapping file; the error names it.
    pub fn read(path: &Path) -> anyhow::Result<Self> {
        let shown = path.display().to_string();
        match std::fs::metadata(path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!("{shown}: no such file"),
            Ok(m) if m.is_dir() => bail!("{shown}: is a directory, expected a file"),
            _ => {}
        }
        let text =
            std::fs::read_to_string(path).with_context(|| format!("{shown}: cannot read"))?;
        Ok(Self { path: shown, text })
    }
}

/// Matches `motion` onto `rig` automatically, or through a mapping file (checked against both sides;
/// the error names the file and the joint).
pub fn make_mapping(
    rig: &JointSet,
    motion: &JointSet,
    file: Option<&MappingFile>,
) -> anyhow::Result<Mapping> {
    match file {
        None => Ok(mapping::map_joints(rig, motion)),
        Some(f) => {
            mapping::read_mapping(&f.text, rig, motion).map_err(|e| anyhow!("{}: {e}", f.path))
        }
    }
}

/// Binds the clips of a motion file to `scene`'s skeleton (see docs/cli.md, `convert --anim`).
///
/// Pushes the mapping warnings, the unmatched names and the rest-difference warning into
/// `scene.diagnostics`, and the bound clips into `scene.clips` (renamed `STEM_NAME` when the name is
/// taken).
pub fn bind_motion(
    scene: &mut Scene,
    model_label: &str,
    motion: &Scene,
    motion_label: &str,
    map_file: Option<&MappingFile>,
    retarget_options: Option<&RetargetOptions>,
) -> anyhow::Result<MotionReport> {
    let Some(rig_skel) = scene.skeleton.clone() else {
        bail!("{model_label}: has no skeleton to bind the motion of {motion_label} to");
    };
    if motion.clips.is_empty() {
        bail!("{motion_label}: holds no animation clip");
    }
    let rig = rig_joint_set(&rig_skel, model_label);
    let mset = motion_joint_set(motion, motion_label);
    let mapping = make_mapping(&rig, &mset, map_file)?;
    let report = mapping_report(&mapping);
    scene.diagnostics.extend(mapping.warnings.iter().cloned());
    if !report.unmatched_motion.is_empty() {
        scene.diagnostics.push(
            Diagnostic::warning(
                "motion-unmatched",
                format!(
                    "{motion_label}: {} motion joints bind to no joint of {model_label}: {}",
                    report.unmatched_motion.len(),
                    report.unmatched_motion.join(", ")
                ),
            )
            .with_figure("count", report.unmatched_motion.len() as f64),
        );
    }
    let mut leg_scale = None;
    let mut root = None;
    let mut rest_differences = Vec::new();
    let mut bound: Vec<SceneClip> = Vec::new();
    if let Some(options) = retarget_options {
        let Some(src_skel) = &motion.skeleton else {
            bail!("{motion_label}: --retarget needs a skeleton in the motion file");
        };
        for clip in &motion.clips {
            let r = retarget::retarget_with(clip, src_skel, &rig_skel, &mapping, options)
                .map_err(|e| anyhow!("{motion_label}: retargeting onto {model_label}: {e}"))?;
            leg_scale = Some(r.leg_scale);
            root = Some(RootScaleReport {
                root_scale: r.root_scale,
                source: r.root_scale_source.name(),
                hip_heights: r.hip_heights.map(|(m, r)| [m, r]),
                standing_shift: r.standing_shift,
                grounding: r.grounding,
                root_joints: r.root_joints.clone(),
            });
            scene.diagnostics.extend(r.diagnostics);
            bound.push(r.clip);
        }
    } else {
        if let Some(src_skel) = &motion.skeleton {
            rest_differences =
                retarget::rest_orientation_differences(src_skel, &rig_skel, &mapping)
                    .into_iter()
                    .filter(|d| d.degrees > REST_DIFFERENCE_WARN_DEGREES)
                    .map(|d| RestDifferenceReport {
                        rig: d.rig,
                        motion: d.motion,
                        degrees: d.degrees,
                    })
                    .collect::<Vec<_>>();
            if let Some(worst) = rest_differences
                .iter()
                .max_by(|a, b| a.degrees.total_cmp(&b.degrees))
            {
                scene.diagnostics.push(
                    Diagnostic::warning(
                        "rest-pose-differs",
                        format!(
                            "{motion_label}: {} bound joints' rest orientations differ from {model_label}'s bind pose by more than {REST_DIFFERENCE_WARN_DEGREES} degrees (worst {:?} -> {:?}, {:.1} degrees); local rotations are copied as they are, consider --retarget",
                            rest_differences.len(),
                            worst.motion,
                            worst.rig,
                            worst.degrees
                        ),
                    )
                    .with_figure("count", rest_differences.len() as f64)
                    .with_figure("max_degrees", f64::from(worst.degrees)),
                );
            }
        }
        bound.extend(
            motion
                .clips
                .iter()
                .map(|c| mapping::apply_mapping(c, &mapping)),
        );
    }
    let stem = Path::new(motion_label)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| motion_label.to_string());
    let mut names = Vec::new();
    for mut clip in bound {
        if scene.clips.iter().any(|c| c.name == clip.name) {
            let new = format!("{stem}_{}", clip.name);
            scene.diagnostics.push(Diagnostic::info(
                "clip-renamed",
                format!(
                    "{motion_label}: clip {:?} renamed {new:?}: the name is already taken",
                    clip.name
                ),
            ));
            clip.name = new;
        }
        names.push(clip.name.clone());
        scene.clips.push(clip);
    }
    Ok(MotionReport {
        file: motion_label.to_string(),
        mapping: report,
        retargeted: retarget_options.is_some(),
        leg_scale,
        root_scale: root.as_ref().map(|r| r.root_scale),
        root,
        rest_differences,
        clips: names,
    })
}

/// Cuts the scene's single clip into named clips (`walk=1-30,run=31-50`). Frame numbers start at 1
/// for MS3D (as Milkshape counts) and 0 for the other formats. Returns the new clip names.
pub fn cut(scene: &mut Scene, spec: &str, file: &str) -> anyhow::Result<Vec<String>> {
    let [clip] = scene.clips.as_slice() else {
        bail!(
            "{file}: --clips cuts a single timeline, but the file has {} clips",
            scene.clips.len()
        );
    };
    let first = if scene.source_format == SourceFormat::Ms3d {
        1
    } else {
        0
    };
    let cuts = sinew_pipeline::cut::cut_clips(clip, spec, first)
        .map_err(|e| anyhow!("{file}: --clips: {e}"))?;
    let names = cuts.iter().map(|c| c.name.clone()).collect();
    scene.clips = cuts;
    Ok(names)
}

/// Parsed `--at`/`--mask` options.
#[derive(Debug, Clone, Default)]
pub struct SplitPlan {
    /// Joints to split at.
    pub at: Vec<String>,
    /// Hand-made joint sets.
    pub masks: Vec<MaskSpec>,
}

impl SplitPlan {
    /// Parses the options (syntax only; joints are checked against a skeleton by [`split`]).
    pub fn parse(opts: &SplitOpts) -> anyhow::Result<Self> {
        let masks = opts
            .mask
            .iter()
            .map(|m| split::parse_mask_spec(m).map_err(|e| anyhow!("--mask: {e}")))
            .collect::<anyhow::Result<Vec<_>>>()?;
        Ok(Self {
            at: opts.at.clone(),
            masks,
        })
    }

    /// Whether there is anything to do.
    pub fn is_empty(&self) -> bool {
        self.at.is_empty() && self.masks.is_empty()
    }
}

fn part(c: &SceneClip) -> PartReport {
    PartReport {
        name: c.name.clone(),
        joints: c
            .tracks
            .iter()
            .filter(|t| !(t.translation.is_empty() && t.rotation.is_empty() && t.scale.is_empty()))
            .map(|t| t.joint.clone())
            .collect(),
    }
}

/// Refuses a scene with nothing to convert: no joint, no mesh and no clip (an empty glTF, an SMD
/// without nodes, a QC whose SMDs were all left out), as an empty OBJ is refused by its importer.
pub fn check_not_empty(scene: &Scene, file: &str) -> anyhow::Result<()> {
    let joints = scene.skeleton.as_ref().map_or(0, |s| s.len());
    if joints == 0 && scene.meshes.is_empty() && scene.clips.is_empty() {
        let why: Vec<String> = scene
            .diagnostics
            .iter()
            .filter(|d| d.level == sinew_scene::Level::Warning)
            .map(|d| format!("[{}] {}", d.code, d.message))
            .collect();
        let why = if why.is_empty() {
            String::new()
        } else {
            format!(" ({})", why.join("; "))
        };
        bail!("{file}: nothing to convert: the file holds no joint, mesh or clip{why}");
    }
    Ok(())
}

/// Checks every joint of the plan against the skeleton; the error names the file and the joint.
pub fn check_split(scene: &Scene, plan: &SplitPlan, file: &str) -> anyhow::Result<()> {
    if plan.is_empty() {
        return Ok(());
    }
    let Some(skel) = &scene.skeleton else {
        bail!("{file}: has no skeleton to split clips by");
    };
    let all = plan
        .at
        .iter()
        .chain(plan.masks.iter().flat_map(|m| m.joints.iter()));
    for j in all {
        if skel.find(j).is_none() {
            bail!("{file}: joint {j:?} does not exist in the skeleton");
        }
    }
    Ok(())
}

/// Splits every clip: with `--at`, each clip is replaced by `CLIP.upper` and `CLIP.lower`; each
/// `--mask NAME=...` adds `CLIP.NAME`. With masks only, the source clips are kept.
pub fn split(scene: &mut Scene, plan: &SplitPlan, file: &str) -> anyhow::Result<Vec<SplitReport>> {
    if plan.is_empty() {
        return Ok(Vec::new());
    }
    check_split(scene, plan, file)?;
    let Some(skel) = scene.skeleton.clone() else {
        bail!("{file}: has no skeleton to split clips by");
    };
    let at: Vec<&str> = plan.at.iter().map(String::as_str).collect();
    let mut out_clips = Vec::new();
    let mut reports = Vec::new();
    let mut game = scene.game.clone();
    for clip in &scene.clips {
        let mut made = Vec::new();
        if at.is_empty() {
            out_clips.push(clip.clone());
        } else {
            let (u, l) = split::split_clip(clip, &skel, &at).map_err(|e| anyhow!("{file}: {e}"))?;
            made.push(u);
            made.push(l);
        }
        for m in &plan.masks {
            made.push(split::clip_for_mask(clip, &skel, m).map_err(|e| anyhow!("{file}: {e}"))?);
        }
        reports.push(SplitReport {
            clip: clip.name.clone(),
            parts: made.iter().map(part).collect(),
        });
        let names: Vec<String> = made.iter().map(|c| c.name.clone()).collect();
        split::carry_game_data(&mut game, &clip.name, &names, at.is_empty());
        out_clips.extend(made);
    }
    let mut seen = std::collections::HashSet::new();
    for c in &out_clips {
        if !seen.insert(c.name.as_str()) {
            bail!("{file}: splitting makes two clips named {:?}", c.name);
        }
    }
    scene.clips = out_clips;
    scene.game = game;
    add_masks(scene, &skel, plan, file)?;
    Ok(reports)
}

/// Adds the named joint masks of a split to the scene (weight 1 for each listed joint; joints not
/// listed have weight 0), replacing masks of the same name: with `--at`, `upper` (the joints of the
/// subtrees under the `--at` joints, the joints of the `CLIP.upper` clips) and `lower` (every other
/// joint); each `--mask NAME=...` adds `NAME` with exactly the listed joints (the joints of
/// `CLIP.NAME`). Joints are listed in skeleton order.
pub fn add_masks(
    scene: &mut Scene,
    skel: &Skeleton,
    plan: &SplitPlan,
    file: &str,
) -> anyhow::Result<()> {
    let mut made: Vec<sinew_scene::Mask> = Vec::new();
    let from_weights = |name: &str, weights: &[f32], keep: bool| sinew_scene::Mask {
        name: name.to_string(),
        weights: skel
            .names()
            .iter()
            .zip(weights)
            .filter(|(_, &w)| (w > 0.5) == keep)
            .map(|(n, _)| (n.clone(), 1.0))
            .collect(),
    };
    if !plan.at.is_empty() {
        let upper =
            split::mask_from_subtrees(skel, &plan.at).map_err(|e| anyhow!("{file}: {e}"))?;
        made.push(from_weights(split::UPPER_SUFFIX, &upper, true));
        made.push(from_weights(split::LOWER_SUFFIX, &upper, false));
    }
    for m in &plan.masks {
        let w = split::mask_from_joints(skel, &m.joints).map_err(|e| anyhow!("{file}: {e}"))?;
        made.push(from_weights(&m.name, &w, true));
    }
    for m in made {
        scene.masks.retain(|old| old.name != m.name);
        scene.masks.push(m);
    }
    Ok(())
}

/// Parses the LOD options; `None` for `--lod none`.
pub fn lod_options(args: &LodArgs) -> anyhow::Result<Option<LodOptions>> {
    let spec = args.lod.trim();
    if spec.eq_ignore_ascii_case("none") {
        return Ok(None);
    }
    let ratios = spec
        .split(',')
        .map(|r| {
            r.trim().parse::<f32>().map_err(|_| {
                anyhow!(
                    "--lod {spec:?}: {:?} is not a number (expected e.g. 0.5,0.25 or none)",
                    r.trim()
                )
            })
        })
        .collect::<anyhow::Result<Vec<f32>>>()?;
    let opts = LodOptions {
        ratios,
        max_error: args.lod_max_error,
        lowest_lod_influences: args.lod_influences,
        keep_uv_seams: args.lod_keep_uv_seams,
    };
    opts.validate().map_err(|e| anyhow!("--lod: {e}"))?;
    Ok(Some(opts))
}

/// Replaces every mesh's generated LODs by a new chain, or removes them for `None`.
pub fn lods(scene: &mut Scene, options: Option<&LodOptions>, file: &str) -> anyhow::Result<()> {
    let Scene {
        meshes,
        skeleton,
        clips,
        materials,
        ..
    } = scene;
    mesh_lods(
        meshes,
        skeleton.as_ref(),
        clips,
        materials,
        options,
        &LodTuning::default(),
        file,
    )
    .map(|_| ())
}

/// The LOD builder's tuning for `--effort`: `max` also builds each step the plain ways and keeps
/// the closest ([`LodTuning::plain_candidate`]).
pub fn lod_tuning(effort: EffortArg) -> LodTuning {
    LodTuning {
        plain_candidate: effort == EffortArg::Max,
        ..LodTuning::default()
    }
}

/// [`lods`] on a scene's meshes alone (`skeleton`, `clips` and `materials` are the scene's), so
/// that its clips can be worked on at the same time. Returns each mesh's wall times (empty for
/// `None`).
pub fn mesh_lods(
    meshes: &mut [sinew_scene::Mesh],
    skeleton: Option<&sinew_core::Skeleton>,
    clips: &[sinew_scene::SceneClip],
    materials: &[sinew_scene::Material],
    options: Option<&LodOptions>,
    tuning: &LodTuning,
    file: &str,
) -> anyhow::Result<Vec<sinew_pipeline::lod::MeshLodTimes>> {
    match options {
        None => {
            for m in meshes {
                m.lods.clear();
            }
            Ok(Vec::new())
        }
        Some(o) => {
            // The plain builds are also compared under poses of the scene's own clips, and the
            // clips' size sets how many meshes have them.
            let motion = sinew_pipeline::lod::scene_motion_for(clips, skeleton, meshes, tuning);
            let (_, times) = sinew_pipeline::lod::generate_mesh_lods_timed(
                meshes, skeleton, materials, o, tuning, &motion,
            )
            .map_err(|e| anyhow!("{file}: LOD generation: {e}"))?;
            Ok(times)
        }
    }
}

/// The compression options of `--no-compress`, `--tolerance`, `--error-distance`; `None` for plain
/// clips. Errors on a tolerance that is not a positive number or a negative distance.
pub fn compress_options(args: &CompressArgs) -> anyhow::Result<Option<CompressOptions>> {
    if args.no_compress {
        return Ok(None);
    }
    if let Some(t) = args.tolerance {
        if !(t.is_finite() && t > 0.0) {
            bail!("--tolerance {t}: must be a positive number of model units");
        }
    }
    if let Some(d) = args.error_distance {
        if !(d.is_finite() && d >= 0.0) {
            bail!("--error-distance {d}: must be a non-negative number of model units");
        }
    }
    Ok(Some(CompressOptions {
        tolerance: args.tolerance,
        error_distance: args.error_distance,
        effort: match args.effort {
            EffortArg::Fast => Effort::Fast,
            EffortArg::Default => Effort::Default,
            EffortArg::Max => Effort::Max,
        },
        ..CompressOptions::default()
    }))
}

/// LOD options for a `--lod R1,R2|none` spec with the default error limit and influences (`export`,
/// `preview`); `None` when no spec was given (inside, `None` for `none`).
pub fn lod_spec_options(
    spec: Option<&str>,
) -> anyhow::Result<Option<Option<sinew_pipeline::lod::LodOptions>>> {
    spec.map(|spec| {
        lod_options(&crate::cli::LodArgs {
            lod: spec.to_string(),
            lod_max_error: None,
            lod_influences: 4,
            lod_keep_uv_seams: false,
        })
    })
    .transpose()
}

/// The meshes `--body` / `--mesh` name, or `None` when neither is given (the default body).
pub fn body_meshes(
    asset: &sinew_core::format::Asset,
    args: &crate::cli::BodyArgs,
) -> anyhow::Result<Option<Vec<usize>>> {
    if args.body.is_none() && args.mesh.is_none() {
        return Ok(None);
    }
    let choice = sinew_pipeline::body::BodyChoice::from_args(args.body, args.mesh.as_deref());
    Ok(Some(sinew_pipeline::body::select(asset, &choice)?))
}
