//! The picture of a baked cache (`sinew bake --preview`): a strip of frames spread over the cache,
//! drawn from the positions the cache file holds (read back from its bytes), with the mesh's triangles.

use super::camera::{Facing, Fit, View};
use super::canvas::{Canvas, Cell, Rgb};
use super::model::{draw_meshes, Posed, INK};
use super::sheet::{CAPTION, CELL, TITLE};
use super::text;
use crate::cache::Frames;
use sinew_core::format::Asset;
use sinew_core::{Lod, Mesh};

/// Frames drawn (fewer when the cache has fewer).
pub const STRIP: usize = 6;

const BACKGROUND: Rgb = [236, 236, 232];
const CELL_BACKGROUND: Rgb = [250, 250, 247];

/// What the strip shows.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct CacheStripReport {
    /// Picture width, pixels.
    pub width: u32,
    /// Picture height, pixels.
    pub height: u32,
    /// The cache frames drawn (0-based).
    pub frames: Vec<usize>,
}

/// The frames of a strip of at most [`STRIP`] over `count` frames: first, last and evenly between.
pub fn strip_frames(count: usize) -> Vec<usize> {
    match count {
        0 => Vec::new(),
        n if n <= STRIP => (0..n).collect(),
        n => (0..STRIP).map(|k| k * (n - 1) / (STRIP - 1)).collect(),
    }
}

/// Draws frames of `frames` (positions in the cache's vertex order) as triangles `indices`; `label`
/// captions frame `f` (clip name and time), `title` heads the picture.
pub fn cache_strip(
    frames: &Frames,
    indices: &[u32],
    facing: Facing,
    title: &str,
    label: impl Fn(usize) -> String,
) -> Result<(Vec<u8>, CacheStripReport), String> {
    let shown = strip_frames(frames.frame_count);
    let n = frames.vertex_count;
    if frames.positions.len() != n * frames.frame_count {
        return Err(format!(
            "{} positions for {} frames of {n} vertices",
            frames.positions.len(),
            frames.frame_count
        ));
    }
    let columns = shown.len().max(1) as u32;
    let width = columns * CELL;
    let height = TITLE + CAPTION + CELL + 8;
    let mut canvas = Canvas::new(width, height, BACKGROUND).ok_or("picture too large")?;
    let t = text::fit(title, 14.0, width as f32 - 16.0);
    text::draw(&mut canvas, 8.0, 20.0, 14.0, &t, INK);
    // One mesh with the cache's triangles; each frame's positions are its pose.
    let asset = Asset {
        meshes: vec![Mesh {
            name: String::new(),
            lods: vec![Lod {
                indices: indices.to_vec(),
                ..Default::default()
            }],
        }],
        ..Default::default()
    };
    let posed: Vec<Posed> = shown
        .iter()
        .map(|&f| Posed {
            models: Vec::new(),
            positions: vec![vec![frames.frame(f).to_vec()]],
        })
        .collect();
    let points: Vec<_> = posed.iter().flat_map(|p| p.points(0)).collect();
    for (col, (f, p)) in shown.iter().zip(&posed).enumerate() {
        let cell = Cell {
            x: col as u32 * CELL + 2,
            y: TITLE + CAPTION,
            w: CELL - 4,
            h: CELL - 4,
        };
        canvas.fill_rect(cell, CELL_BACKGROUND);
        let c = text::fit(&label(*f), 11.0, cell.w as f32 - 8.0);
        text::draw(
            &mut canvas,
            cell.x as f32 + 4.0,
            cell.y as f32 - 5.0,
            11.0,
            &c,
            INK,
        );
        let fit = Fit::new(View::front(facing), points.iter().copied(), cell, 12.0);
        draw_meshes(&mut canvas, &asset, p, 0, &fit, cell, &Default::default());
    }
    let png = canvas.png()?;
    Ok((
        png,
        CacheStripReport {
            width,
            height,
            frames: shown,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preview::camera::Up;
    use sinew_core::glam::Vec3;

    #[test]
    fn strip_frames_cover_first_and_last() {
        assert_eq!(strip_frames(0), Vec::<usize>::new());
        assert_eq!(strip_frames(3), vec![0, 1, 2]);
        assert_eq!(strip_frames(31), vec![0, 6, 12, 18, 24, 30]);
    }

    #[test]
    fn a_moving_triangle_is_drawn_in_every_cell() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let positions: Vec<Vec3> = (0..4)
            .flat_map(|f| tri.map(|p| p + Vec3::X * f as f32))
            .collect();
        let frames = Frames {
            vertex_count: 3,
            frame_count: 4,
            fps: 30.0,
            positions,
            normals: Vec::new(),
        };
        let (png, r) =
            cache_strip(&frames, &[0, 1, 2], Up::Y.into(), "t", |f| format!("{f}")).expect("strip");
        assert_eq!(r.frames, vec![0, 1, 2, 3]);
        assert_eq!((r.width, r.height), (4 * CELL, TITLE + CAPTION + CELL + 8));
        assert!(png.starts_with(b"\x89PNG"));
        let bad = Frames {
            frame_count: 5,
            ..frames
        };
        assert!(cache_strip(&bad, &[0, 1, 2], Up::Y.into(), "t", |f| format!("{f}")).is_err());
    }
}
