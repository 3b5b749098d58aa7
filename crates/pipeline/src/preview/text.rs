//! Labels: text drawn with the embedded DejaVu Sans Mono (Bitstream Vera licence, see
//! `assets/fonts/README.md`) through ab_glyph's outline rasteriser, blended into the canvas by
//! coverage.

use super::canvas::{Canvas, Rgb};
use ab_glyph::{Font, FontRef, PxScale, ScaleFont};

static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSansMono.ttf");

fn font() -> Option<FontRef<'static>> {
    FontRef::try_from_slice(FONT_BYTES).ok()
}

/// Width in pixels of `text` at `size` pixels (the advance of every character; monospaced).
pub fn width(text: &str, size: f32) -> f32 {
    let Some(f) = font() else { return 0.0 };
    let s = f.as_scaled(PxScale::from(size));
    text.chars().map(|c| s.h_advance(f.glyph_id(c))).sum()
}

/// Draws `text` with its baseline at `y`, starting at `x`, `size` pixels tall. Characters the font
/// lacks draw as its missing-glyph box.
pub fn draw(canvas: &mut Canvas, x: f32, y: f32, size: f32, text: &str, color: Rgb) {
    let Some(f) = font() else { return };
    let scale = PxScale::from(size);
    let s = f.as_scaled(scale);
    let mut pen = x;
    for ch in text.chars() {
        let id = f.glyph_id(ch);
        let glyph = id.with_scale_and_position(scale, ab_glyph::point(pen, y));
        pen += s.h_advance(id);
        if let Some(outline) = f.outline_glyph(glyph) {
            let b = outline.px_bounds();
            outline.draw(|gx, gy, cov| {
                canvas.blend(
                    b.min.x as i64 + i64::from(gx),
                    b.min.y as i64 + i64::from(gy),
                    color,
                    cov,
                );
            });
        }
    }
}

/// `text` cut to at most `max` pixels wide at `size`, ending in `…` when cut.
pub fn fit(text: &str, size: f32, max: f32) -> String {
    if width(text, size) <= max {
        return text.to_string();
    }
    let mut out: String = String::new();
    for ch in text.chars() {
        let next = format!("{out}{ch}…");
        if width(&next, size) > max {
            break;
        }
        out.push(ch);
    }
    out.push('…');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_marks_pixels_and_is_monospaced() {
        assert!(font().is_some());
        let w1 = width("a", 12.0);
        assert!(w1 > 5.0 && w1 < 9.0, "{w1}");
        assert!((width("abcd", 12.0) - 4.0 * w1).abs() < 1e-3);
        let mut c = Canvas::new(40, 20, [0, 0, 0]).expect("canvas");
        draw(&mut c, 2.0, 15.0, 14.0, "Hi", [255, 255, 255]);
        let lit = c
            .pixmap
            .data()
            .chunks_exact(4)
            .filter(|p| p[0] > 128)
            .count();
        assert!(lit > 10, "{lit}");
    }

    #[test]
    fn long_text_is_cut_to_fit() {
        let t = fit("Bip01 L Forearm Twist", 10.0, 60.0);
        assert!(t.ends_with('…'));
        assert!(width(&t, 10.0) <= 60.0);
        assert_eq!(fit("ok", 10.0, 60.0), "ok");
    }
}
