//! `sinew lod FILE -o OUT.sinew [--lod R1,R2|none]`: regenerate the LODs of an existing file. The
//! report is the same per-output object as `convert`.

use crate::cli::LodCmdArgs;
use crate::commands::convert::{details, emit_one, write_scene};
use crate::output::{check_output_path, Ctx};
use crate::steps;
use crate::Status;

/// Runs `sinew lod`.
pub fn run(args: &LodCmdArgs, ctx: &Ctx) -> anyhow::Result<Status> {
    let options = steps::lod_options(&args.lod)?;
    let compress = steps::compress_options(&args.compress)?;
    check_output_path(&args.output)?;
    let label = args.file.display().to_string();
    let mut scene = crate::input::import(&args.file, &args.import)?;
    steps::lods(&mut scene, options.as_ref(), &label)?;
    let written = write_scene(&scene, &label, &args.output, compress.as_ref())?;
    let d = details(&scene, written, Vec::new(), Vec::new(), Vec::new());
    emit_one(&label, &args.output, d, ctx)?;
    Ok(Status::Success)
}
