//! The picture being drawn: an RGBA [`tiny_skia::Pixmap`] with a depth buffer, flat-shaded and
//! textured triangles rasterised with a z-buffer (our own: tiny-skia draws 2D paths and has no depth
//! test), lines and dots through tiny-skia, and PNG encoding. Everything is CPU arithmetic in a fixed order: the same calls
//! give the same bytes.

use super::textures::{Blend, Texture};
use sinew_core::glam::{Vec2, Vec3};
use tiny_skia::{FillRule, LineCap, Paint, PathBuilder, Pixmap, Rect, Stroke, Transform};

/// An sRGB colour, 8 bits per channel.
pub type Rgb = [u8; 3];

/// A pixel rectangle: x, y, width, height.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cell {
    /// Left edge.
    pub x: u32,
    /// Top edge.
    pub y: u32,
    /// Width.
    pub w: u32,
    /// Height.
    pub h: u32,
}

/// An RGBA picture with a depth buffer.
pub struct Canvas {
    /// The pixels (every pixel opaque).
    pub pixmap: Pixmap,
    depth: Vec<f32>,
}

fn paint(c: Rgb) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color_rgba8(c[0], c[1], c[2], 255);
    p.anti_alias = true;
    p
}

/// Twice the signed area of a triangle in pixel coordinates (positive counter-clockwise in y-down
/// pixels); its absolute value divides the edge weights into barycentric coordinates.
fn signed_area([a, b, c]: [Vec3; 3]) -> f32 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// Calls `f(pixel index, depth, edge weights, corners)` for every pixel of a `width` x `height`
/// canvas inside `clip` whose centre is inside or on an edge of triangle `p` (either winding).
/// The weights go with `corners`, the triangle's corner indices in the order the pixel loop
/// uses (the second and third swapped for a clockwise triangle); dividing them by the triangle's
/// absolute area gives its barycentric coordinates.
fn covered(
    p: [Vec3; 3],
    clip: Cell,
    width: u32,
    height: u32,
    mut f: impl FnMut(usize, f32, [f32; 3], [usize; 3]),
) {
    let area = signed_area(p);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    let corners = if area < 0.0 { [0, 2, 1] } else { [0, 1, 2] };
    let [a, b, c] = corners.map(|k| p[k]);
    let area = area.abs();
    let x0 = a.x.min(b.x).min(c.x).floor().max(clip.x as f32) as i64;
    let y0 = a.y.min(b.y).min(c.y).floor().max(clip.y as f32) as i64;
    let x1 = (a.x.max(b.x).max(c.x).ceil() as i64).min(i64::from(clip.x + clip.w) - 1);
    let y1 = (a.y.max(b.y).max(c.y).ceil() as i64).min(i64::from(clip.y + clip.h) - 1);
    let w = i64::from(width);
    let x1 = x1.min(w - 1);
    let y1 = y1.min(i64::from(height) - 1);
    let edge = |p: Vec3, q: Vec3, x: f32, y: f32| (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
    for y in y0.max(0)..=y1 {
        let py = y as f32 + 0.5;
        for x in x0.max(0)..=x1 {
            let px = x as f32 + 0.5;
            let w0 = edge(b, c, px, py);
            let w1 = edge(c, a, px, py);
            let w2 = edge(a, b, px, py);
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = (w0 * a.z + w1 * b.z + w2 * c.z) / area;
            f((y * w + x) as usize, z, [w0, w1, w2], corners);
        }
    }
}

impl Canvas {
    /// A `w` x `h` canvas filled with `background`. `None` when a side is 0 or too large.
    pub fn new(w: u32, h: u32, background: Rgb) -> Option<Canvas> {
        if w > 16_384 || h > 16_384 {
            return None;
        }
        let mut pixmap = Pixmap::new(w, h)?;
        pixmap.fill(tiny_skia::Color::from_rgba8(
            background[0],
            background[1],
            background[2],
            255,
        ));
        Some(Canvas {
            pixmap,
            depth: vec![f32::INFINITY; w as usize * h as usize],
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.pixmap.width()
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.pixmap.height()
    }

    /// Fills a rectangle (no depth).
    pub fn fill_rect(&mut self, cell: Cell, color: Rgb) {
        if let Some(r) = Rect::from_xywh(cell.x as f32, cell.y as f32, cell.w as f32, cell.h as f32)
        {
            let mut p = paint(color);
            p.anti_alias = false;
            self.pixmap.fill_rect(r, &p, Transform::identity(), None);
        }
    }

    /// Forgets all depths, so the next triangles are drawn over whatever is there.
    pub fn clear_depth(&mut self) {
        self.depth.fill(f32::INFINITY);
    }

    /// Draws one triangle whose corners are (pixel x, pixel y, depth; smaller depth is nearer), inside
    /// `clip` only, both windings, with the z-buffer. A pixel is covered when its centre is inside
    /// or on an edge.
    pub fn triangle(&mut self, a: Vec3, b: Vec3, c: Vec3, color: Rgb, clip: Cell) {
        let (w, h) = (self.pixmap.width(), self.pixmap.height());
        covered([a, b, c], clip, w, h, |i, z, _, _| {
            if z < self.depth[i] {
                self.depth[i] = z;
                let px = &mut self.pixmap.data_mut()[i * 4..i * 4 + 4];
                px.copy_from_slice(&[color[0], color[1], color[2], 255]);
            }
        });
    }

    /// Draws one textured triangle (corners as in [`Canvas::triangle`], texture coordinates `uv`),
    /// each covered pixel the nearest texel times `shade`, with the z-buffer: an opaque texture
    /// writes colour and depth; a masked one skips texels with alpha below 128 (holes); an additive one
    /// adds to the pixel and writes no depth (it hides nothing). A chrome texture is drawn flat in its
    /// mean colour.
    pub fn textured_triangle(
        &mut self,
        p: [Vec3; 3],
        uv: [Vec2; 3],
        tex: &Texture,
        shade: f32,
        clip: Cell,
    ) {
        let lit = |v: u8| (f32::from(v) * shade).round().clamp(0.0, 255.0) as u8;
        // What `covered` divides its edge weights by.
        let area = signed_area(p).abs();
        let (w, h) = (self.pixmap.width(), self.pixmap.height());
        covered(p, clip, w, h, |i, z, [w0, w1, w2], corner| {
            if z >= self.depth[i] {
                return;
            }
            let texel = if tex.chrome {
                [tex.mean[0], tex.mean[1], tex.mean[2], 255]
            } else {
                let [ua, ub, uc] = corner.map(|k| uv[k]);
                let t = (ua * w0 + ub * w1 + uc * w2) / area;
                tex.sample(t.x, t.y)
            };
            let dst = &mut self.pixmap.data_mut()[i * 4..i * 4 + 4];
            match tex.blend {
                Blend::Masked if texel[3] < 128 => return,
                Blend::Additive => {
                    for k in 0..3 {
                        dst[k] = dst[k].saturating_add(lit(texel[k]));
                    }
                    return;
                }
                _ => {
                    dst.copy_from_slice(&[lit(texel[0]), lit(texel[1]), lit(texel[2]), 255]);
                }
            }
            self.depth[i] = z;
        });
    }

    /// An anti-aliased line `width` pixels wide (no depth).
    pub fn line(&mut self, a: (f32, f32), b: (f32, f32), color: Rgb, width: f32) {
        let mut pb = PathBuilder::new();
        pb.move_to(a.0, a.1);
        pb.line_to(b.0, b.1);
        if let Some(path) = pb.finish() {
            let stroke = Stroke {
                width,
                line_cap: LineCap::Round,
                ..Default::default()
            };
            self.pixmap
                .stroke_path(&path, &paint(color), &stroke, Transform::identity(), None);
        }
    }

    /// A filled disc of radius `r` with a thin dark outline (no depth).
    pub fn dot(&mut self, c: (f32, f32), r: f32, color: Rgb) {
        if let Some(path) = PathBuilder::from_circle(c.0, c.1, r) {
            self.pixmap.fill_path(
                &path,
                &paint(color),
                FillRule::Winding,
                Transform::identity(),
                None,
            );
            let stroke = Stroke {
                width: 1.0,
                ..Default::default()
            };
            self.pixmap.stroke_path(
                &path,
                &paint([30, 30, 30]),
                &stroke,
                Transform::identity(),
                None,
            );
        }
    }

    /// Blends `color` into pixel (x, y) with coverage `alpha` (0..1); outside pixels are ignored.
    pub fn blend(&mut self, x: i64, y: i64, color: Rgb, alpha: f32) {
        if x < 0 || y < 0 || x >= i64::from(self.width()) || y >= i64::from(self.height()) {
            return;
        }
        let a = alpha.clamp(0.0, 1.0);
        let i = (y as usize * self.width() as usize + x as usize) * 4;
        let px = &mut self.pixmap.data_mut()[i..i + 3];
        for (p, &c) in px.iter_mut().zip(&color) {
            *p = (f32::from(*p) * (1.0 - a) + f32::from(c) * a).round() as u8;
        }
    }

    /// The picture as an 8-bit RGB PNG (every pixel is opaque, so alpha is dropped).
    pub fn png(&self) -> Result<Vec<u8>, String> {
        let rgb: Vec<u8> = self
            .pixmap
            .data()
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width(), self.height());
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            enc.set_compression(png::Compression::Fast);
            let mut w = enc.write_header().map_err(|e| e.to_string())?;
            w.write_image_data(&rgb).map_err(|e| e.to_string())?;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pixel(c: &Canvas, x: u32, y: u32) -> [u8; 3] {
        let i = ((y * c.width() + x) * 4) as usize;
        let d = c.pixmap.data();
        [d[i], d[i + 1], d[i + 2]]
    }

    #[test]
    fn nearer_triangle_wins_whatever_the_order() {
        let cell = Cell {
            x: 0,
            y: 0,
            w: 8,
            h: 8,
        };
        for near_first in [false, true] {
            let mut c = Canvas::new(8, 8, [0, 0, 0]).expect("canvas");
            let far = |c: &mut Canvas| {
                c.triangle(
                    Vec3::new(0.0, 0.0, 5.0),
                    Vec3::new(8.0, 0.0, 5.0),
                    Vec3::new(0.0, 8.0, 5.0),
                    [255, 0, 0],
                    cell,
                )
            };
            let near = |c: &mut Canvas| {
                c.triangle(
                    Vec3::new(0.0, 0.0, 1.0),
                    Vec3::new(0.0, 8.0, 1.0),
                    Vec3::new(8.0, 0.0, 1.0),
                    [0, 255, 0],
                    cell,
                )
            };
            if near_first {
                near(&mut c);
                far(&mut c);
            } else {
                far(&mut c);
                near(&mut c);
            }
            assert_eq!(pixel(&c, 1, 1), [0, 255, 0]);
            assert_eq!(pixel(&c, 7, 7), [0, 0, 0]);
        }
    }

    #[test]
    fn triangles_stay_inside_their_cell() {
        let mut c = Canvas::new(8, 8, [0, 0, 0]).expect("canvas");
        let cell = Cell {
            x: 0,
            y: 0,
            w: 4,
            h: 8,
        };
        c.triangle(
            Vec3::new(-10.0, -10.0, 0.0),
            Vec3::new(30.0, -10.0, 0.0),
            Vec3::new(-10.0, 30.0, 0.0),
            [9, 9, 9],
            cell,
        );
        assert_eq!(pixel(&c, 3, 3), [9, 9, 9]);
        assert_eq!(pixel(&c, 4, 3), [0, 0, 0]);
    }

    fn tex(blend: Blend, rgba: Vec<u8>) -> Texture {
        Texture {
            width: 2,
            height: 1,
            rgba,
            blend,
            chrome: false,
            mean: [0; 3],
        }
    }

    /// A triangle covering the whole 8x8 canvas with u running 0..1 left to right.
    fn cover(c: &mut Canvas, t: &Texture, z: f32) {
        let cell = Cell {
            x: 0,
            y: 0,
            w: 8,
            h: 8,
        };
        c.textured_triangle(
            [
                Vec3::new(0.0, 0.0, z),
                Vec3::new(16.0, 0.0, z),
                Vec3::new(0.0, 16.0, z),
            ],
            [Vec2::ZERO, Vec2::new(2.0, 0.0), Vec2::new(0.0, 2.0)],
            t,
            1.0,
            cell,
        );
    }

    #[test]
    fn textured_triangles_sample_mask_and_add() {
        // Left texel red, right texel green (u = x / 8: pixels 0-3 and 4-7).
        let opaque = tex(Blend::Opaque, vec![200, 0, 0, 255, 0, 200, 0, 255]);
        let mut c = Canvas::new(8, 8, [0, 0, 0]).expect("canvas");
        cover(&mut c, &opaque, 5.0);
        assert_eq!(pixel(&c, 1, 1), [200, 0, 0]);
        assert_eq!(pixel(&c, 5, 1), [0, 200, 0]);
        // Masked: the transparent right texel leaves what is behind; the left one covers it.
        let masked = tex(Blend::Masked, vec![0, 0, 90, 255, 9, 9, 9, 0]);
        cover(&mut c, &masked, 1.0);
        assert_eq!(pixel(&c, 1, 1), [0, 0, 90]);
        assert_eq!(pixel(&c, 5, 1), [0, 200, 0]);
        // Additive: adds (saturating) and writes no depth, so an opaque triangle drawn after it,
        // farther away, still covers the pixel.
        let add = tex(
            Blend::Additive,
            vec![100, 100, 100, 255, 100, 100, 100, 255],
        );
        cover(&mut c, &add, 0.5);
        assert_eq!(pixel(&c, 1, 1), [100, 100, 190]);
        assert_eq!(pixel(&c, 5, 1), [100, 255, 100]);
        let mut d = Canvas::new(8, 8, [0, 0, 0]).expect("canvas");
        cover(&mut d, &add, 0.5);
        cover(&mut d, &opaque, 5.0);
        assert_eq!(pixel(&d, 1, 1), [200, 0, 0]);
    }

    #[test]
    fn png_decodes_to_the_pixels() {
        let mut c = Canvas::new(3, 2, [10, 20, 30]).expect("canvas");
        c.blend(1, 1, [250, 250, 250], 1.0);
        let bytes = c.png().expect("png");
        let dec = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut r = dec.read_info().expect("header");
        let mut buf = vec![0; r.output_buffer_size().expect("size")];
        let info = r.next_frame(&mut buf).expect("frame");
        assert_eq!((info.width, info.height), (3, 2));
        assert_eq!(&buf[0..3], &[10, 20, 30]);
        assert_eq!(&buf[12..15], &[250, 250, 250]);
    }
}
