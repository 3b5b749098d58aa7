//! `sinew.load` on the Rust side: a file decoded as the runtime holds it ([`AssetHandle`]), its parts
//! as read-only numpy arrays (one copy each, made at load), and sampling and skinning into numpy
//! buffers through `sinew_pipeline::pose` and `sinew_pipeline::bake`, with the GIL released.
//!
//! Nothing here computes a pose or a vertex: it finds the file's asset the way `inspect --pose` and
//! `bake` do (`sinew_cli::commands::bake::load_asset`), copies its arrays out, and hands the caller's
//! buffers to the pipeline. Matrices are written row by row (numpy's `m[row, col]`, translation in
//! column 3); the numbers are the runtime's.

use crate::errors::{InputError, SinewError, UsageError};
use numpy::ndarray::{ArrayD, IxDyn};
use numpy::{
    Element, PyArray1, PyArrayDyn, PyArrayMethods, PyReadonlyArray1, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};
use sinew_cli::cli::{ImportArgs, PositionKeys};
use sinew_core::format::Asset;
use sinew_core::glam::Mat4;
use sinew_core::{Clip, ClipBinding, Lod, Skeleton};
use sinew_pipeline::bake::{self, BakeError};
use sinew_pipeline::pose::{self, PoseTimes, Space};
use std::path::PathBuf;
use std::sync::Arc;

/// A decoded asset, held for sampling and skinning: the file's [`Asset`] with its skeleton and clips
/// shared as the runtime's animator takes them.
#[pyclass(frozen, module = "sinew._sinew")]
pub struct AssetHandle {
    path: String,
    asset: Asset,
    skeleton: Option<Arc<Skeleton>>,
    clips: Vec<Arc<Clip>>,
}

/// Reads `path` (any format sinew reads, or a `.sinew`) as the runtime sees it, as `sinew inspect
/// --pose` and `sinew bake` do: a source file is imported, compiled and read back (with generated
/// LODs when `lods` is true and the source has none). Returns the handle and the parts as a dict of
/// read-only numpy arrays and strings.
#[pyfunction]
#[pyo3(signature = (path, lods=false, ms3d_position_keys=None, gltf_skin=None, allow_missing=false))]
pub fn load<'py>(
    py: Python<'py>,
    path: PathBuf,
    lods: bool,
    ms3d_position_keys: Option<&str>,
    gltf_skin: Option<usize>,
    allow_missing: bool,
) -> PyResult<(AssetHandle, Bound<'py, PyDict>)> {
    let rule = match ms3d_position_keys {
        None | Some("auto") => PositionKeys::Auto,
        Some("viewer") => PositionKeys::Viewer,
        Some("parent") => PositionKeys::Parent,
        Some(other) => {
            return Err(UsageError::new_err(format!(
                "ms3d_position_keys {other:?}: expected \"auto\", \"viewer\" or \"parent\""
            )))
        }
    };
    let import = ImportArgs {
        ms3d_position_keys: rule,
        gltf_skin,
        allow_missing,
    };
    let shown = path.display().to_string();
    let asset = py
        .detach(|| sinew_cli::commands::bake::load_asset(&path, &import, lods))
        .map_err(|e| InputError::new_err(sinew_cli::output::one_line(&e)))?;
    let handle = AssetHandle {
        path: shown,
        skeleton: asset.skeleton.clone().map(Arc::new),
        clips: asset.clips.iter().cloned().map(Arc::new).collect(),
        asset,
    };
    let parts = handle.parts(py)?;
    Ok((handle, parts))
}

impl AssetHandle {
    /// A pipeline error as a Python exception naming the file.
    fn usage(&self, e: impl std::fmt::Display) -> PyErr {
        UsageError::new_err(format!("{}: {e}", self.path))
    }

    fn skeleton(&self) -> PyResult<&Arc<Skeleton>> {
        self.skeleton
            .as_ref()
            .ok_or_else(|| self.usage("the file has no skeleton to pose"))
    }

    fn clip(&self, index: usize) -> PyResult<&Arc<Clip>> {
        self.clips.get(index).ok_or_else(|| {
            self.usage(format!(
                "clip {index} does not exist; the file has {} clips",
                self.clips.len()
            ))
        })
    }

