//! `sinew preview FILE -o OUT.png`: a contact sheet of the file as the runtime poses it (rest pose
//! front and side with the skeleton, poses across each clip, LODs with their measured error), drawn
//! on the CPU by [`sinew_pipeline::preview`].

use crate::cli::{PreviewArgs, UpArg};
use crate::output::{check_output_path, write_atomic, Ctx};
use crate::Status;
use anyhow::{bail, Context};
use sinew_core::format::{Axes, Axis};
use sinew_pipeline::preview::camera::Facing;
use sinew_pipeline::preview::{contact_sheet, SheetOptions, SheetReport, Up};
use std::path::Path;

/// The JSON report of `preview`.
#[derive(Debug, serde::Serialize)]
pub struct PreviewReport {
    /// The input path as given.
    pub input: String,
    /// The PNG written.
    pub output: String,
    /// Size of the PNG file.
    pub bytes: usize,
    /// `y` or `z`: the up axis used.
    pub up: &'static str,
    /// The axes the pictures were drawn with: `up`, `forward` (clip poses), `bind_forward` (the rest
    /// pose), each `+x` ... `-z`, and `from`: `file` (the axes the source format defines, or a
    /// `.sinew` file's `AXES`), `--up`, or `guess` (a `.sinew` written before 1.6 without `--up`).
    pub axes: AxesReport,
    /// What the sheet shows.
    #[serde(flatten)]
    pub sheet: SheetReport,
}

/// The axes of a picture, as reported.
#[derive(Debug, serde::Serialize)]
pub struct AxesReport {
    /// Up.
    pub up: &'static str,
    /// Facing of the clip poses.
    pub forward: &'static str,
    /// Facing of the rest pose.
    pub bind_forward: &'static str,
    /// Where they came from.
    pub from: &'static str,
}

/// The axes to draw with: `--up y|z` (each with its convention: Y up facing +Z, Z up facing +X),
/// else the file's own (the source format's, or a `.sinew`'s `AXES`), else a guess for a `.sinew`
/// written before 1.6 (Half-Life's axes when it has game data, Y up otherwise).
pub fn picture_axes(
    arg: UpArg,
    path: &Path,
    asset: &sinew_core::format::Asset,
) -> (Axes, &'static str) {
    let conventional = |up: Up| match up {
        Up::Y => Axes::Y_UP,
        Up::Z => Axes {
            up: Axis::PosZ,
            forward: Axis::PosX,
            bind_forward: Axis::PosX,
        },
    };
    match arg {
        UpArg::Y => (conventional(Up::Y), "--up"),
        UpArg::Z => (conventional(Up::Z), "--up"),
        UpArg::Auto => match asset.axes {
            Some(a) => (a, "file"),
            None => match auto_up(path, !asset.game.is_empty()) {
                Up::Z => (
                    sinew_scene::SourceFormat::Mdl
                        .axes()
                        .unwrap_or(conventional(Up::Z)),
                    "guess",
                ),
                Up::Y => (Axes::Y_UP, "guess"),
            },
        },
    }
}

/// The up axis for `--up auto`: Z for Half-Life sources (`.mdl`, `.smd`, `.qc`, or a `.sinew` with
/// game data), Y otherwise.
pub fn auto_up(path: &Path, has_game_data: bool) -> Up {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if matches!(ext.as_str(), "mdl" | "smd" | "qc") || has_game_data {
        Up::Z
    } else {
        Up::Y
    }
}

/// Resolves `--up`.
pub fn up_axis(arg: UpArg, path: &Path, has_game_data: bool) -> Up {
    match arg {
        UpArg::Y => Up::Y,
        UpArg::Z => Up::Z,
        UpArg::Auto => auto_up(path, has_game_data),
    }
}

/// Checks that the output path ends in `.png`.
pub fn check_png_output(path: &Path) -> anyhow::Result<()> {
    if !path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        bail!("{}: the output must end in .png", path.display());
    }
    check_output_path(path)
}

/// Runs `sinew preview`.
pub fn run(args: &PreviewArgs, ctx: &Ctx) -> anyhow::Result<Status> {
    check_png_output(&args.output)?;
    let lods = crate::steps::lod_spec_options(args.lod.as_deref())?;
    let shown = args.file.display().to_string();
    let loaded = super::export::load(&args.file, &args.import, lods.as_ref())?;
    let (axes, axes_from) = picture_axes(args.up, &args.file, &loaded.asset);
    let up = if axes.up.parallel(Axis::PosZ) {
        Up::Z
    } else {
        Up::Y
    };
    let title = args
        .file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| shown.clone());
    let meshes =
        crate::steps::body_meshes(&loaded.asset, &args.body).with_context(|| shown.clone())?;
    let opts = SheetOptions {
        facing: Facing::of(axes, false),
        rest_facing: Facing::of(axes, true),
        clip: args.clip.clone(),
        frames: args.frames,
        names: args.names,
        title,
        meshes,
        images: loaded.decoded,
    };
    let (png, sheet) = contact_sheet(&loaded.asset, &opts).with_context(|| shown.clone())?;
    write_atomic(&args.output, &png)?;
    let report = PreviewReport {
        input: shown,
        output: args.output.display().to_string(),
        bytes: png.len(),
        up: match up {
            Up::Y => "y",
            Up::Z => "z",
        },
        axes: AxesReport {
            up: axes.up.name(),
            forward: axes.forward.name(),
            bind_forward: axes.bind_forward.name(),
            from: axes_from,
        },
        sheet,
    };
    if ctx.json {
        ctx.emit_json(&report)?;
    } else if ctx.human() {
        eprintln!(
            "{} -> {}: {}x{} pixels, {} clip strips, {} LODs",
            report.input,
            report.output,
            report.sheet.width,
            report.sheet.height,
            report.sheet.clips.len(),
            report.sheet.lods.len()
        );
        for n in &report.sheet.notes {
            eprintln!("  note: {n}");
        }
    }
    Ok(Status::Success)
}
