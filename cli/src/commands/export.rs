//! `sinew export FILE -o OUT.glb|OUT.gltf`: the file as the runtime sees it, written as glTF 2.0 with
//! every clip sampled through sinew-core ([`sinew_pipeline::export`]; decisions in docs/export.md).

use crate::cli::ExportArgs;
use crate::output::{check_output_path, write_atomic, Ctx};
use crate::Status;
use anyhow::Context;
use sinew_core::format::{self, Asset};
use sinew_pipeline::export::{self, Container, ExportImage, ExportOptions, ExportReport};
use sinew_scene::Scene;
use std::path::Path;

/// Largest texture file embedded from beside the input.
const MAX_TEXTURE_BYTES: u64 = 64 << 20;

/// The JSON report of `export`.
#[derive(Debug, serde::Serialize)]
pub struct ExportCmdReport {
    /// The input path as given.
    pub input: String,
    /// The output path.
    pub output: String,
    /// `glb` or `gltf`.
    pub container: &'static str,
    /// Size of the written file.
    pub bytes: usize,
    /// What went in and what was left out.
    #[serde(flatten)]
    pub export: ExportReport,
}

/// Runs `sinew export`.
pub fn run(args: &ExportArgs, ctx: &Ctx) -> anyhow::Result<Status> {
    let out_shown = args.output.display();
    let container = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .and_then(Container::from_extension)
        .with_context(|| format!("{out_shown}: the output must end in .glb or .gltf"))?;
    check_output_path(&args.output)?;
    let lods = crate::steps::lod_spec_options(args.lod.as_deref())?;
    let loaded = load(&args.file, &args.import, lods.as_ref())?;
    let shown = args.file.display().to_string();
    let game = crate::report::game::game_report(&loaded.asset.game)
        .map(|g| serde_json::to_value(g).context("encoding the game data"))
        .transpose()?;
    let meshes =
        crate::steps::body_meshes(&loaded.asset, &args.body).with_context(|| shown.clone())?;
    let (bytes, report) = export::export(
        &loaded.asset,
        &loaded.images,
        container,
        &ExportOptions {
            game,
            meshes,
            variants: args.variants,
        },
    )
    .map_err(anyhow::Error::msg)
    .with_context(|| shown.clone())?;
    write_atomic(&args.output, &bytes)?;
    let report = ExportCmdReport {
        input: shown,
        output: args.output.display().to_string(),
        container: match container {
            Container::Glb => "glb",
            Container::Gltf => "gltf",
        },
        bytes: bytes.len(),
        export: report,
    };
    if ctx.json {
        ctx.emit_json(&report)?;
    } else if ctx.human() {
        eprint!("{}", human(&report));
    }
    Ok(Status::Success)
}

/// The human report (stderr).
pub fn human(r: &ExportCmdReport) -> String {
    let e = &r.export;
    let mut s = format!(
        "{} -> {}: {} bytes, {} joints, {} meshes (+{} LOD meshes, +{} other meshes, {} scenes), {} materials, {} images, {} animations ({} keys)\n",
        r.input, r.output, r.bytes, e.joints, e.meshes, e.lod_meshes, e.other_meshes, e.scenes, e.materials, e.images, e.animations, e.keys
    );
    for n in &e.notes {
        s.push_str(&format!("  note: {n}\n"));
    }
    s
}

/// An input as the exporter takes it.
pub struct Loaded {
    /// The decoded asset (a `.sinew` as stored; a source file imported and compiled).
    pub asset: Asset,
    /// Images found for the materials' textures.
    pub images: Vec<ExportImage>,
    /// The same images decoded to RGBA (those a Half-Life source carries, those a glTF stores inside
    /// itself, and PNG or JPEG files found beside the input), named by the materials' `texture`
    /// strings: what pictures draw.
    pub decoded: Vec<sinew_scene::Image>,
}

