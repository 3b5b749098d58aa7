//! Materials and meshes: primitives to submeshes, skin weights reduced to four, generated normals.

use super::document::{at, floats, uints, Loaded};
use super::skin::{Graph, Rig};
use crate::ImportError;
use glam::{Mat3, Mat4, Vec2, Vec3};
use sinew_core::{Lod, Submesh};
use sinew_scene::{Diagnostic, Material, Mesh, Scene};
use std::collections::HashSet;

pub(super) fn material_names(doc: &gltf::Document) -> Vec<String> {
    let mut used = HashSet::new();
    doc.materials()
        .map(|m| {
            let i = m.index().unwrap_or(0);
            let mut n = match m.name() {
                Some(s) if !s.is_empty() => s.to_string(),
                _ => format!("material{i}"),
            };
            if !used.insert(n.clone()) {
                n = format!("{n}#{i}");
                used.insert(n.clone());
            }
            n
        })
        .collect()
}

pub(super) fn materials(doc: &gltf::Document) -> Vec<Material> {
    let names = material_names(doc);
    doc.materials()
        .zip(names)
        .map(|(m, name)| {
            let pbr = m.pbr_metallic_roughness();
            // A texture without a source (its image only in an extension's format) is left out
            // (the `gltf-texture-without-image` warning, tolerate.rs).
            let texture = pbr.base_color_texture().and_then(|info| {
                let img = info.texture().source()?;
                Some(match img.source() {
                    gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
                        uri.to_string()
                    }
                    _ => format!("images[{}]", img.index()),
                })
            });
            Material {
                name,
                base_color: pbr.base_color_factor(),
                texture,
            }
        })
        .collect()
}

/// The UVs of a material's base colour texture, the one texture (and so the one UV set) sinew
/// keeps: the set it reads (its KHR_texture_transform `texCoord` override, else its `texCoord`; 0
/// without a texture), and what a coordinate of that set becomes, with the texture's transform
/// (`offset + R(rotation) * (scale * uv)`) baked in (the identity without one). gltfpack's
/// quantized texture coordinates (KHR_mesh_quantization) are integers that this transform maps
/// back to the texture's coordinates.
fn base_colour_uvs(material: &gltf::Material<'_>) -> (u32, impl Fn(Vec2) -> Vec2) {
    let info = material.pbr_metallic_roughness().base_color_texture();
    let transform = info.as_ref().and_then(|i| i.texture_transform());
    let set = match (&info, &transform) {
        (Some(info), t) => t
            .as_ref()
            .and_then(|t| t.tex_coord())
            .unwrap_or(info.tex_coord()),
        (None, _) => 0,
    };
    let t = transform.map(|t| (Vec2::from(t.offset()), t.rotation(), Vec2::from(t.scale())));
    let map = move |uv: Vec2| match t {
        None => uv,
        Some((offset, rotation, scale)) => {
            let (sin, cos) = rotation.sin_cos();
            let s = uv * scale;
            offset + Vec2::new(cos * s.x + sin * s.y, -sin * s.x + cos * s.y)
        }
    };
    (set, map)
}

/// The meshes to import: (node index or None, mesh) in scene order.
pub(super) fn mesh_instances<'a>(
    doc: &'a gltf::Document,
    g: &Graph,
) -> Vec<(Option<usize>, gltf::Mesh<'a>)> {
    // A scene that lists no nodes is read as no scene (the `gltf-empty-scene` warning).
    let scene = doc.default_scene().or_else(|| doc.scenes().next());
    let roots: Vec<usize> = match scene.filter(|s| s.nodes().len() > 0) {
        Some(s) => s.nodes().map(|n| n.index()).collect(),
        None => (0..g.parent.len())
            .filter(|&i| g.parent[i].is_none())
            .collect(),
    };
    let nodes: Vec<gltf::Node<'a>> = doc.nodes().collect();
    if nodes.is_empty() {
        return doc.meshes().map(|m| (None, m)).collect();
    }
    let mut out = Vec::new();
    let mut stack: Vec<usize> = roots.into_iter().rev().collect();
    while let Some(i) = stack.pop() {
        let Some(node) = nodes.get(i) else { continue };
        if let Some(m) = node.mesh() {
            out.push((Some(i), m));
        }
        let kids: Vec<usize> = node.children().map(|c| c.index()).collect();
        stack.extend(kids.into_iter().rev());
    }
    out
}

