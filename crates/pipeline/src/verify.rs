//! Encoding a [`Baked`] result as cache files with their JSON sidecar, and verifying a cache against
//! a fresh bake through sinew-core (layout and sidecar fields: docs/formats/vat.md).
//!
//! Verification recomputes every frame with the parameters the sidecar records, encodes the result the
//! way the cache stores it (f32 as is; f16 by `half::f16::from_f32`; offsets as `p - bind` in f32
//! first), and compares the stored bits exactly: no tolerance.

use crate::bake::{bake, BakeError, BakeRequest, Baked, ClipRange, LayerSpec, VertexOrder};
use crate::cache::vat::{self, VatEncoding, VatImage, VatLayout};
use crate::cache::{mdd, pc2, CacheError};
use half::f16;
use sinew_core::format::Asset;
use sinew_core::glam::Vec3;
use std::path::{Path, PathBuf};

/// Cache file formats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CacheFormat {
    /// OpenEXR vertex animation texture.
    Exr,
    /// PC2 point cache (little-endian).
    Pc2,
    /// MDD point cache (big-endian).
    Mdd,
}

/// Where EXR normals go.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NormalsPlacement {
    /// A layer `N` in the position file (positions are layer `P`).
    Layer,
    /// A second file `<stem>_normals.exr` (one unnamed layer).
    File,
    /// Not written.
    None,
}

/// How to encode a bake.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CacheOptions {
    /// File format.
    pub format: CacheFormat,
    /// EXR: largest texture width.
    pub max_width: usize,
    /// EXR: position encoding.
    pub encoding: VatEncoding,
    /// EXR: normals placement.
    pub normals: NormalsPlacement,
}

impl Default for CacheOptions {
    fn default() -> Self {
        Self {
            format: CacheFormat::Exr,
            max_width: 4096,
            encoding: VatEncoding::OffsetF16,
            normals: NormalsPlacement::File,
        }
    }
}

/// OpenVAT's remap box: bounds of the stored position values and the frame count.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OsRemap {
    /// Per-axis minimum of the stored values.
    #[serde(rename = "Min")]
    pub min: [f32; 3],
    /// Per-axis maximum of the stored values.
    #[serde(rename = "Max")]
    pub max: [f32; 3],
    /// Number of frames.
    #[serde(rename = "Frames")]
    pub frames: usize,
}

/// One clip in OpenVAT's `animations` form (frames inclusive).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Animation {
    /// Clip name.
    pub name: String,
    /// First frame.
    #[serde(rename = "startFrame")]
    pub start_frame: usize,
    /// Last frame (inclusive).
    #[serde(rename = "endFrame")]
    pub end_frame: usize,
    /// Frames per second.
    pub framerate: f32,
}

/// The JSON sidecar written next to every cache; it holds what verify needs to bake again.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sidecar {
    /// Always `"sinew"`.
    pub generator: String,
    /// Cache format.
    pub format: CacheFormat,
    /// File name of the baked input.
    pub source: String,
    /// The first mesh baked (kept for readers of sidecars before `meshes`).
    pub mesh: usize,
    /// The names of the meshes baked, joined with ` + `.
    pub mesh_name: String,
    /// Every mesh baked, in cache order (their vertices one after another). Absent in sidecars
    /// written before it: `[mesh]`.
    #[serde(default)]
    pub meshes: Vec<usize>,
    /// Their names.
    #[serde(default)]
    pub mesh_names: Vec<String>,
    /// LOD index.
    pub lod: usize,
    /// Vertex order.
    pub vertex_order: VertexOrder,
    /// Vertices per frame.
    pub vertex_count: usize,
    /// Frames in the cache.
    pub frame_count: usize,
    /// Frames per second.
    pub fps: f32,
    /// Clips baked (empty for a layered bake).
    pub requested_clips: Vec<String>,
    /// Layers of a layered bake (empty otherwise).
    pub layers: Vec<LayerSpec>,
    /// Frame ranges.
    pub clips: Vec<ClipRange>,
    /// The same ranges in OpenVAT's form.
    pub animations: Vec<Animation>,
    /// Bounds of the stored position values (offsets or absolute positions).
    #[serde(rename = "os-remap")]
    pub os_remap: OsRemap,
    /// EXR: texture layout.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub layout: Option<VatLayout>,
    /// EXR: position encoding.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub encoding: Option<VatEncoding>,
    /// EXR: normals placement.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normals: Option<NormalsPlacement>,
    /// EXR: file name of the normals texture when `normals` is `file`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normals_file: Option<String>,
}

