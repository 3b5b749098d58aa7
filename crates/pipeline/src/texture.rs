//! Texture images a source carried (Half-Life models embed 8-bit paletted textures), written as PNG
//! files beside a converted model: file names, deterministic encoding, and the material references
//! that point at them; and PNG files decoded back to RGBA (for pictures).

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

/// Largest side of an image [`decode_png`] accepts.
pub const MAX_DECODED_SIDE: u32 = 8192;

/// Decodes a PNG file (any colour type and depth) to 8-bit RGBA, named `name`. `None` when it is not
/// a PNG, is damaged, or has a side above [`MAX_DECODED_SIDE`].
pub fn decode_png(name: &str, bytes: &[u8]) -> Option<Image> {
    let mut dec = png::Decoder::new(std::io::Cursor::new(bytes));
    dec.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = dec.read_info().ok()?;
    let (w, h) = (reader.info().width, reader.info().height);
    if w == 0 || h == 0 || w > MAX_DECODED_SIDE || h > MAX_DECODED_SIDE {
        return None;
    }
    let mut buf = vec![0; reader.output_buffer_size()?];
    let frame = reader.next_frame(&mut buf).ok()?;
    let data = buf.get(..frame.buffer_size())?;
    let n = w as usize * h as usize;
    let rgba: Vec<u8> = match frame.color_type {
        png::ColorType::Rgba => data.to_vec(),
        png::ColorType::Rgb => data
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect(),
        png::ColorType::GrayscaleAlpha => data
            .chunks_exact(2)
            .flat_map(|p| [p[0], p[0], p[0], p[1]])
            .collect(),
        png::ColorType::Grayscale => data.iter().flat_map(|&g| [g, g, g, 255]).collect(),
        png::ColorType::Indexed => return None,
    };
    (rgba.len() == n * 4).then(|| Image {
        name: name.to_string(),
        width: w,
        height: h,
        rgba,
    })
}

/// Decodes a baseline or progressive JPEG file to 8-bit RGBA (zune-jpeg), named `name`. `None` when
/// it is not a JPEG, is damaged, or has a side above [`MAX_DECODED_SIDE`]; a panic inside the decoder
/// on a hostile file is caught and is `None` too.
pub fn decode_jpeg(name: &str, bytes: &[u8]) -> Option<Image> {
    use zune_jpeg::zune_core::bytestream::ZCursor;
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    if !bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        return None;
    }
    let side = MAX_DECODED_SIDE as usize;
    let opts = DecoderOptions::default()
        .set_max_width(side)
        .set_max_height(side)
        .jpeg_set_out_colorspace(ColorSpace::RGBA);
    let decoded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut dec = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), opts);
        let pixels = dec.decode().ok()?;
        let info = dec.info()?;
        Some((info.width, info.height, dec.output_colorspace()?, pixels))
    }))
    .ok()??;
    let (w, h, space, pixels) = decoded;
    let n = usize::from(w) * usize::from(h);
    if w == 0 || h == 0 || space != ColorSpace::RGBA || pixels.len() != n * 4 {
        return None;
    }
    Some(Image {
        name: name.to_string(),
        width: u32::from(w),
        height: u32::from(h),
        rgba: pixels,
    })
}

/// Decodes a PNG or JPEG file (by its first bytes) to RGBA; `None` for anything else.
pub fn decode_image(name: &str, bytes: &[u8]) -> Option<Image> {
    decode_png(name, bytes).or_else(|| decode_jpeg(name, bytes))
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
    fn a_png_decodes_to_its_rgba_and_junk_does_not() {
        let png = encode_png(&image()).unwrap();
        let back = decode_png("x.png", &png).unwrap();
        assert_eq!((back.width, back.height), (2, 1));
        assert_eq!(back.rgba, image().rgba);
        assert_eq!(back.name, "x.png");
        assert!(decode_png("x", b"\x89PNG\r\n\x1a\nbroken").is_none());
        assert!(decode_png("x", &png[..png.len() / 2]).is_none());
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