    fn lod(&self, mesh: usize, lod: i64) -> PyResult<&Lod> {
        let m = self.asset.meshes.get(mesh).ok_or_else(|| {
            self.usage(BakeError::NoMesh {
                mesh,
                count: self.asset.meshes.len(),
            })
        })?;
        let last = m.lods.len().saturating_sub(1);
        usize::try_from(lod)
            .ok()
            .and_then(|l| m.lods.get(l))
            .ok_or_else(|| {
                self.usage(format!(
                    "LOD {lod} does not exist; mesh {:?} has LODs 0..={last}",
                    m.name
                ))
            })
    }

    /// Everything the file holds, as a dict of read-only arrays, strings and numbers.
    fn parts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let a = &self.asset;
        let d = PyDict::new(py);
        d.set_item("path", &self.path)?;
        d.set_item(
            "skeleton",
            match &a.skeleton {
                Some(s) => Some(skeleton_parts(py, s)?),
                None => None,
            },
        )?;
        let clips = PyList::empty(py);
        for c in &a.clips {
            clips.append(clip_parts(py, c, a.skeleton.as_ref())?)?;
        }
        d.set_item("clips", clips)?;
        let meshes = PyList::empty(py);
        for (mi, m) in a.meshes.iter().enumerate() {
            let lods = PyList::empty(py);
            for (li, lod) in m.lods.iter().enumerate() {
                let p = lod_parts(py, lod)?;
                let info = a.lod_info(mi, li);
                p.set_item("target_ratio", info.target_ratio)?;
                p.set_item("reached_ratio", info.reached_ratio)?;
                p.set_item("error_model", info.error_model)?;
                let map = a.source_vertex(mi).filter(|_| li == 0);
                match map {
                    Some(map) => {
                        p.set_item(
                            "source_vertex",
                            array(py, map.map.clone(), &[map.map.len()])?,
                        )?;
                        p.set_item("source_vertex_count", map.source_vertex_count)?;
                    }
                    None => {
                        p.set_item("source_vertex", py.None())?;
                        p.set_item("source_vertex_count", py.None())?;
                    }
                }
                lods.append(p)?;
            }
            let md = PyDict::new(py);
            md.set_item("name", &m.name)?;
            md.set_item("lods", lods)?;
            meshes.append(md)?;
        }
        d.set_item("meshes", meshes)?;
        let materials = PyList::empty(py);
        for m in &a.materials {
            let md = PyDict::new(py);
            md.set_item("name", &m.name)?;
            md.set_item("base_color", array(py, m.base_color.to_vec(), &[4])?)?;
            md.set_item("texture", m.texture.as_deref())?;
            materials.append(md)?;
        }
        d.set_item("materials", materials)?;
        let masks = PyList::empty(py);
        for m in &a.masks {
            let md = PyDict::new(py);
            md.set_item("name", &m.name)?;
            md.set_item(
                "joints",
                PyTuple::new(py, m.weights.iter().map(|(j, _)| j.as_str()))?,
            )?;
            let w: Vec<f32> = m.weights.iter().map(|&(_, w)| w).collect();
            md.set_item("weights", array(py, w, &[m.weights.len()])?)?;
            let per_joint = a
                .skeleton
                .as_ref()
                .map(|s| m.per_joint(s))
                .unwrap_or_default();
            let n = per_joint.len();
            md.set_item("per_joint", array(py, per_joint, &[n])?)?;
            masks.append(md)?;
        }
        d.set_item("masks", masks)?;
        let game = match sinew_cli::report::game::game_report(&a.game) {
            Some(g) => Some(
                serde_json::to_string(&g)
                    .map_err(|e| SinewError::new_err(format!("{}: game data: {e}", self.path)))?,
            ),
            None => None,
        };
        d.set_item("game", game)?;
        Ok(d)
    }

    /// Checks a caller's output array: float32, exactly `shape`, C-contiguous, writeable.
    fn out_array<'a, 'py>(
        &self,
        out: &'a Bound<'py, PyAny>,
        shape: &[usize],
    ) -> PyResult<&'a Bound<'py, PyArrayDyn<f32>>> {
        let arr = out.cast::<PyArrayDyn<f32>>().map_err(|_| {
            UsageError::new_err(format!(
                "out must be a float32 numpy array of shape {shape:?}"
            ))
        })?;
        if arr.shape() != shape {
            return Err(UsageError::new_err(format!(
                "out has shape {:?}; {shape:?} is needed",
                arr.shape()
            )));
        }
        if !arr.is_c_contiguous() {
            return Err(UsageError::new_err("out must be C-contiguous"));
        }
        Ok(arr)
    }

    /// The times as a slice, checked against the clip unless `wrap`.
    fn check_times(&self, clip: &Clip, times: &[f32], wrap: bool) -> PyResult<()> {
        let r = if wrap {
            match times.iter().position(|t| !t.is_finite()) {
                Some(index) => Err(BakeError::NonFiniteTime {
                    index,
                    time: times[index],
                }),
                None => Ok(()),
            }
        } else {
            pose::check_times(clip, times)
        };
        r.map_err(|e| self.usage(e))
    }
}

