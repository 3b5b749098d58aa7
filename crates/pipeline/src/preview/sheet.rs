//! The contact sheet of `sinew preview`: a title line, then a row with the rest pose from the front
//! and from the side (skeleton over the mesh) and each LOD beside them (front view, same scale as
//! LOD 0, with its triangle count and measured error), then one row per clip with poses spread across
//! it, then notes. Layout and sizes: [`CELL`], [`CAPTION`], [`TITLE`], [`NOTE`] (docs/cli.md).

use super::camera::{Facing, Fit, Up, View};
use super::canvas::{Canvas, Cell, Rgb};
use super::model::{bind_pose, draw_meshes, draw_skeleton, measured_error, pose, Posed, INK};
use super::text;
use super::textures::Textures;
use crate::body::{self, BodyChoice};
use sinew_core::format::Asset;
use sinew_core::{Animator, Clip, Skeleton};
use std::sync::Arc;

/// Side of one picture cell, pixels.
pub const CELL: u32 = 256;
/// Height of the caption line above each cell.
pub const CAPTION: u32 = 18;
/// Height of the title line.
pub const TITLE: u32 = 30;
/// Height of one note line under the rows.
pub const NOTE: u32 = 16;
/// Most frames a clip strip may ask for.
pub const MAX_FRAMES: usize = 32;
/// Clip rows drawn when no clip is chosen; further clips are listed in a note.
pub const MAX_CLIP_ROWS: usize = 8;

const BACKGROUND: Rgb = [236, 236, 232];
const CELL_BACKGROUND: Rgb = [250, 250, 247];
const MARGIN: f32 = 12.0;

/// What the sheet shows.
#[derive(Debug, Clone, PartialEq)]
pub struct SheetOptions {
    /// Up and facing of the model's clips (clip strips, LOD cells).
    pub facing: Facing,
    /// Up and facing of its bind pose (the rest cells).
    pub rest_facing: Facing,
    /// Only this clip (else every clip, up to [`MAX_CLIP_ROWS`]).
    pub clip: Option<String>,
    /// Poses per clip strip, 1 to [`MAX_FRAMES`].
    pub frames: usize,
    /// Joint names beside the joints of the front rest view.
    pub names: bool,
    /// The title line (usually the file name).
    pub title: String,
    /// The meshes drawn, or `None` for the model's default body ([`crate::body`]).
    pub meshes: Option<Vec<usize>>,
    /// Images of the materials' textures, named as the materials' `texture` strings name them (a
    /// Half-Life model's own images, or files found beside the input).
    pub images: Vec<sinew_scene::Image>,
}

impl Default for SheetOptions {
    fn default() -> Self {
        Self {
            facing: Up::Y.into(),
            rest_facing: Up::Y.into(),
            clip: None,
            frames: 6,
            names: false,
            title: String::new(),
            meshes: None,
            images: Vec::new(),
        }
    }
}

/// One LOD cell.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LodCellReport {
    /// LOD level (1 for the first generated LOD).
    pub level: usize,
    /// Triangles over all meshes at this level.
    pub triangles: usize,
    /// Largest distance from a vertex of the LOD to LOD 0's surface over all meshes, model units.
    pub error_measured: f32,
    /// The same relative to the largest mesh extent (bounding-box diagonal of LOD 0).
    pub error_relative: f32,
}

/// One clip strip.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClipStripReport {
    /// Clip name.
    pub clip: String,
    /// Clip times of the poses drawn, seconds.
    pub times: Vec<f32>,
}

/// What was drawn.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct SheetReport {
    /// Picture width, pixels.
    pub width: u32,
    /// Picture height, pixels.
    pub height: u32,
    /// Cells per row.
    pub columns: u32,
    /// Rows of cells.
    pub rows: u32,
    /// The meshes drawn (the model's body, or the ones asked for), by name.
    pub meshes: Vec<String>,
    /// Materials drawn with their texture.
    pub textured_materials: usize,
    /// Triangles of LOD 0 over all meshes drawn.
    pub triangles: usize,
    /// The LOD cells.
    pub lods: Vec<LodCellReport>,
    /// The clip strips.
    pub clips: Vec<ClipStripReport>,
    /// Notes written under the picture.
    pub notes: Vec<String>,
}

