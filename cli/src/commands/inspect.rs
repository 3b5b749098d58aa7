//! `sinew inspect FILE`: what a file holds, as a human report on stderr or JSON on stdout.
//!
//! The JSON report is [`crate::report::InspectReport`]; its field names are a stable interface documented in
//! docs/cli.md. Add fields, never rename or remove them.

use crate::cli::InspectArgs;
use crate::output::Ctx;
use crate::report::human;
use crate::report::pose::{pose_report, pose_text};
use crate::report::SectionReport;
use crate::report::{add_encodings, build_report};
use crate::Status;
use anyhow::Context;
use sinew_pipeline::pose::{self, PoseRequest};

/// Runs `sinew inspect`.
pub fn run(args: &InspectArgs, ctx: &Ctx) -> anyhow::Result<Status> {
    if let Some(spec) = &args.pose {
        return run_pose(args, spec, ctx);
    }
    let scene = crate::input::import(&args.file, &args.import)?;
    let file_size = std::fs::metadata(&args.file).map(|m| m.len()).ok();
    let mut report = build_report(&args.file, file_size, &scene);
    if scene.source_format == sinew_scene::SourceFormat::Sinew {
        // The scene has the decoded curves; how each channel is stored comes from the asset itself.
        // The import above already read and checked the file.
        if let Ok(bytes) = std::fs::read(&args.file) {
            if let Ok(asset) = sinew_core::format::read(&bytes) {
                add_encodings(&mut report, &asset.clips);
            }
            if let Ok(sections) = sinew_core::format::sections(&bytes) {
                report.sections = sections
                    .iter()
                    .map(|s| SectionReport {
                        tag: String::from_utf8_lossy(&s.tag.0).into_owned(),
                        offset: s.offset,
                        size: s.size,
                        checksum_ok: s.checksum_ok,
                        known: s.known,
                    })
                    .collect();
            }
        }
    }
    if ctx.json {
        ctx.emit_json(&report)?;
    } else if ctx.human() {
        eprint!("{}", human(&report));
    }
    Ok(Status::Success)
}

/// Runs `sinew inspect FILE --pose CLIP@TIME`: the file as the runtime sees it (a source file is
/// compiled and read back, as `bake` does), posed by sinew-core at each requested time.
fn run_pose(args: &InspectArgs, spec: &str, ctx: &Ctx) -> anyhow::Result<Status> {
    let shown = args.file.display();
    let req = PoseRequest::parse(spec, args.fps).map_err(anyhow::Error::msg)?;
    let asset = crate::commands::bake::load_asset(&args.file, &args.import, false)?;
    let Some(skeleton) = &asset.skeleton else {
        anyhow::bail!("{shown}: has no skeleton to pose");
    };
    let poses = pose::sample(&asset, &req).with_context(|| format!("{shown}"))?;
    let report = pose_report(&shown.to_string(), skeleton, &poses);
    if ctx.json {
        ctx.emit_json(&report)?;
    } else if ctx.human() {
        eprint!("{}", pose_text(&report));
    }
    Ok(Status::Success)
}