#[pymethods]
impl AssetHandle {
    /// The index of a clip given by name (str) or index (int).
    fn clip_index(&self, clip: &Bound<'_, PyAny>) -> PyResult<usize> {
        if let Ok(name) = clip.extract::<String>() {
            return pose::find_clip(&self.asset, &name).map_err(|e| self.usage(e));
        }
        let index: i64 = clip
            .extract()
            .map_err(|_| UsageError::new_err("clip must be a name (str) or an index (int)"))?;
        usize::try_from(index)
            .ok()
            .filter(|&i| i < self.clips.len())
            .ok_or_else(|| {
                self.usage(format!(
                    "clip {index} does not exist; the file has {} clips",
                    self.clips.len()
                ))
            })
    }

    /// The index of a mesh given by name (str) or index (int).
    fn mesh_index(&self, mesh: &Bound<'_, PyAny>) -> PyResult<usize> {
        let meshes = &self.asset.meshes;
        if let Ok(name) = mesh.extract::<String>() {
            return meshes.iter().position(|m| m.name == name).ok_or_else(|| {
                let names: Vec<&str> = meshes.iter().map(|m| m.name.as_str()).collect();
                self.usage(format!(
                    "no mesh {name:?}; the file has: {}",
                    if names.is_empty() {
                        "(none)".to_string()
                    } else {
                        names.join(", ")
                    }
                ))
            });
        }
        let index: i64 = mesh
            .extract()
            .map_err(|_| UsageError::new_err("mesh must be a name (str) or an index (int)"))?;
        usize::try_from(index)
            .ok()
            .filter(|&i| i < meshes.len())
            .ok_or_else(|| {
                self.usage(BakeError::NoMesh {
                    mesh: usize::try_from(index).unwrap_or(usize::MAX),
                    count: meshes.len(),
                })
            })
    }

    /// Joints of the skeleton (an error when there is none).
    fn joint_count(&self) -> PyResult<usize> {
        Ok(self.skeleton()?.len())
    }

    /// Vertices of LOD `lod` of mesh `mesh`, checked to be skinned.
    fn skinned_vertex_count(&self, mesh: usize, lod: i64) -> PyResult<usize> {
        let l = self.lod(mesh, lod)?;
        if !l.is_skinned() {
            return Err(self.usage(BakeError::NotSkinned(self.asset.meshes[mesh].name.clone())));
        }
        Ok(l.vertex_count())
    }