/// Loads FILE as the runtime would see it: a `.sinew` is decoded as stored (compressed clips stay
/// compressed) unless `lods` asks for new LODs; a source file is imported, given LODs when asked, and
/// compiled. Images: those the source carries (Half-Life), those a glTF stores inside itself, else
/// files beside FILE that materials name.
pub fn load(
    path: &Path,
    import: &crate::cli::ImportArgs,
    lods: Option<&Option<sinew_pipeline::lod::LodOptions>>,
) -> anyhow::Result<Loaded> {
    let shown = path.display();
    let is_sinew = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("sinew"));
    let mut scene_images = Vec::new();
    let asset = if is_sinew && lods.is_none() {
        crate::input::check_input(path)?;
        let bytes = std::fs::read(path).with_context(|| format!("{shown}: reading"))?;
        format::read(&bytes).with_context(|| format!("{shown}"))?
    } else {
        let mut scene: Scene = crate::input::import(path, import)?;
        if let Some(l) = lods {
            crate::steps::lods(&mut scene, l.as_ref(), &shown.to_string())?;
        }
        scene_images = std::mem::take(&mut scene.images);
        let bytes = sinew_pipeline::compile::compile_to_bytes(&scene)
            .with_context(|| format!("{shown}: compiling"))?;
        format::read(&bytes).with_context(|| format!("{shown}: reading the compiled asset back"))?
    };
    let mut images = Vec::new();
    let mut decoded = scene_images.clone();
    for img in &scene_images {
        let bytes = sinew_pipeline::texture::encode_png(img).map_err(anyhow::Error::msg)?;
        images.push(ExportImage {
            key: img.name.clone(),
            name: img.name.clone(),
            mime: "image/png".to_string(),
            bytes,
            alpha_mask: img.rgba.chunks_exact(4).any(|p| p[3] < 255),
        });
    }
    // Images a glTF source stores inside itself (materials name them `images[N]`).
    let is_gltf = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"));
    let mut embedded = Vec::new();
    if is_gltf && !is_sinew {
        let bytes = std::fs::read(path).with_context(|| format!("{shown}: reading"))?;
        let resolve = sinew_import::beside(path);
        embedded = sinew_import::gltf::embedded_images(&shown.to_string(), &bytes, &resolve)?;
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    for m in &asset.materials {
        let Some(t) = &m.texture else { continue };
        if images.iter().any(|i| &i.key == t) {
            continue;
        }
        let found = match embedded.iter().find(|(k, _)| k == t) {
            Some((k, b)) => image_of(k, k, b.clone()),
            None => texture_file(dir, t),
        };
        if let Some(img) = found {
            decoded.extend(sinew_pipeline::texture::decode_image(&img.key, &img.bytes));
            images.push(img);
        }
    }
    Ok(Loaded {
        asset,
        images,
        decoded,
    })
}

/// A PNG or JPEG file named by a material, relative to the input's folder; `None` when it is not
/// there, too large, or neither PNG nor JPEG.
fn texture_file(dir: &Path, texture: &str) -> Option<ExportImage> {
    if texture.contains("://") || texture.starts_with("data:") {
        return None;
    }
    let p = dir.join(texture);
    let meta = std::fs::metadata(&p).ok()?;
    if !meta.is_file() || meta.len() > MAX_TEXTURE_BYTES {
        return None;
    }
    let bytes = std::fs::read(&p).ok()?;
    let name = p
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| texture.to_string());
    image_of(texture, &name, bytes)
}

/// An image to embed, keyed `key`, when `bytes` are a PNG or JPEG file.
fn image_of(key: &str, name: &str, bytes: Vec<u8>) -> Option<ExportImage> {
    let mime = if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        "image/png"
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        "image/jpeg"
    } else {
        return None;
    };
    Some(ExportImage {
        key: key.to_string(),
        name: name.to_string(),
        mime: mime.to_string(),
        bytes,
        alpha_mask: false,
    })
}
