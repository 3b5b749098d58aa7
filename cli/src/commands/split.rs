//! `sinew split FILE --at JOINT [--mask NAME=J,...] -o OUT.sinew`: partial-body clips. The report is
//! the same per-output object as `convert` ([`crate::report::FileReport`]).

use crate::cli::SplitArgs;
use crate::commands::convert::{details, emit_one, write_scene};
use crate::output::{check_output_path, Ctx};
use crate::steps::{self, SplitPlan};
use crate::Status;
use anyhow::bail;

/// Runs `sinew split`.
pub fn run(args: &SplitArgs, ctx: &Ctx) -> anyhow::Result<Status> {
    let plan = SplitPlan::parse(&args.split)?;
    if plan.is_empty() {
        bail!("split: give at least one --at JOINT or --mask NAME=JOINT,...");
    }
    let compress = steps::compress_options(&args.compress)?;
    check_output_path(&args.output)?;
    let label = args.file.display().to_string();
    let mut scene = crate::input::import(&args.file, &args.import)?;
    steps::check_split(&scene, &plan, &label)?;
    if scene.clips.is_empty() {
        bail!("{label}: holds no clip to split");
    }
    let splits = steps::split(&mut scene, &plan, &label)?;
    let written = write_scene(&scene, &label, &args.output, compress.as_ref())?;
    let d = details(&scene, written, Vec::new(), Vec::new(), splits);
    emit_one(&label, &args.output, d, ctx)?;
    Ok(Status::Success)
}