/// Why no sheet was drawn.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SheetError {
    /// `--clip` names no clip of the file.
    #[error("no clip named {name:?} (clips: {available})")]
    UnknownClip {
        /// The name asked for.
        name: String,
        /// The file's clips, comma-separated.
        available: String,
    },
    /// `--frames` out of range.
    #[error("--frames must be 1 to {MAX_FRAMES}, not {0}")]
    Frames(usize),
    /// The picture would be too large.
    #[error("the picture would be {0}x{1} pixels")]
    TooLarge(u32, u32),
    /// PNG encoding failed.
    #[error("encoding the PNG: {0}")]
    Png(String),
}

/// The clip times a strip of `n` poses shows: spread evenly from 0 to the end (a looping clip stops
/// one step short of its end, which is its start again).
pub fn strip_times(clip: &Clip, n: usize) -> Vec<f32> {
    let d = clip.duration().max(0.0);
    if n <= 1 {
        return vec![0.0];
    }
    let steps = if clip.looping() { n } else { n - 1 };
    (0..n).map(|k| d * k as f32 / steps as f32).collect()
}

/// The local pose of `clip` at `t` through the runtime's animator.
fn clip_pose(skeleton: &Arc<Skeleton>, clip: &Clip, t: f32) -> Option<Vec<sinew_core::Transform>> {
    let mut a = Animator::new(Arc::clone(skeleton));
    let id = a.add_clip(Arc::new(clip.clone()));
    a.activate(id).ok()?;
    a.set_time(id, t).ok()?;
    let mut out = skeleton.bind_local().to_vec();
    a.evaluate(&mut out).ok()?;
    Some(out)
}

fn caption(canvas: &mut Canvas, cell: Cell, s: &str) {
    let t = text::fit(s, 11.0, cell.w as f32 - 8.0);
    text::draw(
        canvas,
        cell.x as f32 + 4.0,
        cell.y as f32 - 5.0,
        11.0,
        &t,
        INK,
    );
}

