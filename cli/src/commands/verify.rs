//! `sinew verify`: re-bake a cache with sinew-core using its sidecar's parameters and compare bits.

use crate::cli::VerifyArgs;
use crate::output::Ctx;
use crate::Status;
use anyhow::{bail, Context};
use sinew_pipeline::verify::{self, CacheFormat, NormalsPlacement, Sidecar, VerifyReport};
use std::path::Path;

#[derive(Debug, serde::Serialize)]
struct Report<'a> {
    cache: String,
    against: String,
    identical: bool,
    #[serde(flatten)]
    report: &'a VerifyReport,
}

fn format_of(path: &Path) -> anyhow::Result<CacheFormat> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    Ok(match ext.as_str() {
        "exr" => CacheFormat::Exr,
        "pc2" => CacheFormat::Pc2,
        "mdd" => CacheFormat::Mdd,
        _ => bail!(
            "{}: unknown cache type (expected .exr, .pc2 or .mdd)",
            path.display()
        ),
    })
}

/// Runs `sinew verify`.
pub fn run(args: &VerifyArgs, ctx: &Ctx) -> anyhow::Result<Status> {
    let cache_shown = args.cache.display();
    let format = format_of(&args.cache)?;
    let paths = verify::cache_paths(&args.cache, format);
    let cache = std::fs::read(&args.cache).with_context(|| format!("{cache_shown}: reading"))?;
    let sidecar_bytes = std::fs::read(&paths.sidecar)
        .with_context(|| format!("{}: reading the sidecar", paths.sidecar.display()))?;
    let sidecar: Sidecar = serde_json::from_slice(&sidecar_bytes)
        .with_context(|| format!("{}: not a sinew sidecar", paths.sidecar.display()))?;
    if sidecar.format != format {
        bail!(
            "{}: the sidecar describes a {:?} cache",
            paths.sidecar.display(),
            sidecar.format
        );
    }
    let normals = if format == CacheFormat::Exr && sidecar.normals == Some(NormalsPlacement::File) {
        let p = args
            .cache
            .with_file_name(sidecar.normals_file.as_deref().unwrap_or_default());
        Some(std::fs::read(&p).with_context(|| format!("{}: reading", p.display()))?)
    } else {
        None
    };
    let asset = crate::commands::bake::load_asset(&args.against, &args.import, sidecar.lod > 0)?;
    let report = verify::verify(&asset, &sidecar, &cache, normals.as_deref())
        .with_context(|| format!("{cache_shown}"))?;
    if ctx.json {
        ctx.emit_json(&Report {
            cache: cache_shown.to_string(),
            against: args.against.display().to_string(),
            identical: report.identical(),
            report: &report,
        })?;
    } else if ctx.human() || (!report.identical() && ctx.stderr()) {
        match &report.first {
            None => eprintln!(
                "{cache_shown}: identical to the runtime ({} frames x {} vertices, {} vectors compared)",
                report.frames, report.vertices, report.compared
            ),
            Some(m) => eprintln!(
                "{cache_shown}: differs from the runtime: {} of {} vectors; first at frame {} vertex {} ({}): expected {:?}, found {:?}",
                report.mismatches, report.compared, m.frame, m.vertex, m.what, m.expected, m.found
            ),
        }
    }
    Ok(if report.identical() {
        Status::Success
    } else {
        Status::CheckFailed
    })
}
