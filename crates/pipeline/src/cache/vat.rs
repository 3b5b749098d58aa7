//! Vertex animation textures in OpenEXR, written and read with the `exr` crate.
//!
//! Layout (docs/formats/vat.md): the texture is `width` pixels wide, `width = min(vertex_count,
//! max_width)`. A frame takes `rows_per_frame = ceil(vertex_count / width)` consecutive rows; vertex `v`
//! of frame `f` is the pixel `x = v % width`, `y = f * rows_per_frame + v / width` (row 0 is the first
//! row of the file, EXR's top). Pixels past the last vertex of a frame are 0. Channels R, G, B hold
//! x, y, z; A is 1.
//!
//! Positions are stored absolute (f32) or as offsets from the bind pose (f16 or f32). Normals go in a
//! layer named `N` of the same file, or in a second file, or nowhere.

use super::{cache_error, CacheError};
use exr::prelude::{
    f16, read, AnyChannel, AnyChannels, Blocks, Compression, Encoding, FlatSamples, Image,
    ImageAttributes, IntegerBounds, Layer, LayerAttributes, LineOrder, ReadChannels, ReadLayers,
    SmallVec, Text, Vec2, WritableImage,
};
use sinew_core::glam::Vec3;

/// How positions are stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum VatEncoding {
    /// Absolute model-space positions, 32-bit float.
    AbsoluteF32,
    /// Offsets from the bind-pose position, 16-bit half float.
    OffsetF16,
    /// Offsets from the bind-pose position, 32-bit float.
    OffsetF32,
}

impl VatEncoding {
    /// True for the offset encodings.
    pub fn is_offset(self) -> bool {
        !matches!(self, VatEncoding::AbsoluteF32)
    }
    /// True when samples are f16.
    pub fn is_half(self) -> bool {
        matches!(self, VatEncoding::OffsetF16)
    }
}

/// Where the texture's pixels go.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct VatLayout {
    /// Texture width in pixels.
    pub width: usize,
    /// Rows one frame occupies.
    pub rows_per_frame: usize,
    /// Texture height: `frame_count * rows_per_frame`.
    pub height: usize,
}

/// Largest texture height sinew writes (EXR itself allows more; engines do not).
pub const MAX_HEIGHT: usize = 1 << 20;

/// The layout for a bake, or why it cannot be made.
pub fn layout(
    vertex_count: usize,
    frame_count: usize,
    max_width: usize,
) -> Result<VatLayout, String> {
    if vertex_count == 0 || frame_count == 0 {
        return Err("nothing to bake: no vertices or no frames".into());
    }
    if max_width == 0 {
        return Err("maximum width must be at least 1".into());
    }
    let width = vertex_count.min(max_width);
    let rows_per_frame = vertex_count.div_ceil(width);
    let height = frame_count
        .checked_mul(rows_per_frame)
        .filter(|&h| h <= MAX_HEIGHT)
        .ok_or_else(|| {
            format!("{frame_count} frames of {rows_per_frame} rows exceed {MAX_HEIGHT} rows")
        })?;
    Ok(VatLayout {
        width,
        rows_per_frame,
        height,
    })
}

/// One RGB(A) image to write: frame-major vectors laid out per [`VatLayout`].
pub struct VatImage<'a> {
    /// EXR layer name (`P` for positions, `N` for normals).
    pub layer: &'a str,
    /// `frame_count * vertex_count` values.
    pub values: &'a [Vec3],
    /// Store as f16 instead of f32.
    pub half: bool,
}

fn channel_samples(
    values: &[Vec3],
    vertex_count: usize,
    lay: &VatLayout,
    axis: usize,
    half: bool,
) -> FlatSamples {
    let pixels = lay.width * lay.height;
    let mut out = vec![0.0f32; pixels];
    for (i, v) in values.iter().enumerate() {
        let (f, vert) = (i / vertex_count, i % vertex_count);
        let y = f * lay.rows_per_frame + vert / lay.width;
        out[y * lay.width + vert % lay.width] = v.to_array()[axis];
    }
    if half {
        FlatSamples::F16(out.into_iter().map(f16::from_f32).collect())
    } else {
        FlatSamples::F32(out)
    }
}

fn alpha(lay: &VatLayout, half: bool) -> FlatSamples {
    let n = lay.width * lay.height;
    if half {
        FlatSamples::F16(vec![f16::ONE; n])
    } else {
        FlatSamples::F32(vec![1.0; n])
    }
}