/// Draws the contact sheet of `asset` and encodes it as PNG.
pub fn contact_sheet(
    asset: &Asset,
    opts: &SheetOptions,
) -> Result<(Vec<u8>, SheetReport), SheetError> {
    if opts.frames == 0 || opts.frames > MAX_FRAMES {
        return Err(SheetError::Frames(opts.frames));
    }
    let chosen = match &opts.meshes {
        Some(m) => m.clone(),
        None => body::select(asset, &BodyChoice::Default).unwrap_or_default(),
    };
    let asset = &body::only(asset, &chosen);
    let textures = Textures::new(asset, &opts.images);
    let skeleton = asset
        .skeleton
        .clone()
        .filter(|s| !s.is_empty())
        .map(Arc::new);
    let mut notes = Vec::new();
    // Clips to draw.
    let clips: Vec<&Clip> = match &opts.clip {
        Some(name) => match asset.clips.iter().find(|c| c.name() == name) {
            Some(c) => vec![c],
            None => {
                return Err(SheetError::UnknownClip {
                    name: name.clone(),
                    available: asset
                        .clips
                        .iter()
                        .map(Clip::name)
                        .collect::<Vec<_>>()
                        .join(", "),
                })
            }
        },
        None => asset.clips.iter().take(MAX_CLIP_ROWS).collect(),
    };
    if opts.clip.is_none() && asset.clips.len() > MAX_CLIP_ROWS {
        notes.push(format!(
            "{} more clips not drawn (choose one with --clip NAME)",
            asset.clips.len() - MAX_CLIP_ROWS
        ));
    }
    let clips: Vec<&Clip> = if skeleton.is_some() {
        clips
    } else {
        if !clips.is_empty() {
            notes.push("clips not drawn: the file has no skeleton".to_string());
        }
        Vec::new()
    };
    let lod_levels = asset
        .meshes
        .iter()
        .map(|m| m.lods.len())
        .max()
        .unwrap_or(0)
        .saturating_sub(1);
    let strip_len = if clips.is_empty() { 0 } else { opts.frames };
    let columns = (2 + lod_levels).max(strip_len) as u32;
    let rows = 1 + clips.len() as u32;
    let width = columns * CELL;
    let height = TITLE + rows * (CAPTION + CELL) + notes.len() as u32 * NOTE + NOTE;
    let mut canvas =
        Canvas::new(width, height, BACKGROUND).ok_or(SheetError::TooLarge(width, height))?;
    let cell_at = |col: u32, row: u32| Cell {
        x: col * CELL + 2,
        y: TITLE + row * (CAPTION + CELL) + CAPTION,
        w: CELL - 4,
        h: CELL - 4,
    };
    let lod0_triangles: usize = asset
        .meshes
        .iter()
        .map(|m| m.lods.first().map_or(0, |l| l.triangle_count()))
        .sum();
    let title = format!(
        "{}  |  {} joints, {} meshes, {} triangles, {} clips",
        opts.title,
        skeleton.as_ref().map_or(0, |s| s.len()),
        asset.meshes.len(),
        lod0_triangles,
        asset.clips.len()
    );
    let t = text::fit(&title, 14.0, width as f32 - 16.0);
    text::draw(&mut canvas, 8.0, 20.0, 14.0, &t, INK);

    // Row 0: rest pose front and side, then LODs.
    let rest = pose(asset, &bind_pose(asset));
    let rest_points = rest.points(0);
    let mut lods = Vec::new();
    let mut cells: Vec<(Cell, View, String, usize)> = vec![
        (
            cell_at(0, 0),
            View::front(opts.rest_facing),
            "rest pose, front".to_string(),
            0,
        ),
        (
            cell_at(1, 0),
            View::side(opts.rest_facing),
            "rest pose, side".to_string(),
            0,
        ),
    ];
    let extent = asset
        .meshes
        .iter()
        .filter_map(|m| m.lods.first())
        .map(|l| diagonal(&l.positions))
        .fold(0.0f32, f32::max);
    for level in 1..=lod_levels {
        let mut tris = 0;
        let mut err = 0.0f32;
        for m in &asset.meshes {
            let li = level.min(m.lods.len().saturating_sub(1));
            if let (Some(base), Some(l)) = (m.lods.first(), m.lods.get(li)) {
                tris += l.triangle_count();
                if li > 0 {
                    err = err.max(measured_error(base, l));
                }
            }
        }
        let rel = if extent > 0.0 { err / extent } else { 0.0 };
        cells.push((
            cell_at(1 + level as u32, 0),
            View::front(opts.rest_facing),
            format!(
                "LOD{level}: {tris} tris, err {} ({:.2}%)",
                short(err),
                rel * 100.0
            ),
            level,
        ));
        lods.push(LodCellReport {
            level,
            triangles: tris,
            error_measured: err,
            error_relative: rel,
        });
    }
    if lod_levels > 0 {
        cells[0].2 = format!("rest pose, front: LOD0 {lod0_triangles} tris");
    }
    for (cell, view, label, level) in &cells {
        canvas.fill_rect(*cell, CELL_BACKGROUND);
        caption(&mut canvas, *cell, label);
        let fit = Fit::new(*view, rest_points.iter().copied(), *cell, MARGIN);
        draw_meshes(&mut canvas, asset, &rest, *level, &fit, *cell, &textures);
        if let (Some(s), 0) = (&skeleton, *level) {
            draw_skeleton(&mut canvas, s, &rest, &fit, opts.names && cell.x <= 2);
        }
    }
    if asset.meshes.is_empty() && skeleton.is_none() {
        let c = cell_at(0, 0);
        text::draw(
            &mut canvas,
            c.x as f32 + 20.0,
            c.y as f32 + 120.0,
            13.0,
            "nothing to draw",
            INK,
        );
    }

    // One row per clip.
    let mut strips = Vec::new();
    if let Some(s) = &skeleton {
        for (row, clip) in clips.iter().enumerate() {
            let times = strip_times(clip, opts.frames);
            let poses: Vec<Posed> = times
                .iter()
                .map(|&t| {
                    pose(
                        asset,
                        &clip_pose(s, clip, t).unwrap_or_else(|| bind_pose(asset)),
                    )
                })
                .collect();
            let points: Vec<_> = poses.iter().flat_map(|p| p.points(0)).collect();
            for (col, (p, t)) in poses.iter().zip(&times).enumerate() {
                let cell = cell_at(col as u32, 1 + row as u32);
                canvas.fill_rect(cell, CELL_BACKGROUND);
                caption(
                    &mut canvas,
                    cell,
                    &format!("{} @ {}s", clip.name(), short(*t)),
                );
                let fit = Fit::new(
                    View::front(opts.facing),
                    points.iter().copied(),
                    cell,
                    MARGIN,
                );
                draw_meshes(&mut canvas, asset, p, 0, &fit, cell, &textures);
                draw_skeleton(&mut canvas, s, p, &fit, false);
            }
            strips.push(ClipStripReport {
                clip: clip.name().to_string(),
                times,
            });
        }
    }
    let notes_y = TITLE + rows * (CAPTION + CELL) + NOTE - 4;
    for (i, n) in notes.iter().enumerate() {
        text::draw(
            &mut canvas,
            8.0,
            (notes_y + i as u32 * NOTE) as f32,
            11.0,
            n,
            INK,
        );
    }
    let png = canvas.png().map_err(SheetError::Png)?;
    Ok((
        png,
        SheetReport {
            width,
            height,
            columns,
            rows,
            meshes: asset.meshes.iter().map(|m| m.name.clone()).collect(),
            textured_materials: textures.len(),
            triangles: lod0_triangles,
            lods,
            clips: strips,
            notes,
        },
    ))
}

