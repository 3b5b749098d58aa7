//! `sinew bake`: skin a mesh through clips with sinew-core and write an EXR, PC2 or MDD vertex cache,
//! its JSON sidecar and the matching mesh as OBJ.

use crate::cli::{BakeArgs, CacheFormatArg, NormalsArg, VatEncodingArg, VertexOrderArg};
use crate::output::{check_output_path, write_atomic, Ctx};
use crate::Status;
use anyhow::{bail, Context};
use sinew_core::format::{self, Asset};
use sinew_pipeline::bake::{self, BakeRequest, LayerSpec, VertexOrder};
use sinew_pipeline::cache::vat::VatEncoding;
use sinew_pipeline::cache::{self, Frames};
use sinew_pipeline::preview::cache::{cache_strip, CacheStripReport};
use sinew_pipeline::verify::{self, CacheFormat, CacheOptions, NormalsPlacement};
use std::path::Path;
use std::time::Instant;

/// Loads FILE as the runtime would see it: a `.sinew` is decoded as is; a source file is imported,
/// compiled, written and read back (with LODs generated when `need_lods` and the scene has none).
pub fn load_asset(
    path: &Path,
    import: &crate::cli::ImportArgs,
    need_lods: bool,
) -> anyhow::Result<Asset> {
    let shown = path.display();
    let is_sinew = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("sinew"));
    if is_sinew {
        crate::input::check_input(path)?;
        let bytes = std::fs::read(path).with_context(|| format!("{shown}: reading"))?;
        return format::read(&bytes).with_context(|| format!("{shown}"));
    }
    let mut scene = crate::input::import(path, import)?;
    if need_lods && scene.meshes.iter().all(|m| m.lods.is_empty()) {
        sinew_pipeline::lod::generate_lods(&mut scene, &Default::default())
            .with_context(|| format!("{shown}: generating LODs"))?;
    }
    let bytes = sinew_pipeline::compile::compile_to_bytes(&scene)
        .with_context(|| format!("{shown}: compiling"))?;
    format::read(&bytes).with_context(|| format!("{shown}: reading the compiled asset back"))
}

/// Report of one bake.
#[derive(Debug, serde::Serialize)]
struct Report<'a> {
    input: String,
    outputs: Vec<String>,
    seconds: f64,
    sidecar: &'a verify::Sidecar,
    /// `--preview` only: the frames drawn.
    #[serde(skip_serializing_if = "Option::is_none")]
    preview: Option<CacheStripReport>,
}

/// The `--preview` picture: frames of the cache as written (PC2 and MDD read back from their bytes;
/// EXR from the values it stores, offsets added back to the bind pose).
fn cache_picture(
    baked: &bake::Baked,
    encoded: &verify::Encoded,
    opts: &CacheOptions,
    args: &BakeArgs,
    asset: &Asset,
) -> anyhow::Result<(Vec<u8>, CacheStripReport)> {
    let shown = args.output.display().to_string();
    let frames: Frames = match opts.format {
        CacheFormat::Pc2 => {
            cache::pc2::read(&encoded.cache)
                .with_context(|| shown.clone())?
                .1
        }
        CacheFormat::Mdd => {
            cache::mdd::read(&encoded.cache)
                .with_context(|| shown.clone())?
                .1
        }
        CacheFormat::Exr => {
            let stored = verify::stored_positions(baked, opts);
            let n = baked.frames.vertex_count.max(1);
            let positions = if opts.encoding.is_offset() {
                stored
                    .iter()
                    .enumerate()
                    .map(|(i, d)| *d + baked.bind_positions.get(i % n).copied().unwrap_or_default())
                    .collect()
            } else {
                stored
            };
            Frames {
                positions,
                normals: Vec::new(),
                ..baked.frames.clone()
            }
        }
    };
    let fps = encoded.sidecar.fps;
    let label = |f: usize| {
        baked
            .clips
            .iter()
            .find(|c| f >= c.first_frame && f < c.first_frame + c.frame_count)
            .map(|c| {
                let t = bake::frame_time(f - c.first_frame, c.frame_count, c.duration, fps);
                format!("{} @ {:.3}s (frame {f})", c.name, t)
            })
            .unwrap_or_else(|| format!("frame {f}"))
    };
    let (axes, _) = super::preview::picture_axes(args.up, &args.file, asset);
    let title = format!(
        "{}  |  {} frames x {} vertices at {} fps (as stored)",
        Path::new(&shown)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        frames.frame_count,
        frames.vertex_count,
        fps
    );
    cache_strip(
        &frames,
        &baked.indices,
        sinew_pipeline::preview::camera::Facing::of(axes, false),
        &title,
        label,
    )
    .map_err(anyhow::Error::msg)
    .with_context(|| shown.clone())
}