impl Sidecar {
    /// The bake request this sidecar records.
    pub fn request(&self) -> BakeRequest {
        BakeRequest {
            clips: self.requested_clips.clone(),
            layers: self.layers.clone(),
            fps: Some(self.fps),
            meshes: if self.meshes.is_empty() {
                vec![self.mesh]
            } else {
                self.meshes.clone()
            },
            lod: self.lod,
            vertex_order: self.vertex_order,
        }
    }
}

/// The files one bake produces, by path.
#[derive(Debug, Clone, PartialEq)]
pub struct CachePaths {
    /// The cache itself.
    pub cache: PathBuf,
    /// The JSON sidecar: `<stem>-remap_info.json` for EXR, `<out>.json` otherwise.
    pub sidecar: PathBuf,
    /// The normals texture (EXR with `file` normals): `<stem>_normals.exr`.
    pub normals: PathBuf,
    /// The mesh: `<out>.obj`.
    pub obj: PathBuf,
}

/// The paths that belong with cache file `out`.
pub fn cache_paths(out: &Path, format: CacheFormat) -> CachePaths {
    let stem = out.with_extension("");
    let with = |suffix: &str| {
        let mut s = stem.clone().into_os_string();
        s.push(suffix);
        PathBuf::from(s)
    };
    let append = |suffix: &str| {
        let mut s = out.as_os_str().to_owned();
        s.push(suffix);
        PathBuf::from(s)
    };
    CachePaths {
        cache: out.to_path_buf(),
        sidecar: match format {
            CacheFormat::Exr => with("-remap_info.json"),
            _ => append(".json"),
        },
        normals: with("_normals.exr"),
        obj: append(".obj"),
    }
}

/// Encoded cache bytes, ready to be written.
#[derive(Debug, Clone, PartialEq)]
pub struct Encoded {
    /// The cache file.
    pub cache: Vec<u8>,
    /// The normals file (EXR, `file` placement, LOD with normals).
    pub normals: Option<Vec<u8>>,
    /// The sidecar.
    pub sidecar: Sidecar,
}

/// Position values as the cache stores them, widened back to f32 (f16 values are exact in f32).
pub fn stored_positions(baked: &Baked, opts: &CacheOptions) -> Vec<Vec3> {
    let f = &baked.frames;
    if opts.format != CacheFormat::Exr || !opts.encoding.is_offset() {
        return f.positions.clone();
    }
    let n = f.vertex_count.max(1);
    f.positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let d = *p - baked.bind_positions.get(i % n).copied().unwrap_or_default();
            if opts.encoding.is_half() {
                halve(d)
            } else {
                d
            }
        })
        .collect()
}

/// Normal values as the EXR stores them (f16 when the positions are f16).
pub fn stored_normals(baked: &Baked, opts: &CacheOptions) -> Vec<Vec3> {
    if opts.encoding.is_half() {
        baked.frames.normals.iter().map(|&n| halve(n)).collect()
    } else {
        baked.frames.normals.clone()
    }
}

fn halve(v: Vec3) -> Vec3 {
    Vec3::from_array(v.to_array().map(|c| f16::from_f32(c).to_f32()))
}

fn bounds(values: &[Vec3]) -> ([f32; 3], [f32; 3]) {
    if values.is_empty() {
        return ([0.0; 3], [0.0; 3]);
    }
    let (lo, hi) = values
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        });
    (lo.to_array(), hi.to_array())
}

