//! Texture images a source carried (Half-Life models embed 8-bit paletted textures), written as PNG
//! files beside a converted model: file names, deterministic encoding, and the material references
//! that point at them.

use sinew_scene::{Image, Scene};

/// The PNG file name of an image written beside `output_stem`: `<stem>_<texture stem>.png`, with
/// characters that are unsafe in file names replaced by `_`.
pub fn png_name(output_stem: &str, image: &Image) -> String {
    let base = image.name.rsplit(['/', '\\']).next().unwrap_or(&image.name);
    let stem = base.rsplit_once('.').map_or(base, |(s, _)| s);
    let clean: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("{output_stem}_{clean}.png")
}

/// Encodes an image as an 8-bit RGBA PNG. The bytes depend only on the image (no time stamps).
pub fn encode_png(image: &Image) -> Result<Vec<u8>, String> {
    let expected = (image.width as usize)
        .checked_mul(image.height as usize)
        .and_then(|n| n.checked_mul(4));
    if expected != Some(image.rgba.len()) || image.width == 0 || image.height == 0 {
        return Err(format!(
            "image {:?}: {} bytes for {}x{} RGBA",
            image.name,
            image.rgba.len(),
            image.width,
            image.height
        ));
    }
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, image.width, image.height);
        enc.set_color(png::ColorType::Rgba);
        enc.set_depth(png::BitDepth::Eight);
        // fdeflate: several times faster than the default for a few percent more bytes.
        enc.set_compression(png::Compression::Fast);
        let mut w = enc
            .write_header()
            .map_err(|e| format!("image {:?}: {e}", image.name))?;
        w.write_image_data(&image.rgba)
            .map_err(|e| format!("image {:?}: {e}", image.name))?;
    }
    Ok(out)
}

/// The PNG files for a scene's images, named for `output_stem`, and the scene's materials pointed at
/// them: `(file name, bytes)` in image order.
pub fn textures_for_output(
    scene: &mut Scene,
    output_stem: &str,
) -> Result<Vec<(String, Vec<u8>)>, String> {
    let mut files = Vec::with_capacity(scene.images.len());
    for image in &scene.images {
        let name = png_name(output_stem, image);
        let bytes = encode_png(image)?;
        for m in &mut scene.materials {
            if m.texture.as_deref() == Some(image.name.as_str()) {
                m.texture = Some(name.clone());
            }
        }
        files.push((name, bytes));
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;
    use sinew_scene::{Material, SourceFormat};

    fn image() -> Image {
        Image {
            name: "skins/Body Skin.bmp".into(),
            width: 2,
            height: 1,
            rgba: vec![255, 0, 0, 255, 0, 0, 255, 0],
        }
    }

    #[test]
    fn names_are_safe_and_materials_point_at_them() {
        assert_eq!(png_name("man", &image()), "man_Body_Skin.png");
        let mut scene = Scene::new(SourceFormat::Mdl);
        scene.images.push(image());
        scene.materials.push(Material {
            name: "Body Skin.bmp".into(),
            base_color: [1.0; 4],
            texture: Some("skins/Body Skin.bmp".into()),
        });
        let files = textures_for_output(&mut scene, "man").unwrap();
        assert_eq!(files.len(), 1);
        assert_eq!(
            scene.materials[0].texture.as_deref(),
            Some("man_Body_Skin.png")
        );
        // A PNG: signature, then IHDR with width 2, height 1, depth 8, colour type 6 (RGBA).
        let b = &files[0].1;
        assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n");
        assert_eq!(&b[12..16], b"IHDR");
        assert_eq!(u32::from_be_bytes([b[16], b[17], b[18], b[19]]), 2);
        assert_eq!(u32::from_be_bytes([b[20], b[21], b[22], b[23]]), 1);
        assert_eq!((b[24], b[25]), (8, 6));
        // Same image, same bytes.
        assert_eq!(encode_png(&image()).unwrap(), files[0].1);
        let mut bad = image();
        bad.rgba.pop();
        assert!(encode_png(&bad).is_err());
    }
}
