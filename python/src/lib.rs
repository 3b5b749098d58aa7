//! `sinew._sinew`, the extension module of the `sinew` Python package: the command line's functions
//! (through `sinew_cli::run_captured`, so options, checks, outputs and reports are the CLI's own), an
//! in-memory bake, the PC2/MDD cache writers, and a decoded asset as numpy arrays that samples and
//! skins into numpy buffers ([`asset`]). The GIL is released while sinew works. The Python package
//! (`python/sinew/`) turns arguments and results into Python data.

mod asset;
mod errors;

use errors::{InputError, SinewError, UsageError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use sinew_core::glam::Vec3;
use sinew_pipeline::bake::{BakeRequest, VertexOrder};
use sinew_pipeline::cache::Frames;

/// Runs a `sinew` command (arguments without the program name) as the binary would with `--json`:
/// returns `(exit code, JSON report or None, one-line error or None, whether the arguments were
/// refused)`.
#[pyfunction]
fn run(py: Python<'_>, argv: Vec<String>) -> (u8, Option<String>, Option<String>, bool) {
    let c = py.detach(move || sinew_cli::run_captured(argv));
    (c.code, c.json, c.error, c.usage)
}

/// Skins a mesh through clips with sinew-core, in memory: returns `(positions, frames, vertices, fps,
/// clips)`, positions as little-endian f32 bytes, frame-major (`frames x vertices x 3`), and the clip
/// ranges as JSON (`[{name, first_frame, frame_count, looping, duration}]`).
#[pyfunction]
#[pyo3(signature = (path, clips=Vec::new(), fps=None, mesh=None, lod=0))]
fn bake<'py>(
    py: Python<'py>,
    path: String,
    clips: Vec<String>,
    fps: Option<f32>,
    mesh: Option<usize>,
    lod: usize,
) -> PyResult<(Bound<'py, PyBytes>, usize, usize, f32, String)> {
    let result = py.detach(
        move || -> anyhow::Result<(Vec<u8>, usize, usize, f32, String)> {
            let file = std::path::PathBuf::from(&path);
            let asset = sinew_cli::commands::bake::load_asset(&file, &Default::default(), lod > 0)?;
            let request = BakeRequest {
                clips,
                fps,
                meshes: mesh.into_iter().collect(),
                lod,
                vertex_order: VertexOrder::Split,
                ..BakeRequest::default()
            };
            let baked = sinew_pipeline::bake::bake(&asset, &request)
                .map_err(|e| anyhow::anyhow!("{path}: {e}"))?;
            let f = &baked.frames;
            let mut bytes = Vec::with_capacity(f.positions.len() * 12);
            for p in &f.positions {
                for c in p.to_array() {
                    bytes.extend_from_slice(&c.to_le_bytes());
                }
            }
            let clips = serde_json::to_string(&baked.clips)?;
            Ok((bytes, f.frame_count, f.vertex_count, f.fps, clips))
        },
    );
    match result {
        Ok((bytes, frames, vertices, fps, clips)) => {
            Ok((PyBytes::new(py, &bytes), frames, vertices, fps, clips))
        }
        Err(e) => Err(InputError::new_err(sinew_cli::output::one_line(&e))),
    }
}

/// Writes a PC2 or MDD cache atomically from little-endian f32 positions (`frames x vertices x 3`).
#[pyfunction]
fn write_cache(
    py: Python<'_>,
    path: String,
    format: String,
    positions: Vec<u8>,
    frames: usize,
    vertices: usize,
    fps: f32,
) -> PyResult<()> {
    let result = py.detach(move || -> anyhow::Result<()> {
        let need = frames
            .checked_mul(vertices)
            .and_then(|n| n.checked_mul(12))
            .ok_or_else(|| anyhow::anyhow!("{path}: {frames} x {vertices} is too large"))?;
        if positions.len() != need {
            anyhow::bail!(
                "{path}: {} bytes of positions for {frames} frames x {vertices} vertices (need {need})",
                positions.len()
            );
        }
        if !(fps.is_finite() && fps > 0.0) {
            anyhow::bail!("{path}: fps must be a positive number");
        }
        let points: Vec<Vec3> = positions
            .chunks_exact(12)
            .map(|c| {
                let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
                Vec3::new(f(0), f(4), f(8))
            })
            .collect();
        let data = Frames {
            vertex_count: vertices,
            frame_count: frames,
            fps,
            positions: points,
            normals: Vec::new(),
        };
        let bytes = match format.as_str() {
            "pc2" => sinew_pipeline::cache::pc2::write(&data),
            "mdd" => sinew_pipeline::cache::mdd::write(&data),
            other => anyhow::bail!("{path}: cache format {other:?} (expected pc2 or mdd)"),
        };
        sinew_cli::output::write_atomic(std::path::Path::new(&path), &bytes)
    });
    result.map_err(|e| InputError::new_err(sinew_cli::output::one_line(&e)))
}

/// The module.
#[pymodule]
fn _sinew(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(bake, m)?)?;
    m.add_function(wrap_pyfunction!(write_cache, m)?)?;
    asset::register(m)?;
    m.add("SinewError", m.py().get_type::<SinewError>())?;
    m.add("InputError", m.py().get_type::<InputError>())?;
    m.add("UsageError", m.py().get_type::<UsageError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