    /// The frame times `sinew bake` and `inspect --pose CLIP@0..DURATION` use for clip `clip` at
    /// `fps` (default: the clip's rate), seconds.
    #[pyo3(signature = (clip, fps=None))]
    fn frame_times<'py>(
        &self,
        py: Python<'py>,
        clip: usize,
        fps: Option<f32>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let c = self.clip(clip)?;
        let range = PoseTimes::Range {
            start: 0.0,
            end: c.duration(),
            fps,
        };
        let (times, _) = pose::times(c, range).map_err(|e| self.usage(e))?;
        let arr = PyArray1::from_vec(py, times);
        readonly(arr.as_any())?;
        Ok(arr)
    }

    /// Poses clip `clip` at `times` into `out` (float32, `(T, J, 4, 4)`): model-space or local
    /// matrices, row by row.
    fn sample_into(
        &self,
        py: Python<'_>,
        clip: usize,
        times: PyReadonlyArray1<'_, f32>,
        local: bool,
        wrap: bool,
        out: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let skeleton = self.skeleton()?.clone();
        let c = self.clip(clip)?.clone();
        let times = times
            .as_slice()
            .map_err(|_| UsageError::new_err("times must be contiguous"))?;
        let out = self.out_array(out, &[times.len(), skeleton.len(), 4, 4])?;
        let mut out = out.try_readwrite().map_err(not_writeable)?;
        let out = out.as_slice_mut().map_err(not_writeable)?;
        self.check_times(&c, times, wrap)?;
        let space = if local { Space::Local } else { Space::Model };
        py.detach(|| pose::matrices_into(&skeleton, &c, times, space, out))
            .map_err(|e| self.usage(e))
    }

    /// Poses clip `clip` at `times` into translations `(T, J, 3)`, rotations `(T, J, 4)` (x, y, z, w)
    /// and scales `(T, J, 3)`, all float32.
    #[allow(clippy::too_many_arguments)]
    fn sample_trs_into(
        &self,
        py: Python<'_>,
        clip: usize,
        times: PyReadonlyArray1<'_, f32>,
        local: bool,
        wrap: bool,
        translations: &Bound<'_, PyAny>,
        rotations: &Bound<'_, PyAny>,
        scales: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let skeleton = self.skeleton()?.clone();
        let c = self.clip(clip)?.clone();
        let times = times
            .as_slice()
            .map_err(|_| UsageError::new_err("times must be contiguous"))?;
        let (t, j) = (times.len(), skeleton.len());
        let tr = self.out_array(translations, &[t, j, 3])?;
        let ro = self.out_array(rotations, &[t, j, 4])?;
        let sc = self.out_array(scales, &[t, j, 3])?;
        let (mut tr, mut ro, mut sc) = (
            tr.try_readwrite().map_err(not_writeable)?,
            ro.try_readwrite().map_err(not_writeable)?,
            sc.try_readwrite().map_err(not_writeable)?,
        );
        let tr = tr.as_slice_mut().map_err(not_writeable)?;
        let ro = ro.as_slice_mut().map_err(not_writeable)?;
        let sc = sc.as_slice_mut().map_err(not_writeable)?;
        self.check_times(&c, times, wrap)?;
        let space = if local { Space::Local } else { Space::Model };
        py.detach(|| pose::trs_into(&skeleton, &c, times, space, tr, ro, sc))
            .map_err(|e| self.usage(e))
    }

    /// Skins LOD `lod` of mesh `mesh` through clip `clip` at `times` into `out` (float32, `(T, V,
    /// 3)`), the LOD's own vertex order.
    #[allow(clippy::too_many_arguments)]
    fn skin_into(
        &self,
        py: Python<'_>,
        clip: usize,
        times: PyReadonlyArray1<'_, f32>,
        mesh: usize,
        lod: i64,
        wrap: bool,
        out: &Bound<'_, PyAny>,
    ) -> PyResult<()> {
        let skeleton = self.skeleton()?.clone();
        let c = self.clip(clip)?.clone();
        let nv = self.skinned_vertex_count(mesh, lod)?;
        let lod = usize::try_from(lod).map_err(|_| self.usage(format!("LOD {lod}")))?;
        let times = times
            .as_slice()
            .map_err(|_| UsageError::new_err("times must be contiguous"))?;
        let out = self.out_array(out, &[times.len(), nv, 3])?;
        let mut out = out.try_readwrite().map_err(not_writeable)?;
        let out = out.as_slice_mut().map_err(not_writeable)?;
        self.check_times(&c, times, wrap)?;
        let m = &self.asset.meshes[mesh];
        py.detach(|| bake::skin_into(&skeleton, &c, m, lod, times, out))
            .map_err(|e| self.usage(e))
    }
}

fn not_writeable(e: impl std::fmt::Display) -> PyErr {
    UsageError::new_err(format!("out must be a writeable, C-contiguous array ({e})"))
}

/// Marks an array read-only (`setflags(write=False)`).
fn readonly(a: &Bound<'_, PyAny>) -> PyResult<()> {
    let kw = PyDict::new(a.py());
    kw.set_item("write", false)?;
    a.call_method("setflags", (), Some(&kw))?;
    Ok(())
}

/// A read-only numpy array of `shape` that takes over `data` (no further copy).
fn array<'py, T: Element>(
    py: Python<'py>,
    data: Vec<T>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    let a = ArrayD::from_shape_vec(IxDyn(shape), data)
        .map_err(|e| SinewError::new_err(format!("array of shape {shape:?}: {e}")))?;
    let arr = PyArrayDyn::from_owned_array(py, a).into_any();
    readonly(&arr)?;
    Ok(arr)
}

/// Matrices as row-by-row floats (numpy's `m[row, col]`).
fn rows(m: &[Mat4]) -> Vec<f32> {
    m.iter()
        .flat_map(|m| m.transpose().to_cols_array())
        .collect()
}

