//! `sinew preview FILE -o OUT.png`: a contact sheet of the file as the runtime poses it (rest pose
//! front and side with the skeleton, poses across each clip, LODs with their measured error), drawn
//! on the CPU by [`sinew_pipeline::preview`].

use crate::cli::{PreviewArgs, UpArg};
use crate::output::{check_output_path, write_atomic, Ctx};
use crate::Status;
use anyhow::{bail, Context};
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
    /// What the sheet shows.
    #[serde(flatten)]
    pub sheet: SheetReport,
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
    let up = up_axis(args.up, &args.file, !loaded.asset.game.is_empty());
    let title = args
        .file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| shown.clone());
    let meshes =
        crate::steps::body_meshes(&loaded.asset, &args.body).with_context(|| shown.clone())?;
    let opts = SheetOptions {
        up,
        clip: args.clip.clone(),
        frames: args.frames,
        names: args.names,
        title,
        meshes,
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