/// Encodes images as one EXR file (one layer each), losslessly compressed, deterministically.
pub fn write_exr(
    images: &[VatImage<'_>],
    vertex_count: usize,
    lay: &VatLayout,
) -> Result<Vec<u8>, String> {
    let size = Vec2(lay.width, lay.height);
    let mut layers = Vec::new();
    for img in images {
        if img.values.len() != vertex_count * (lay.height / lay.rows_per_frame) {
            return Err(format!(
                "layer {}: {} values do not fill the layout",
                img.layer,
                img.values.len()
            ));
        }
        let channels = AnyChannels::sort(SmallVec::from_vec(vec![
            AnyChannel::new(
                "R",
                channel_samples(img.values, vertex_count, lay, 0, img.half),
            ),
            AnyChannel::new(
                "G",
                channel_samples(img.values, vertex_count, lay, 1, img.half),
            ),
            AnyChannel::new(
                "B",
                channel_samples(img.values, vertex_count, lay, 2, img.half),
            ),
            AnyChannel::new("A", alpha(lay, img.half)),
        ]));
        let mut attributes = LayerAttributes::named(img.layer);
        attributes.software_name = Some(Text::from("sinew"));
        layers.push(Layer::new(
            size,
            attributes,
            Encoding {
                compression: Compression::ZIP16,
                blocks: Blocks::ScanLines,
                line_order: LineOrder::Increasing,
            },
            channels,
        ));
    }
    let image = Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions(size)),
        layers,
    );
    let mut out = std::io::Cursor::new(Vec::new());
    image
        .write()
        .non_parallel()
        .to_buffered(&mut out)
        .map_err(|e| format!("EXR encoding failed: {e}"))?;
    Ok(out.into_inner())
}

/// A layer read back from an EXR file: its name, size and RGB samples as f32 together with whether the
/// file stored them as f16.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadLayer {
    /// Layer name (`None` for a single unnamed layer).
    pub name: Option<String>,
    /// Width and height.
    pub size: (usize, usize),
    /// R, G, B samples (row-major), widened to f32.
    pub rgb: [Vec<f32>; 3],
    /// True when the file stored f16 samples.
    pub half: bool,
}

/// Reads every layer of an EXR file (through the exr crate's reader).
pub fn read_exr(bytes: &[u8]) -> Result<Vec<ReadLayer>, CacheError> {
    super::exr_header::check_declared_size(bytes)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .non_parallel()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| cache_error("exr", "file", 0, e.to_string()))?;
    let mut out = Vec::new();
    for layer in &image.layer_data {
        let mut rgb: [Vec<f32>; 3] = Default::default();
        let mut half = false;
        for (k, name) in ["R", "G", "B"].iter().enumerate() {
            let ch = layer
                .channel_data
                .list
                .iter()
                .find(|c| c.name.to_string() == *name)
                .ok_or_else(|| {
                    cache_error("exr", "channels", 0, format!("layer has no {name} channel"))
                })?;
            half |= matches!(ch.sample_data, FlatSamples::F16(_));
            rgb[k] = ch.sample_data.values_as_f32().collect();
        }
        out.push(ReadLayer {
            name: layer.attributes.layer_name.as_ref().map(|t| t.to_string()),
            size: (layer.size.0, layer.size.1),
            rgb,
            half,
        });
    }
    Ok(out)
}

/// Pulls frame-major vectors back out of a layer laid out per `lay`.
pub fn unpack(
    layer: &ReadLayer,
    vertex_count: usize,
    frame_count: usize,
    lay: &VatLayout,
) -> Result<Vec<Vec3>, CacheError> {
    if layer.size != (lay.width, lay.height) || lay.height != frame_count * lay.rows_per_frame {
        return Err(cache_error(
            "exr",
            "layout",
            0,
            format!(
                "texture is {}x{}; {vertex_count} vertices x {frame_count} frames need {}x{}",
                layer.size.0, layer.size.1, lay.width, lay.height
            ),
        ));
    }
    let mut out = Vec::with_capacity(vertex_count * frame_count);
    for f in 0..frame_count {
        for v in 0..vertex_count {
            let i = (f * lay.rows_per_frame + v / lay.width) * lay.width + v % lay.width;
            out.push(Vec3::new(layer.rgb[0][i], layer.rgb[1][i], layer.rgb[2][i]));
        }
    }
    Ok(out)
}