fn skeleton_parts<'py>(py: Python<'py>, s: &Skeleton) -> PyResult<Bound<'py, PyDict>> {
    let n = s.len();
    let d = PyDict::new(py);
    d.set_item("names", PyTuple::new(py, s.names())?)?;
    let parents: Vec<i32> = s
        .parents()
        .iter()
        .map(|p| p.map_or(-1, i32::from))
        .collect();
    d.set_item("parents", array(py, parents, &[n])?)?;
    let b = s.bind_local();
    let t: Vec<f32> = b.iter().flat_map(|t| t.translation.to_array()).collect();
    let r: Vec<f32> = b.iter().flat_map(|t| t.rotation.to_array()).collect();
    let sc: Vec<f32> = b.iter().flat_map(|t| t.scale.to_array()).collect();
    d.set_item("bind_translations", array(py, t, &[n, 3])?)?;
    d.set_item("bind_rotations", array(py, r, &[n, 4])?)?;
    d.set_item("bind_scales", array(py, sc, &[n, 3])?)?;
    let locals: Vec<Mat4> = b.iter().map(|t| t.to_mat4()).collect();
    d.set_item("bind_local", array(py, rows(&locals), &[n, 4, 4])?)?;
    let mut models = vec![Mat4::IDENTITY; n];
    sinew_core::local_to_model(s.parents(), b, &mut models)
        .map_err(|e| SinewError::new_err(format!("bind pose: {e}")))?;
    d.set_item("bind_model", array(py, rows(&models), &[n, 4, 4])?)?;
    d.set_item(
        "inverse_bind",
        array(py, rows(s.inverse_bind()), &[n, 4, 4])?,
    )?;
    Ok(d)
}

fn clip_parts<'py>(
    py: Python<'py>,
    c: &Clip,
    skeleton: Option<&Skeleton>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", c.name())?;
    d.set_item("duration", c.duration())?;
    d.set_item("sample_rate", c.sample_rate())?;
    d.set_item("looping", c.looping())?;
    d.set_item("additive", c.additive())?;
    d.set_item("compressed", c.is_compressed())?;
    d.set_item(
        "tracks",
        PyTuple::new(py, c.tracks().iter().map(|t| t.joint.as_str()))?,
    )?;
    let (driven, unbound): (Vec<i32>, Vec<String>) = match skeleton {
        Some(s) => {
            let b = ClipBinding::new(c, s);
            (
                b.driven().iter().map(|&j| i32::from(j)).collect(),
                b.unmatched().to_vec(),
            )
        }
        None => (
            Vec::new(),
            c.tracks().iter().map(|t| t.joint.clone()).collect(),
        ),
    };
    let n = driven.len();
    d.set_item("driven", array(py, driven, &[n])?)?;
    d.set_item("unbound", PyTuple::new(py, unbound)?)?;
    d.set_item("times", array(py, c.times().to_vec(), &[c.times().len()])?)?;
    Ok(d)
}

fn lod_parts<'py>(py: Python<'py>, l: &Lod) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let flat3 = |v: &[sinew_core::glam::Vec3]| -> Vec<f32> {
        v.iter().flat_map(|p| p.to_array()).collect()
    };
    d.set_item(
        "positions",
        array(py, flat3(&l.positions), &[l.positions.len(), 3])?,
    )?;
    d.set_item(
        "normals",
        array(py, flat3(&l.normals), &[l.normals.len(), 3])?,
    )?;
    let uvs: Vec<f32> = l.uvs.iter().flat_map(|p| p.to_array()).collect();
    d.set_item("uvs", array(py, uvs, &[l.uvs.len(), 2])?)?;
    d.set_item(
        "indices",
        array(py, l.indices.clone(), &[l.indices.len() / 3, 3])?,
    )?;
    let joints: Vec<u16> = l.joints.iter().flatten().copied().collect();
    d.set_item("joint_indices", array(py, joints, &[l.joints.len(), 4])?)?;
    let weights: Vec<f32> = l.weights.iter().flatten().copied().collect();
    d.set_item("joint_weights", array(py, weights, &[l.weights.len(), 4])?)?;
    let ranges: Vec<u32> = l
        .submeshes
        .iter()
        .flat_map(|s| [s.first_index, s.index_count])
        .collect();
    d.set_item("submeshes", array(py, ranges, &[l.submeshes.len(), 2])?)?;
    d.set_item(
        "materials",
        PyTuple::new(py, l.submeshes.iter().map(|s| s.material.as_str()))?,
    )?;
    d.set_item("error", l.error)?;
    Ok(d)
}

/// Adds the functions and classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_class::<AssetHandle>()?;
    Ok(())
}