/// Encodes a bake as cache bytes plus sidecar. `request` is what was baked; `source` names the input.
pub fn encode(
    baked: &Baked,
    request: &BakeRequest,
    opts: &CacheOptions,
    source: &str,
    normals_file_name: &str,
) -> Result<Encoded, String> {
    let f = &baked.frames;
    let stored = stored_positions(baked, opts);
    let (min, max) = bounds(&stored);
    let mut sidecar = Sidecar {
        generator: "sinew".into(),
        format: opts.format,
        source: source.into(),
        mesh: baked.meshes.first().copied().unwrap_or(0),
        mesh_name: baked.mesh_name.clone(),
        meshes: baked.meshes.clone(),
        mesh_names: baked.mesh_names.clone(),
        lod: request.lod,
        vertex_order: request.vertex_order,
        vertex_count: f.vertex_count,
        frame_count: f.frame_count,
        fps: f.fps,
        requested_clips: request.clips.clone(),
        layers: request.layers.clone(),
        clips: baked.clips.clone(),
        animations: baked
            .clips
            .iter()
            .map(|c| Animation {
                name: c.name.clone(),
                start_frame: c.first_frame,
                end_frame: c.first_frame + c.frame_count.saturating_sub(1),
                framerate: f.fps,
            })
            .collect(),
        os_remap: OsRemap {
            min,
            max,
            frames: f.frame_count,
        },
        layout: None,
        encoding: None,
        normals: None,
        normals_file: None,
    };
    let (cache, normals) = match opts.format {
        CacheFormat::Pc2 => (pc2::write(f), None),
        CacheFormat::Mdd => (mdd::write(f), None),
        CacheFormat::Exr => {
            let lay = vat::layout(f.vertex_count, f.frame_count, opts.max_width)?;
            let placement = if f.normals.is_empty() {
                NormalsPlacement::None
            } else {
                opts.normals
            };
            let half = opts.encoding.is_half();
            let nvals = stored_normals(baked, opts);
            let p = VatImage {
                layer: "P",
                values: &stored,
                half,
            };
            let n = VatImage {
                layer: "N",
                values: &nvals,
                half,
            };
            let (cache, normals) = match placement {
                NormalsPlacement::Layer => (vat::write_exr(&[p, n], f.vertex_count, &lay)?, None),
                NormalsPlacement::File => (
                    vat::write_exr(&[p], f.vertex_count, &lay)?,
                    Some(vat::write_exr(&[n], f.vertex_count, &lay)?),
                ),
                NormalsPlacement::None => (vat::write_exr(&[p], f.vertex_count, &lay)?, None),
            };
            sidecar.layout = Some(lay);
            sidecar.encoding = Some(opts.encoding);
            sidecar.normals = Some(placement);
            if placement == NormalsPlacement::File {
                sidecar.normals_file = Some(normals_file_name.into());
            }
            (cache, normals)
        }
    };
    Ok(Encoded {
        cache,
        normals,
        sidecar,
    })
}

/// The first difference verification found.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Mismatch {
    /// `position` or `normal`.
    pub what: &'static str,
    /// Frame index.
    pub frame: usize,
    /// Vertex index (in the cache's vertex order).
    pub vertex: usize,
    /// Value the runtime gives, encoded as the cache stores it.
    pub expected: [f32; 3],
    /// Value in the cache.
    pub found: [f32; 3],
}

/// The outcome of a verification that could read everything.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct VerifyReport {
    /// Frames compared.
    pub frames: usize,
    /// Vertices per frame.
    pub vertices: usize,
    /// Vectors (positions and normals) compared.
    pub compared: usize,
    /// Vectors whose bits differ.
    pub mismatches: usize,
    /// The first mismatch (lowest frame, then vertex; positions before normals).
    pub first: Option<Mismatch>,
}

impl VerifyReport {
    /// True when every stored value equals the runtime's.
    pub fn identical(&self) -> bool {
        self.mismatches == 0
    }
}