/// Area-weighted vertex normals of a triangle list; returns the normals and how many had no area.
pub fn generate_normals(positions: &[Vec3], indices: &[u32]) -> (Vec<Vec3>, usize) {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let (a, b, c) = (t[0] as usize, t[1] as usize, t[2] as usize);
        if a >= n.len() || b >= n.len() || c >= n.len() {
            continue;
        }
        let f = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        n[a] += f;
        n[b] += f;
        n[c] += f;
    }
    let mut zero = 0;
    for v in &mut n {
        match v.try_normalize() {
            Some(u) => *v = u,
            None => {
                *v = Vec3::Z;
                zero += 1;
            }
        }
    }
    (n, zero)
}

/// Joint indices and weights of a primitive's vertices.
pub(super) type Influences = (Vec<[u16; 4]>, Vec<[f32; 4]>);

/// Statistics of the influence reduction.
#[derive(Default)]
pub(super) struct WeightStats {
    pub(super) vertices_lost: usize,
    pub(super) max_lost: f32,
    pub(super) sum_lost: f64,
    pub(super) zero_weight: usize,
    pub(super) unnormalised: usize,
}

#[allow(clippy::too_many_lines)]
pub(super) fn import_meshes(
    file: &str,
    l: &Loaded,
    g: &Graph,
    rig: Option<&Rig>,
    scene: &mut Scene,
) -> Result<(), ImportError> {
    let mat_names = material_names(&l.doc);
    let mut used_names = HashSet::new();
    let mut generated_normals = 0usize;
    let mut stats = WeightStats::default();
    for (node, mesh) in mesh_instances(&l.doc, g) {
        let mi = mesh.index();
        let node_skin = node
            .and_then(|n| l.doc.nodes().nth(n))
            .and_then(|n| n.skin())
            .map(|s| s.index());
        let skinned = match (node_skin, rig.and_then(|r| r.skin)) {
            (Some(s), Some(c)) if s == c => true,
            (Some(s), _) => {
                scene.diagnostics.push(
                    Diagnostic::warning(
                        "gltf-other-skin-mesh",
                        format!(
                            "meshes[{mi}] on nodes[{}] uses skins[{s}], which was not imported; mesh skipped",
                            node.unwrap_or(0)
                        ),
                    )
                    .with_figure("mesh", mi as f64),
                );
                continue;
            }
            _ => false,
        };
        // Static meshes go to model space; skinned vertices are already in bind space (glTF ignores the
        // skinned mesh node's transform).
        let xf = match node {
            Some(n) if !skinned => g.world[n],
            _ => Mat4::IDENTITY,
        };
        let nxf = Mat3::from_mat4(xf).inverse().transpose();
        let mut lod = Lod::default();
        let mut any_uv = false;
        let mut uv_missing = 0;
        for prim in mesh.primitives() {
            let pp = format!("meshes[{mi}].primitives[{}]", prim.index());
            let mode = prim.mode();
            use gltf::mesh::Mode;
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                scene.diagnostics.push(Diagnostic::warning(
                    "gltf-primitive-skipped",
                    format!("{pp} has mode {mode:?}; only triangles are imported"),
                ));
                continue;
            }
            let Some(pos_acc) = prim.get(&gltf::Semantic::Positions) else {
                scene.diagnostics.push(Diagnostic::warning(
                    "gltf-primitive-skipped",
                    format!("{pp} has no POSITION attribute; skipped"),
                ));
                continue;
            };
            let pos = floats(file, l, &pos_acc, 3, &format!("{pp}.attributes.POSITION"))?;
            let n = pos.len() / 3;
            let check_count = |acc: &gltf::Accessor<'_>, name: &str| -> Result<(), ImportError> {
                if acc.count() != n {
                    return Err(at(
                        file,
                        format!("{pp}.attributes.{name}"),
                        format!(
                            "accessors[{}] has {} elements; POSITION has {n}",
                            acc.index(),
                            acc.count()
                        ),
                    ));
                }
                Ok(())
            };
            // Triangle indices, local to this primitive.
            let raw: Vec<u32> = match prim.indices() {
                Some(acc) => {
                    let v = uints(file, l, &acc, 1, &format!("{pp}.indices"))?;
                    if let Some(k) = v.iter().position(|&i| i as usize >= n) {
                        return Err(at(
                            file,
                            format!("{pp}.indices"),
                            format!(
                                "index {} (entry {k} of accessors[{}]) is out of range for {n} vertices",
                                v[k],
                                acc.index()
                            ),
                        ));
                    }
                    v
                }
                None => (0..n as u32).collect(),
            };
            let tris: Vec<u32> = match mode {
                Mode::TriangleStrip => {
                    let mut t = Vec::new();
                    for k in 2..raw.len() {
                        if k % 2 == 0 {
                            t.extend_from_slice(&[raw[k - 2], raw[k - 1], raw[k]]);
                        } else {
                            t.extend_from_slice(&[raw[k - 1], raw[k - 2], raw[k]]);
                        }
                    }
                    t
                }
                Mode::TriangleFan => {
                    let mut t = Vec::new();
                    for k in 2..raw.len() {
                        t.extend_from_slice(&[raw[0], raw[k - 1], raw[k]]);
                    }
                    t
                }
                _ => {
                    let whole = raw.len() / 3 * 3;
                    if whole != raw.len() {
                        scene.diagnostics.push(Diagnostic::warning(
                            "gltf-partial-triangle",
                            format!(
                                "{pp} has {} indices, not a multiple of 3; the last {} dropped",
                                raw.len(),
                                raw.len() - whole
                            ),
                        ));
                    }
                    raw[..whole].to_vec()
                }
            };
            let positions: Vec<Vec3> = pos
                .chunks_exact(3)
                .map(|c| xf.transform_point3(Vec3::new(c[0], c[1], c[2])))
                .collect();
            let normals: Vec<Vec3> = match prim.get(&gltf::Semantic::Normals) {
                Some(acc) => {
                    check_count(&acc, "NORMAL")?;
                    let v = floats(file, l, &acc, 3, &format!("{pp}.attributes.NORMAL"))?;
                    let (gen, _) = generate_normals(&positions, &tris);
                    v.chunks_exact(3)
                        .zip(gen)
                        .map(|(c, fallback)| {
                            (nxf * Vec3::new(c[0], c[1], c[2]))
                                .try_normalize()
                                .unwrap_or(fallback)
                        })
                        .collect()
                }
                None => {
                    generated_normals += 1;
                    generate_normals(&positions, &tris).0
                }
            };
            let (set, transform) = base_colour_uvs(&prim.material());
            let set = if set != 0 && prim.get(&gltf::Semantic::TexCoords(set)).is_none() {
                scene.diagnostics.push(
                    Diagnostic::warning(
                        "gltf-texcoord-missing",
                        format!(
                            "{pp}: its material's base colour texture reads TEXCOORD_{set}, which the primitive lacks; TEXCOORD_0 read instead"
                        ),
                    )
                    .with_figure("set", f64::from(set)),
                );
                0
            } else {
                set
            };
            let uvs: Option<Vec<Vec2>> = match prim.get(&gltf::Semantic::TexCoords(set)) {
                Some(acc) => {
                    let name = format!("TEXCOORD_{set}");
                    check_count(&acc, &name)?;
                    let v = floats(file, l, &acc, 2, &format!("{pp}.attributes.{name}"))?;
                    Some(
                        v.chunks_exact(2)
                            .map(|c| transform(Vec2::new(c[0], c[1])))
                            .collect(),
                    )
                }
                None => None,
            };
            let mut influences: Option<Influences> = None;
            if skinned {
                let Some(rig) = rig else { continue };
                let mut sets: Vec<(Vec<u32>, Vec<f32>)> = Vec::new();
                for s in 0.. {
                    let (Some(ja), Some(wa)) = (
                        prim.get(&gltf::Semantic::Joints(s)),
                        prim.get(&gltf::Semantic::Weights(s)),
                    ) else {
                        break;
                    };
                    check_count(&ja, &format!("JOINTS_{s}"))?;
                    check_count(&wa, &format!("WEIGHTS_{s}"))?;
                    let jv = uints(file, l, &ja, 4, &format!("{pp}.attributes.JOINTS_{s}"))?;
                    let wv = floats(file, l, &wa, 4, &format!("{pp}.attributes.WEIGHTS_{s}"))?;
                    if let Some(k) = wv.iter().position(|&w| w < 0.0) {
                        return Err(at(
                            file,
                            format!("{pp}.attributes.WEIGHTS_{s}"),
                            format!("vertex {} has a negative weight", k / 4),
                        ));
                    }
                    sets.push((jv, wv));
                }
                if sets.is_empty() {
                    scene.diagnostics.push(Diagnostic::warning(
                        "gltf-primitive-skipped",
                        format!(
                            "{pp} belongs to a skinned mesh but has no JOINTS_0/WEIGHTS_0; skipped"
                        ),
                    ));
                    continue;
                }
                let nj = rig.skin_map.len();
                let mut joints = Vec::with_capacity(n);
                let mut weights = Vec::with_capacity(n);
                for v in 0..n {
                    let mut list: Vec<(u32, f32)> = Vec::with_capacity(4 * sets.len());
                    for (s, (jv, wv)) in sets.iter().enumerate() {
                        for c in 0..4 {
                            let (j, w) = (jv[v * 4 + c], wv[v * 4 + c]);
                            if w == 0.0 {
                                continue;
                            }
                            if j as usize >= nj {
                                return Err(at(
                                    file,
                                    format!("{pp}.attributes.JOINTS_{s}"),
                                    format!("vertex {v} uses joint {j}; the skin has {nj} joints"),
                                ));
                            }
                            match list.iter_mut().find(|e| e.0 == j) {
                                Some(e) => e.1 += w,
                                None => list.push((j, w)),
                            }
                        }
                    }
                    let total: f32 = list.iter().map(|e| e.1).sum();
                    if total > 0.0 && (total - 1.0).abs() > 1e-3 {
                        stats.unnormalised += 1;
                    }
                    list.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
                    let kept: f32 = list.iter().take(4).map(|e| e.1).sum();
                    let mut jj = [0u16; 4];
                    let mut ww = [0f32; 4];
                    if total <= 0.0 || kept <= 0.0 {
                        stats.zero_weight += 1;
                        jj[0] = rig.skin_map.first().copied().unwrap_or(0);
                        ww[0] = 1.0;
                    } else {
                        if list.len() > 4 {
                            let lost = (total - kept) / total;
                            stats.vertices_lost += 1;
                            stats.max_lost = stats.max_lost.max(lost);
                            stats.sum_lost += lost as f64;
                        }
                        for (k, &(j, w)) in list.iter().take(4).enumerate() {
                            jj[k] = rig.skin_map.get(j as usize).copied().unwrap_or(0);
                            ww[k] = w / kept;
                        }
                    }
                    joints.push(jj);
                    weights.push(ww);
                }
                influences = Some((joints, weights));
            }
            let base = lod.positions.len() as u32;
            let first = lod.indices.len() as u32;
            lod.positions.extend(positions);
            lod.normals.extend(normals);
            match uvs {
                Some(u) => {
                    if !any_uv && base > 0 {
                        lod.uvs.resize(base as usize, Vec2::ZERO);
                    }
                    any_uv = true;
                    lod.uvs.extend(u);
                }
                None => {
                    uv_missing += 1;
                    if any_uv {
                        lod.uvs.resize(lod.positions.len(), Vec2::ZERO);
                    }
                }
            }
            if let Some((j, w)) = influences {
                lod.joints.extend(j);
                lod.weights.extend(w);
            }
            lod.indices.extend(tris.iter().map(|&i| i + base));
            let material = prim
                .material()
                .index()
                .and_then(|i| mat_names.get(i).cloned())
                .unwrap_or_default();
            lod.submeshes.push(Submesh {
                first_index: first,
                index_count: lod.indices.len() as u32 - first,
                material,
            });
        }
        if lod.positions.is_empty() {
            continue;
        }
        if any_uv && uv_missing > 0 {
            scene.diagnostics.push(Diagnostic::warning(
                "gltf-missing-uvs",
                format!("meshes[{mi}]: {uv_missing} primitives have no TEXCOORD_0; their UVs are set to 0"),
            ));
        }
        let mut name = match mesh.name() {
            Some(s) if !s.is_empty() => s.to_string(),
            _ => format!("mesh{mi}"),
        };
        if !used_names.insert(name.clone()) {
            name = format!("{name}#{}", node.unwrap_or(mi));
            used_names.insert(name.clone());
        }
        scene.meshes.push(Mesh::unsplit(name, lod));
    }
    if generated_normals > 0 {
        scene.diagnostics.push(
            Diagnostic::warning(
                "gltf-generated-normals",
                format!("{generated_normals} primitives have no NORMAL; area-weighted normals were generated"),
            )
            .with_figure("primitives", generated_normals as f64),
        );
    }
    if stats.vertices_lost > 0 {
        scene.diagnostics.push(
            Diagnostic::warning(
                "gltf-influences-reduced",
                format!(
                    "{} vertices had more than 4 influences; kept the 4 largest and renormalised (lost weight: max {:.4}, mean {:.4})",
                    stats.vertices_lost,
                    stats.max_lost,
                    stats.sum_lost / stats.vertices_lost as f64
                ),
            )
            .with_figure("vertices", stats.vertices_lost as f64)
            .with_figure("max_lost", stats.max_lost as f64)
            .with_figure("mean_lost", stats.sum_lost / stats.vertices_lost as f64),
        );
    }
    if stats.unnormalised > 0 {
        scene.diagnostics.push(
            Diagnostic::warning(
                "gltf-weights-renormalised",
                format!(
                    "{} vertices have weights that do not sum to 1 (off by more than 0.001); they were divided by their sum",
                    stats.unnormalised
                ),
            )
            .with_figure("vertices", stats.unnormalised as f64),
        );
    }
    if stats.zero_weight > 0 {
        scene.diagnostics.push(
            Diagnostic::warning(
                "gltf-zero-weights",
                format!(
                    "{} vertices have no weight; bound to the skin's first joint",
                    stats.zero_weight
                ),
            )
            .with_figure("vertices", stats.zero_weight as f64),
        );
    }
    Ok(())
}
