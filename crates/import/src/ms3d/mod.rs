//! Importer for Milkshape 3D `.ms3d` files (versions 3 and 4), as Milkshape's own viewer reads them.
//!
//! The byte layout and every decision where loaders disagree are in `docs/formats/ms3d.md`. In short:
//! - the mesh is one [`sinew_scene::Mesh`] named after the file, one submesh per group in file order;
//!   vertices are split where triangles give one file vertex different normals or UVs, and appear in
//!   the order of their first use by the triangle corners (groups in file order, each group's triangle
//!   list in order, corners 0, 1, 2); file vertices no triangle uses are dropped. `source_vertex` maps
//!   each vertex back to the file's vertex index.
//! - UVs are kept as stored (origin at the image's top-left, t down), not flipped.
//! - the joints become the skeleton (bind local = `T(position) * Rz * Ry * Rx`), parents found by name;
//! - the keys become one clip sampled at every Milkshape frame and every key time, evaluating the
//!   viewer's slerp (rotations) and Hermite curves (positions) exactly; clip time 0 is Milkshape
//!   frame 1 (file time `1/fps`);
//! - position keys compose with the bind pose by [`PositionKeyRule`](crate::PositionKeyRule); `Auto`
//!   measures both readings and reports its choice as an `ms3d-position-keys` diagnostic.

mod anim;
mod convention;
pub mod parse;

pub use anim::{PositionKeyFigures, ViewerCurves};
pub use convention::euler_to_quat;
use convention::Influences;
pub use parse::{parse, File};

use crate::{ImportError, ImportOptions, Resolver};
use sinew_core::glam::{Mat4, Vec2, Vec3};
use sinew_core::{JointDesc, JointIndex, Lod, Skeleton, Submesh, Transform};
use sinew_scene::{Diagnostic, Material, Mesh, Scene, SourceFormat};
use std::collections::HashMap;

/// Imports an MS3D file into a [`Scene`].
pub fn import(
    file_name: &str,
    bytes: &[u8],
    _resolve: Resolver<'_>,
    options: &ImportOptions,
) -> Result<Scene, ImportError> {
    let file = parse(file_name, bytes)?;
    build_scene(file_name, &file, options)
}

/// Builds the scene from a parsed file (see the module documentation for the conventions).
pub fn build_scene(
    file_name: &str,
    file: &File,
    options: &ImportOptions,
) -> Result<Scene, ImportError> {
    let mut scene = Scene::new(SourceFormat::Ms3d);
    if let Some((at, n)) = file.trailing {
        scene.diagnostics.push(Diagnostic::warning(
            "ms3d-trailing-bytes",
            format!("{n} bytes at byte {at} after the last block understood were ignored"),
        ));
    }

    // Skeleton.
    let (mut skeleton, new_index) = build_skeleton(file_name, file)?;

    // Materials: unique names; empty names become `material<i>`.
    let mut material_names = Vec::with_capacity(file.materials.len());
    for (i, m) in file.materials.iter().enumerate() {
        let mut name = if m.name.is_empty() {
            format!("material{i}")
        } else {
            m.name.clone()
        };
        if material_names.contains(&name) {
            name = format!("{name}#{i}");
        }
        material_names.push(name.clone());
        let c = m.diffuse;
        scene.materials.push(Material {
            name,
            base_color: [c[0], c[1], c[2], m.transparency.clamp(0.0, 1.0)],
            texture: (!m.texture.is_empty()).then(|| m.texture.clone()),
        });
    }

    // Skin influences per file vertex; vertices without a joint go to an added static joint.
    let influences = match &mut skeleton {
        Some(skel) => {
            let (mut inf, unweighted) = vertex_influences(file, &new_index, &mut scene.diagnostics);
            if !unweighted.is_empty() {
                let joint = add_static_joint(file_name, skel)?;
                for &v in &unweighted {
                    if let Some(slot) = inf.get_mut(v) {
                        *slot = ([joint, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]);
                    }
                }
                scene.diagnostics.push(
                    Diagnostic::warning(
                        "ms3d-unweighted-vertices",
                        format!(
                            "{} vertices have no joint; they were bound to the added static joint {:?} \
                             (a root with the identity bind pose that no clip drives), so they stay where \
                             they are in every pose, as in Milkshape",
                            unweighted.len(),
                            skel.names()[usize::from(joint)]
                        ),
                    )
                    .with_figure("vertices", unweighted.len() as f64),
                );
            }
            Some(inf)
        }
        None => None,
    };

    if !file.triangles.is_empty() && !file.groups.is_empty() {
        let mesh = build_mesh(
            file_name,
            file,
            &material_names,
            influences.as_deref(),
            &mut scene.diagnostics,
        )?;
        scene.meshes.push(mesh);
    }

    if let Some(skeleton) = &skeleton {
        if let Some(clip) = anim::build_clip(
            file_name,
            file,
            skeleton,
            &new_index,
            influences.as_deref(),
            options.ms3d_position_keys,
            &mut scene.diagnostics,
        )? {
            scene.clips.push(clip);
        }
    }
    scene.skeleton = skeleton;
    Ok(scene)
}