/// Why a cache could not be verified at all (unreadable, truncated, or not matching the mesh).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VerifyError {
    /// The cache bytes are not a readable cache.
    #[error(transparent)]
    Cache(#[from] CacheError),
    /// The cache's shape differs from the sidecar or the mesh.
    #[error("{0}")]
    Shape(String),
    /// The bake recorded in the sidecar cannot be repeated on this file.
    #[error("re-baking: {0}")]
    Bake(#[from] BakeError),
}

/// The cache contents as read back.
struct ReadBack {
    vertex_count: usize,
    frame_count: usize,
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
}

fn read_cache(
    sidecar: &Sidecar,
    cache: &[u8],
    normals: Option<&[u8]>,
) -> Result<ReadBack, VerifyError> {
    match sidecar.format {
        CacheFormat::Pc2 => {
            let (_, f) = pc2::read(cache)?;
            Ok(ReadBack {
                vertex_count: f.vertex_count,
                frame_count: f.frame_count,
                positions: f.positions,
                normals: None,
            })
        }
        CacheFormat::Mdd => {
            let (_, f) = mdd::read(cache)?;
            Ok(ReadBack {
                vertex_count: f.vertex_count,
                frame_count: f.frame_count,
                positions: f.positions,
                normals: None,
            })
        }
        CacheFormat::Exr => {
            let lay = sidecar
                .layout
                .ok_or_else(|| VerifyError::Shape("the sidecar has no EXR layout".into()))?;
            let (vc, fc) = (sidecar.vertex_count, sidecar.frame_count);
            let expected_lay = vat::layout(vc, fc, lay.width.max(1)).map_err(VerifyError::Shape)?;
            if expected_lay != lay {
                return Err(VerifyError::Shape(format!(
                    "sidecar layout {}x{} ({} rows per frame) does not fit {vc} vertices x {fc} frames",
                    lay.width, lay.height, lay.rows_per_frame
                )));
            }
            let layers = vat::read_exr(cache)?;
            let pick = |layers: &[vat::ReadLayer], name: &str| {
                layers
                    .iter()
                    .find(|l| l.name.as_deref() == Some(name))
                    .or_else(|| layers.first().filter(|_| layers.len() == 1))
                    .cloned()
                    .ok_or_else(|| {
                        VerifyError::Cache(crate::cache::cache_error(
                            "exr",
                            "layers",
                            0,
                            format!("no layer {name}"),
                        ))
                    })
            };
            let p = pick(&layers, "P")?;
            let half = sidecar.encoding.is_some_and(VatEncoding::is_half);
            if p.half != half {
                return Err(VerifyError::Shape(format!(
                    "the texture stores {} samples; the sidecar says {}",
                    if p.half { "f16" } else { "f32" },
                    if half { "f16" } else { "f32" }
                )));
            }
            let positions = vat::unpack(&p, vc, fc, &lay)?;
            let normals = match sidecar.normals {
                Some(NormalsPlacement::Layer) => {
                    Some(vat::unpack(&pick(&layers, "N")?, vc, fc, &lay)?)
                }
                Some(NormalsPlacement::File) => {
                    let bytes = normals
                        .ok_or_else(|| VerifyError::Shape("the normals file is missing".into()))?;
                    let layers = vat::read_exr(bytes)?;
                    Some(vat::unpack(&pick(&layers, "N")?, vc, fc, &lay)?)
                }
                _ => None,
            };
            Ok(ReadBack {
                vertex_count: vc,
                frame_count: fc,
                positions,
                normals,
            })
        }
    }
}

/// Verifies cache bytes (and the normals file, for EXR with `file` normals) against a fresh bake of
/// `asset` with the sidecar's parameters. `Ok` with mismatches means the cache differs (exit 1);
/// `Err` means it could not be compared (exit 2).
pub fn verify(
    asset: &Asset,
    sidecar: &Sidecar,
    cache: &[u8],
    normals: Option<&[u8]>,
) -> Result<VerifyReport, VerifyError> {
    let read = read_cache(sidecar, cache, normals)?;
    if read.vertex_count != sidecar.vertex_count || read.frame_count != sidecar.frame_count {
        return Err(VerifyError::Shape(format!(
            "the cache holds {} vertices x {} frames; its sidecar says {} x {}",
            read.vertex_count, read.frame_count, sidecar.vertex_count, sidecar.frame_count
        )));
    }
    let request = sidecar.request();
    let baked = bake(asset, &request)?;
    if baked.frames.vertex_count != read.vertex_count {
        return Err(VerifyError::Shape(format!(
            "the cache has {} vertices; meshes {:?} LOD {} in {} order have {}",
            read.vertex_count,
            request.meshes,
            sidecar.lod,
            match sidecar.vertex_order {
                VertexOrder::Split => "split",
                VertexOrder::Source => "source",
            },
            baked.frames.vertex_count
        )));
    }
    if baked.frames.frame_count != read.frame_count {
        return Err(VerifyError::Shape(format!(
            "the cache has {} frames; baking the sidecar's clips gives {}",
            read.frame_count, baked.frames.frame_count
        )));
    }
    let opts = CacheOptions {
        format: sidecar.format,
        max_width: sidecar.layout.map_or(4096, |l| l.width),
        encoding: sidecar.encoding.unwrap_or(VatEncoding::AbsoluteF32),
        normals: sidecar.normals.unwrap_or(NormalsPlacement::None),
    };
    let expected_p = stored_positions(&baked, &opts);
    let expected_n = read.normals.as_ref().map(|_| stored_normals(&baked, &opts));
    let mut report = VerifyReport {
        frames: read.frame_count,
        vertices: read.vertex_count,
        compared: 0,
        mismatches: 0,
        first: None,
    };
    let vc = read.vertex_count.max(1);
    let mut check = |what: &'static str, exp: &[Vec3], got: &[Vec3]| {
        for (i, (e, g)) in exp.iter().zip(got).enumerate() {
            report.compared += 1;
            let same = e.to_array().map(f32::to_bits) == g.to_array().map(f32::to_bits);
            if !same {
                report.mismatches += 1;
                let m = Mismatch {
                    what,
                    frame: i / vc,
                    vertex: i % vc,
                    expected: e.to_array(),
                    found: g.to_array(),
                };
                let earlier = report
                    .first
                    .as_ref()
                    .is_none_or(|f| (m.frame, m.vertex) < (f.frame, f.vertex));
                if earlier {
                    report.first = Some(m);
                }
            }
        }
    };
    check("position", &expected_p, &read.positions);
    if let (Some(e), Some(g)) = (&expected_n, &read.normals) {
        if e.len() != g.len() {
            return Err(VerifyError::Shape(format!(
                "the cache has {} normals; the mesh gives {}",
                g.len(),
                e.len()
            )));
        }
        check("normal", e, g);
    }
    Ok(report)
}