/// Runs `sinew bake`.
pub fn run(args: &BakeArgs, ctx: &Ctx) -> anyhow::Result<Status> {
    let start = Instant::now();
    let shown = args.file.display();
    if let Some(f) = args.fps {
        bake::check_fps(f, "").with_context(|| format!("{shown}"))?;
    }
    check_output_path(&args.output)?;
    if let Some(p) = &args.preview {
        super::preview::check_png_output(p)?;
    }
    let format = match args.format {
        CacheFormatArg::Exr => CacheFormat::Exr,
        CacheFormatArg::Pc2 => CacheFormat::Pc2,
        CacheFormatArg::Mdd => CacheFormat::Mdd,
    };
    if args.max_width == 0 {
        bail!("--max-width must be at least 1");
    }
    let layers = args
        .layer
        .iter()
        .map(|s| LayerSpec::parse(s))
        .collect::<Result<Vec<_>, _>>()
        .map_err(anyhow::Error::msg)?;
    if !layers.is_empty() && !args.clip.is_empty() {
        bail!("give --clip or --layer, not both");
    }
    let asset = load_asset(&args.file, &args.import, args.lod > 0)?;
    let meshes = crate::steps::body_meshes(&asset, &args.body)
        .with_context(|| format!("{shown}"))?
        .unwrap_or_default();
    let request = BakeRequest {
        clips: args.clip.clone(),
        layers,
        fps: args.fps,
        meshes,
        lod: args.lod,
        vertex_order: match args.vertex_order {
            VertexOrderArg::Split => VertexOrder::Split,
            VertexOrderArg::Source => VertexOrder::Source,
        },
    };
    let baked = bake::bake(&asset, &request).with_context(|| format!("{shown}"))?;
    let opts = CacheOptions {
        format,
        max_width: args.max_width,
        encoding: match args.vat_encoding {
            VatEncodingArg::AbsoluteF32 => VatEncoding::AbsoluteF32,
            VatEncodingArg::OffsetF16 => VatEncoding::OffsetF16,
            VatEncodingArg::OffsetF32 => VatEncoding::OffsetF32,
        },
        normals: match args.normals {
            NormalsArg::Layer => NormalsPlacement::Layer,
            NormalsArg::File => NormalsPlacement::File,
            NormalsArg::None => NormalsPlacement::None,
        },
    };
    let paths = verify::cache_paths(&args.output, format);
    let file_name = |p: &Path| {
        p.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    };
    let encoded = verify::encode(
        &baked,
        &request,
        &opts,
        &file_name(&args.file),
        &file_name(&paths.normals),
    )
    .map_err(anyhow::Error::msg)
    .with_context(|| format!("{}", args.output.display()))?;
    let sidecar_json = serde_json::to_vec_pretty(&encoded.sidecar)?;
    // Everything is encoded before the first file is written.
    let mut files: Vec<(&Path, &[u8])> = vec![(&paths.cache, &encoded.cache)];
    if let Some(n) = &encoded.normals {
        files.push((&paths.normals, n));
    }
    files.push((&paths.sidecar, &sidecar_json));
    let obj = bake::obj(&baked);
    files.push((&paths.obj, obj.as_bytes()));
    let picture = match &args.preview {
        Some(p) => Some((p, cache_picture(&baked, &encoded, &opts, args, &asset)?)),
        None => None,
    };
    if let Some((p, (png, _))) = &picture {
        files.push((p.as_path(), png));
    }
    for (p, bytes) in &files {
        write_atomic(p, bytes)?;
    }
    let report = Report {
        input: args.file.display().to_string(),
        outputs: files.iter().map(|(p, _)| p.display().to_string()).collect(),
        seconds: start.elapsed().as_secs_f64(),
        sidecar: &encoded.sidecar,
        preview: picture.as_ref().map(|(_, (_, r))| r.clone()),
    };
    if ctx.json {
        ctx.emit_json(&report)?;
    } else if ctx.human() {
        let s = &encoded.sidecar;
        eprintln!(
            "baked {} frames x {} vertices at {} fps from {} in {:.2} s",
            s.frame_count, s.vertex_count, s.fps, shown, report.seconds
        );
        for c in &s.clips {
            eprintln!(
                "  {}: frames {}..{}",
                c.name,
                c.first_frame,
                c.first_frame + c.frame_count
            );
        }
        for o in &report.outputs {
            eprintln!("  wrote {o}");
        }
    }
    Ok(Status::Success)
}