fn build_skeleton(
    file_name: &str,
    file: &File,
) -> Result<(Option<Skeleton>, Vec<JointIndex>), ImportError> {
    if file.joints.is_empty() {
        return Ok((None, Vec::new()));
    }
    let mut descs = Vec::with_capacity(file.joints.len());
    for j in &file.joints {
        let bind = Transform::new(
            Vec3::from_array(j.position),
            euler_to_quat(j.rotation),
            Vec3::ONE,
        );
        if !bind.is_finite() {
            return Err(ImportError::at_offset(
                file_name,
                "joints",
                j.offset as u64,
                format!("joint {:?} has a non-finite bind pose", j.name),
            ));
        }
        descs.push(JointDesc {
            name: j.name.clone(),
            parent: (!j.parent.is_empty()).then(|| j.parent.clone()),
            bind_local: bind,
            inverse_bind: None,
        });
    }
    let (skeleton, new_index) = Skeleton::from_unordered(descs).map_err(|e| {
        ImportError::in_section(file_name, "joints", format!("invalid joint hierarchy: {e}"))
    })?;
    Ok((Some(skeleton), new_index))
}

/// Name of the static joint added for vertices without a joint (`#2`, `#3`... appended if taken).
pub const UNASSIGNED_JOINT: &str = "(unassigned)";

/// Appends a root joint with the identity bind pose and inverse bind matrix, named
/// [`UNASSIGNED_JOINT`], and returns its index. The other joints keep their indices, so the other
/// vertices keep their influences, bit for bit.
fn add_static_joint(file_name: &str, skel: &mut Skeleton) -> Result<JointIndex, ImportError> {
    let mut name = UNASSIGNED_JOINT.to_string();
    let mut k = 2;
    while skel.find(&name).is_some() {
        name = format!("{UNASSIGNED_JOINT}#{k}");
        k += 1;
    }
    let index = skel.len();
    let mut names = skel.names().to_vec();
    names.push(name);
    let mut parents = skel.parents().to_vec();
    parents.push(None);
    let mut bind = skel.bind_local().to_vec();
    bind.push(Transform::IDENTITY);
    let mut inverse = skel.inverse_bind().to_vec();
    inverse.push(Mat4::IDENTITY);
    *skel = Skeleton::new(names, parents, bind, inverse).map_err(|e| {
        ImportError::in_section(
            file_name,
            "joints",
            format!("adding a static joint for vertices without a joint: {e}"),
        )
    })?;
    JointIndex::try_from(index).map_err(|_| {
        ImportError::in_section(file_name, "joints", "too many joints for a static joint")
    })
}

/// Per file vertex its influences, and the vertices with no valid joint (their entry is a
/// placeholder the caller replaces).
fn vertex_influences(
    file: &File,
    new_index: &[JointIndex],
    diagnostics: &mut Vec<Diagnostic>,
) -> (Vec<Influences>, Vec<usize>) {
    let nj = new_index.len();
    let mut unweighted = Vec::new();
    let mut bad_ids = 0usize;
    let mut out = Vec::with_capacity(file.vertices.len());
    for (i, v) in file.vertices.iter().enumerate() {
        let mut pairs: Vec<(i32, f32)> = Vec::with_capacity(4);
        match &file.vertex_extra {
            Some(x) => {
                let ids = x.bone_ids.get(i).copied().unwrap_or([-1; 3]);
                let w = x.weights.get(i).copied().unwrap_or([0; 3]);
                if w == [0, 0, 0] {
                    pairs.push((v.bone_id as i32, 1.0));
                } else {
                    let scale = x.weight_scale();
                    let w = [w[0] as f32, w[1] as f32, w[2] as f32];
                    let rest = (scale - w[0] - w[1] - w[2]).max(0.0);
                    pairs.push((v.bone_id as i32, w[0] / scale));
                    pairs.push((ids[0] as i32, w[1] / scale));
                    pairs.push((ids[1] as i32, w[2] / scale));
                    pairs.push((ids[2] as i32, rest / scale));
                }
            }
            None => pairs.push((v.bone_id as i32, 1.0)),
        }
        // Merge by joint, drop -1 and out-of-range ids and zero weights.
        let mut merged: Vec<(u16, f32)> = Vec::with_capacity(4);
        for (id, w) in pairs {
            if w <= 0.0 {
                continue;
            }
            if id < 0 {
                continue;
            }
            let Some(&j) = new_index.get(id as usize) else {
                bad_ids += 1;
                continue;
            };
            match merged.iter_mut().find(|(mj, _)| *mj == j) {
                Some(e) => e.1 += w,
                None => merged.push((j, w)),
            }
        }
        let total: f32 = merged.iter().map(|p| p.1).sum();
        if merged.is_empty() || total <= 0.0 {
            unweighted.push(i);
            out.push(([0; 4], [1.0, 0.0, 0.0, 0.0]));
            continue;
        }
        merged.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        let mut joints = [0u16; 4];
        let mut weights = [0f32; 4];
        for (k, (j, w)) in merged.iter().take(4).enumerate() {
            joints[k] = *j;
            weights[k] = *w / total;
        }
        out.push((joints, weights));
    }
    if bad_ids > 0 {
        diagnostics.push(Diagnostic::warning(
            "ms3d-bad-bone-id",
            format!("{bad_ids} vertex influences name a joint index at or beyond the {nj} joints and were dropped"),
        ));
    }
    (out, unweighted)
}