/// A thumbnail: the model's rest pose from the front (its bind facing), textured, without skeleton
/// lines unless it has no meshes, `size` pixels square (16 to 1024), for batch reports. `opts` gives
/// the facing, the meshes (default body) and the images; its clip, frames, names and title are not
/// used.
pub fn thumbnail(asset: &Asset, opts: &SheetOptions, size: u32) -> Result<Vec<u8>, SheetError> {
    let size = size.clamp(16, 1024);
    let chosen = match &opts.meshes {
        Some(m) => m.clone(),
        None => body::select(asset, &BodyChoice::Default).unwrap_or_default(),
    };
    let asset = &body::only(asset, &chosen);
    let textures = Textures::new(asset, &opts.images);
    let mut canvas =
        Canvas::new(size, size, CELL_BACKGROUND).ok_or(SheetError::TooLarge(size, size))?;
    let cell = Cell {
        x: 0,
        y: 0,
        w: size,
        h: size,
    };
    let rest = pose(asset, &bind_pose(asset));
    let fit = Fit::new(
        View::front(opts.rest_facing),
        rest.points(0),
        cell,
        (size as f32 * 0.05).max(2.0),
    );
    draw_meshes(&mut canvas, asset, &rest, 0, &fit, cell, &textures);
    if asset.meshes.is_empty() {
        if let Some(s) = asset.skeleton.as_ref().filter(|s| !s.is_empty()) {
            draw_skeleton(&mut canvas, s, &rest, &fit, false);
        }
    }
    canvas.png().map_err(SheetError::Png)
}

/// A number in at most four significant figures (`0.0123`, `1.5`, `120`).
fn short(v: f32) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s.is_empty() || s == "-" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// Bounding-box diagonal of points (0 for none).
fn diagonal(p: &[sinew_core::glam::Vec3]) -> f32 {
    let Some(first) = p.first() else { return 0.0 };
    let (lo, hi) = p
        .iter()
        .fold((*first, *first), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    (hi - lo).length()
}

#[cfg(test)]
mod tests {
    use crate::preview::sheet::*;

    #[test]
    fn strips_spread_over_the_clip() {
        let plain = Clip::from_curves("a", 2.0, 30.0, false, false, Vec::new()).expect("clip");
        assert_eq!(strip_times(&plain, 5), vec![0.0, 0.5, 1.0, 1.5, 2.0]);
        let looping = plain.with_looping(true);
        assert_eq!(strip_times(&looping, 4), vec![0.0, 0.5, 1.0, 1.5]);
        assert_eq!(strip_times(&plain, 1), vec![0.0]);
    }

    #[test]
    fn a_thumbnail_is_square_and_an_empty_asset_draws_a_plain_one() {
        let png = thumbnail(&Asset::default(), &SheetOptions::default(), 64).expect("png");
        let dec = png::Decoder::new(std::io::Cursor::new(png));
        let r = dec.read_info().expect("header");
        assert_eq!((r.info().width, r.info().height), (64, 64));
    }

    #[test]
    fn short_numbers() {
        assert_eq!(short(0.012345), "0.0123");
        assert_eq!(short(1.5), "1.5");
        assert_eq!(short(0.0), "0");
        assert_eq!(short(120.0), "120");
    }

    #[test]
    fn an_empty_asset_draws_a_two_cell_sheet() {
        let (png, r) = contact_sheet(&Asset::default(), &SheetOptions::default()).expect("sheet");
        assert_eq!(
            (r.width, r.height),
            (2 * CELL, TITLE + CAPTION + CELL + NOTE)
        );
        assert!(png.starts_with(b"\x89PNG"));
        assert!(matches!(
            contact_sheet(
                &Asset::default(),
                &SheetOptions {
                    frames: 0,
                    ..Default::default()
                }
            ),
            Err(SheetError::Frames(0))
        ));
    }
}