fn canonical(x: f32) -> u32 {
    // +0.0 and -0.0 are the same key.
    (x + 0.0).to_bits()
}

fn build_mesh(
    file_name: &str,
    file: &File,
    material_names: &[String],
    influences: Option<&[Influences]>,
    diagnostics: &mut Vec<Diagnostic>,
) -> Result<Mesh, ImportError> {
    let mut lod = Lod::default();
    let mut source_vertex: Vec<u32> = Vec::new();
    let mut index_of: HashMap<(u16, [u32; 5]), u32> = HashMap::new();
    let mut bad_material = 0usize;
    let tri_base = parse::HEADER_SIZE + 2 + file.vertices.len() * parse::VERTEX_SIZE + 2;
    for (gi, g) in file.groups.iter().enumerate() {
        let first_index = lod.indices.len() as u32;
        for &ti in &g.triangles {
            let Some(tri) = file.triangles.get(ti as usize) else {
                return Err(ImportError::in_section(
                    file_name,
                    "groups",
                    format!(
                        "group {gi} ({:?}) lists triangle {ti}, but there are {} triangles",
                        g.name,
                        file.triangles.len()
                    ),
                ));
            };
            let tri_at = (tri_base + ti as usize * parse::TRIANGLE_SIZE) as u64;
            let positions = {
                let mut p = [Vec3::ZERO; 3];
                for (c, &vi) in tri.vertices.iter().enumerate() {
                    let Some(v) = file.vertices.get(vi as usize) else {
                        return Err(ImportError::at_offset(
                            file_name,
                            "triangles",
                            tri_at,
                            format!(
                                "triangle {ti} uses vertex {vi}, but there are {} vertices",
                                file.vertices.len()
                            ),
                        ));
                    };
                    p[c] = Vec3::from_array(v.position);
                    if !p[c].is_finite() {
                        return Err(ImportError::at_offset(
                            file_name,
                            "vertices",
                            (parse::HEADER_SIZE + 2 + vi as usize * parse::VERTEX_SIZE + 1) as u64,
                            format!("vertex {vi} has a non-finite position"),
                        ));
                    }
                }
                p
            };
            let face = (positions[1] - positions[0])
                .cross(positions[2] - positions[0])
                .normalize_or_zero();
            for (c, &vi) in tri.vertices.iter().enumerate() {
                let mut n = Vec3::from_array(tri.normals[c]);
                n = if n.is_finite() {
                    n.normalize_or_zero()
                } else {
                    Vec3::ZERO
                };
                if n == Vec3::ZERO {
                    n = if face == Vec3::ZERO { Vec3::Y } else { face };
                }
                let uv = Vec2::new(tri.s[c], tri.t[c]);
                if !uv.is_finite() {
                    return Err(ImportError::at_offset(
                        file_name,
                        "triangles",
                        tri_at,
                        format!("triangle {ti} has a non-finite texture coordinate"),
                    ));
                }
                let key = (
                    vi,
                    [
                        canonical(n.x),
                        canonical(n.y),
                        canonical(n.z),
                        canonical(uv.x),
                        canonical(uv.y),
                    ],
                );
                let next = lod.positions.len() as u32;
                let index = *index_of.entry(key).or_insert(next);
                if index == next {
                    lod.positions.push(positions[c]);
                    lod.normals.push(n);
                    lod.uvs.push(uv);
                    source_vertex.push(vi as u32);
                    if let Some(inf) = influences {
                        let (j, w) = inf
                            .get(vi as usize)
                            .copied()
                            .unwrap_or(([0; 4], [1.0, 0.0, 0.0, 0.0]));
                        lod.joints.push(j);
                        lod.weights.push(w);
                    }
                }
                lod.indices.push(index);
            }
        }
        let material = match g.material {
            m if m < 0 => String::new(),
            m => match material_names.get(m as usize) {
                Some(n) => n.clone(),
                None => {
                    bad_material += 1;
                    String::new()
                }
            },
        };
        lod.submeshes.push(Submesh {
            first_index,
            index_count: lod.indices.len() as u32 - first_index,
            material,
        });
    }
    if bad_material > 0 {
        diagnostics.push(Diagnostic::warning(
            "ms3d-bad-material",
            format!("{bad_material} groups name a material index that does not exist; they have no material"),
        ));
    }
    let name = std::path::Path::new(file_name)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("mesh")
        .to_string();
    Ok(Mesh {
        name,
        geometry: lod,
        source_vertex,
        source_vertex_count: file.vertices.len() as u32,
        lods: Vec::new(),
        lods_not_built: Vec::new(),
    })
}
