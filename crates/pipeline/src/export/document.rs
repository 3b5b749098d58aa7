//! Building the glTF document of an export from a decoded [`Asset`]: joints as nodes, one skin, the
//! materials and their embedded textures, every mesh LOD as its own glTF mesh (LOD 0 in the scene, the
//! others behind `MSFT_lod`), every clip as an animation sampled through the runtime, and what glTF has
//! no place for in `extras`. Decisions: docs/export.md.

use super::animation::{key_clip, tolerances, unit, KeyedClip};
use super::buffer::{Bin, Use};
use crate::body::{self, BodyChoice};
use gltf_json as json;
use json::accessor::Type;
use json::validation::Checked::Valid;
use json::Index;
use serde_json::{json as js, Map, Value};
use sinew_core::format::Asset;
use sinew_core::glam::{Mat4, Vec3};
use sinew_core::{Lod, Skeleton};
use std::collections::BTreeMap;
use std::sync::Arc;

/// An image to embed, and the material texture string it stands for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExportImage {
    /// The `texture` string of the materials that use it, exactly as the asset holds it.
    pub key: String,
    /// The image's name in the glTF file.
    pub name: String,
    /// `image/png` or `image/jpeg`.
    pub mime: String,
    /// The encoded file.
    pub bytes: Vec<u8>,
    /// True when some pixels are transparent (a Half-Life masked texture): the material gets
    /// `alphaMode: MASK`.
    pub alpha_mask: bool,
}

/// What was exported and what was left out.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize)]
pub struct ExportReport {
    /// Joint nodes.
    pub joints: usize,
    /// glTF meshes of the model in the default scene (LOD 0 of each mesh of its body).
    pub meshes: usize,
    /// Further glTF meshes holding LODs 1 and up (`--variants`: behind `MSFT_lod`, in scenes
    /// `LOD 1` ...).
    pub lod_meshes: usize,
    /// LOD 0 of the meshes outside the model's body (`--variants`: each in a scene of its own).
    pub other_meshes: usize,
    /// glTF scenes (1 without `--variants`).
    pub scenes: usize,
    /// Materials.
    pub materials: usize,
    /// Embedded images.
    pub images: usize,
    /// Animations (one per exported clip).
    pub animations: usize,
    /// Keys over all channels of all animations.
    pub keys: usize,
    /// One sentence per thing left out (a clip that drives no joint, a texture not found...).
    pub notes: Vec<String>,
}

/// A built document and its binary buffer (not yet packed as GLB or `.gltf`).
#[derive(Debug)]
pub struct Built {
    /// The JSON document; buffer 0 is `bin`, added by the container writer.
    pub root: json::Root,
    /// Buffer 0's bytes.
    pub bin: Vec<u8>,
    /// What went in.
    pub report: ExportReport,
}

/// The generator string written in `asset.generator`.
pub const GENERATOR: &str = concat!("sinew ", env!("CARGO_PKG_VERSION"));

/// Options of one export.
#[derive(Debug, Clone, Default)]
pub struct ExportOptions {
    /// The file's game data as JSON, written under `extras.sinew.game` (the CLI passes the same object
    /// `inspect --json` prints).
    pub game: Option<Value>,
    /// The meshes that make the model in the default scene, or `None` for the default body
    /// ([`crate::body`]).
    pub meshes: Option<Vec<usize>>,
    /// Also write every other mesh and every LOD, each in a scene of its own.
    pub variants: bool,
}

/// Builds the document. `images` are matched to materials by [`ExportImage::key`].
pub fn build(asset: &Asset, images: &[ExportImage], options: &ExportOptions) -> Built {
    let mut b = Builder {
        root: json::Root::default(),
        bin: Bin::default(),
        report: ExportReport::default(),
    };
    b.root.asset = json::Asset {
        generator: Some(GENERATOR.to_string()),
        version: "2.0".to_string(),
        ..Default::default()
    };
    let skeleton = asset
        .skeleton
        .clone()
        .filter(|s| !s.is_empty())
        .map(Arc::new);
    let mut roots = Vec::new();
    let mut skin = None;
    if let Some(s) = &skeleton {
        roots = b.joints(s);
        if roots.len() > 1 {
            // glTF wants the joints of a skin under one common root: a plain node (not a joint,
            // identity transform) holds the skeleton's roots.
            let holder = b.root.push(json::Node {
                name: Some("skeleton".to_string()),
                children: Some(roots),
                ..Default::default()
            });
            roots = vec![holder];
        }
        skin = Some(b.skin(s, &roots));
    }
    let textures = b.textures(asset, images);
    let materials = b.materials(asset, &textures, images);
    let model: Vec<usize> = match &options.meshes {
        Some(m) => m
            .iter()
            .copied()
            .filter(|&i| i < asset.meshes.len())
            .collect(),
        None => body::select(asset, &BodyChoice::Default).unwrap_or_default(),
    };
    // Per mesh: its nodes by LOD level (LOD 0 first).
    let mut mesh_nodes: Vec<Vec<(usize, Index<json::Node>)>> = vec![Vec::new(); asset.meshes.len()];
    let mut lods_used = false;
    let in_model = |mi: &usize| model.contains(mi);
    let order: Vec<usize> = model
        .iter()
        .copied()
        .chain((0..asset.meshes.len()).filter(|mi| options.variants && !in_model(mi)))
        .collect();
    for mi in order {
        let mesh = &asset.meshes[mi];
        let levels = if options.variants { mesh.lods.len() } else { 1 };
        let mut nodes = Vec::new();
        for (level, lod) in mesh.lods.iter().enumerate().take(levels) {
            let name = if level == 0 {
                mesh.name.clone()
            } else {
                format!("{} LOD{level}", mesh.name)
            };
            let skinned = lod.is_skinned() && skeleton.is_some();
            let Some(m) = b.mesh(&name, lod, skinned, &materials) else {
                if level == 0 {
                    b.report.notes.push(format!(
                        "mesh {:?} has no triangles; not exported",
                        mesh.name
                    ));
                    break;
                }
                continue;
            };
            if level > 0 {
                let info = asset.lod_info(mi, level);
                b.root.meshes[m.value()].extras = raw(&js!({
                    "sinew_lod": {
                        "level": level,
                        "triangles": lod.triangle_count(),
                        "error_relative": lod.error,
                        "error_model": info.error_model,
                        "target_ratio": info.target_ratio,
                        "reached_ratio": info.reached_ratio,
                        "stopped_by_error_limit": info.stopped_by_error_limit,
                    }
                }));
                b.report.lod_meshes += 1;
            } else if in_model(&mi) {
                b.report.meshes += 1;
            } else {
                b.report.other_meshes += 1;
            }
            nodes.push((
                level,
                b.root.push(json::Node {
                    mesh: Some(m),
                    name: Some(name),
                    skin: if skinned { skin } else { None },
                    ..Default::default()
                }),
            ));
        }
        if let Some((&(_, first), rest)) = nodes.split_first() {
            if !rest.is_empty() {
                lods_used = true;
                let mut others = Map::new();
                others.insert(
                    "MSFT_lod".to_string(),
                    js!({ "ids": rest.iter().map(|(_, n)| n.value()).collect::<Vec<_>>() }),
                );
                b.root.nodes[first.value()].extensions =
                    Some(json::extensions::scene::Node { others });
            }
        }
        mesh_nodes[mi] = nodes;
    }
    if lods_used {
        b.root.extensions_used.push("MSFT_lod".to_string());
    }
    // Scene 0: the model at LOD 0. With variants: the model at each further LOD, then each other
    // mesh, every scene with the skeleton.
    let scene = |name: String, nodes: Vec<Index<json::Node>>| json::Scene {
        extensions: None,
        extras: Default::default(),
        name: Some(name),
        nodes: roots.iter().copied().chain(nodes).collect(),
    };
    let at_level = |mi: usize, level: usize| {
        mesh_nodes[mi]
            .iter()
            .find(|(l, _)| *l == level)
            .map(|(_, n)| *n)
    };
    let mut scenes = vec![scene(
        "sinew".to_string(),
        model.iter().filter_map(|&mi| at_level(mi, 0)).collect(),
    )];
    if options.variants {
        let top = model
            .iter()
            .map(|&mi| asset.meshes[mi].lods.len())
            .max()
            .unwrap_or(0);
        for level in 1..top {
            // A mesh whose level was not built (lods_not_built) shows its last level, so the
            // scene is the whole model at that level.
            let nodes: Vec<_> = model
                .iter()
                .filter_map(|&mi| {
                    let last = asset.meshes[mi].lods.len().saturating_sub(1);
                    at_level(mi, level.min(last))
                })
                .collect();
            if !nodes.is_empty() {
                scenes.push(scene(format!("LOD {level}"), nodes));
            }
        }
        for (mi, mesh) in asset.meshes.iter().enumerate() {
            if !in_model(&mi) {
                if let Some(n) = at_level(mi, 0) {
                    scenes.push(scene(mesh.name.clone(), vec![n]));
                }
            }
        }
    } else {
        let others: Vec<&str> = (0..asset.meshes.len())
            .filter(|mi| !in_model(mi))
            .map(|mi| asset.meshes[mi].name.as_str())
            .collect();
        if !others.is_empty() {
            b.report.notes.push(format!(
                "{} meshes outside the model's body are not exported ({}); --variants writes each in a scene of its own",
                others.len(),
                others.join(", ")
            ));
        }
        let lods: usize = model
            .iter()
            .map(|&mi| asset.meshes[mi].lods.len().saturating_sub(1))
            .sum();
        if lods > 0 {
            b.report.notes.push(format!(
                "{lods} LOD meshes are not exported; --variants writes them behind MSFT_lod and in scenes of their own"
            ));
        }
    }
    b.report.scenes = scenes.len();
    let mut clips = Vec::new();
    let tol = tolerances(asset);
    for clip in &asset.clips {
        let mut entry = js!({
            "name": clip.name(),
            "duration": clip.duration(),
            "sample_rate": clip.sample_rate(),
            "looping": clip.looping(),
            "additive": clip.additive(),
            "compressed": clip.is_compressed(),
        });
        match &skeleton {
            None => {
                b.report.notes.push(format!(
                    "clip {:?} not exported: the file has no skeleton",
                    clip.name()
                ));
                entry["animation"] = Value::Null;
            }
            Some(s) => match key_clip(s, clip, &tol) {
                Ok(keyed) => {
                    entry["animation"] = js!(b.root.animations.len());
                    entry["keys"] = js!(keyed.key_count());
                    entry["unbound_tracks"] = js!(keyed.unbound);
                    b.animation(clip.name(), &keyed);
                }
                Err(e) => {
                    b.report.notes.push(format!("{e}; not exported"));
                    entry["animation"] = Value::Null;
                }
            },
        }
        clips.push(entry);
    }
    let masks: Vec<Value> = asset
        .masks
        .iter()
        .map(|m| {
            let w: BTreeMap<&str, f32> = m.weights.iter().map(|(j, w)| (j.as_str(), *w)).collect();
            js!({ "name": m.name, "weights": w })
        })
        .collect();
    let mut sinew = js!({
        "clips": clips,
        "masks": masks,
        "materials": asset.materials.iter().map(|m| js!({
            "name": m.name,
            "texture": m.texture,
        })).collect::<Vec<_>>(),
        "notes": b.report.notes,
    });
    if let Some(g) = &options.game {
        sinew["game"] = g.clone();
    }
    if let Some(a) = asset.axes {
        sinew["axes"] = js!({
            "up": a.up.name(),
            "forward": a.forward.name(),
            "bind_forward": a.bind_forward.name(),
        });
    }
    sinew["body"] = js!(model
        .iter()
        .map(|&mi| asset.meshes[mi].name.as_str())
        .collect::<Vec<_>>());
    b.root.extras = raw(&js!({ "sinew": sinew }));
    b.root.scenes = scenes;
    b.root.scene = Some(Index::new(0));
    Built {
        root: b.root,
        bin: b.bin.bytes,
        report: b.report,
    }
}

/// `value` as a glTF `extras` field.
fn raw(value: &Value) -> json::extras::Extras {
    serde_json::value::to_raw_value(value).ok()
}

struct Builder {
    root: json::Root,
    bin: Bin,
    report: ExportReport,
}

impl Builder {
    /// One node per joint (index = joint index), children linked; returns the roots.
    fn joints(&mut self, s: &Skeleton) -> Vec<Index<json::Node>> {
        let mut children: Vec<Vec<Index<json::Node>>> = vec![Vec::new(); s.len()];
        let mut roots = Vec::new();
        for (j, p) in s.parents().iter().enumerate() {
            match p {
                Some(p) => children[*p as usize].push(Index::new(j as u32)),
                None => roots.push(Index::new(j as u32)),
            }
        }
        for ((name, bind), kids) in s.names().iter().zip(s.bind_local()).zip(children) {
            self.root.push(json::Node {
                name: Some(name.clone()),
                translation: Some(bind.translation.to_array()),
                rotation: Some(json::scene::UnitQuaternion(unit(bind.rotation).to_array())),
                scale: Some(bind.scale.to_array()),
                children: (!kids.is_empty()).then_some(kids),
                ..Default::default()
            });
        }
        self.report.joints = s.len();
        roots
    }

    /// The skin over every joint, in skeleton order, with the runtime's inverse bind matrices.
    fn skin(&mut self, s: &Skeleton, roots: &[Index<json::Node>]) -> Index<json::Skin> {
        let ibm: Vec<f32> = s
            .inverse_bind()
            .iter()
            .flat_map(|m| {
                // glTF requires the last row of an inverse bind matrix to be exactly (0, 0, 0, 1).
                let mut c = m.to_cols_array();
                c[3] = 0.0;
                c[7] = 0.0;
                c[11] = 0.0;
                c[15] = 1.0;
                Mat4::from_cols_array(&c).to_cols_array()
            })
            .collect();
        let acc = self
            .bin
            .floats(&mut self.root, &ibm, Type::Mat4, Use::Other, false);
        self.root.push(json::Skin {
            extensions: None,
            extras: Default::default(),
            inverse_bind_matrices: Some(acc),
            joints: (0..s.len() as u32).map(Index::new).collect(),
            name: Some("skeleton".to_string()),
            skeleton: (roots.len() == 1).then(|| roots[0]),
        })
    }

    /// One texture per image that some material uses, keyed by [`ExportImage::key`].
    fn textures(
        &mut self,
        asset: &Asset,
        images: &[ExportImage],
    ) -> BTreeMap<String, Index<json::Texture>> {
        let mut out = BTreeMap::new();
        let used = |img: &ExportImage| {
            asset
                .materials
                .iter()
                .any(|m| m.texture.as_deref() == Some(img.key.as_str()))
        };
        for img in images {
            if out.contains_key(&img.key) || !used(img) {
                continue;
            }
            if self.root.samplers.is_empty() {
                self.root.push(json::texture::Sampler::default());
            }
            let view = self.bin.view(&mut self.root, &img.bytes, Use::Other);
            let image = self.root.push(json::Image {
                buffer_view: Some(view),
                mime_type: Some(json::image::MimeType(img.mime.clone())),
                name: Some(img.name.clone()),
                uri: None,
                extensions: None,
                extras: Default::default(),
            });
            let t = self.root.push(json::Texture {
                name: Some(img.name.clone()),
                sampler: Some(Index::new(0)),
                source: image,
                extensions: None,
                extras: Default::default(),
            });
            out.insert(img.key.clone(), t);
            self.report.images += 1;
        }
        for m in &asset.materials {
            if let Some(t) = &m.texture {
                if !out.contains_key(t) {
                    self.report.notes.push(format!(
                        "material {:?}: texture {t:?} not found; exported without it",
                        m.name
                    ));
                }
            }
        }
        out
    }

    /// One glTF material per asset material, by name (the first of a repeated name wins).
    fn materials(
        &mut self,
        asset: &Asset,
        textures: &BTreeMap<String, Index<json::Texture>>,
        images: &[ExportImage],
    ) -> BTreeMap<String, Index<json::Material>> {
        let mut out = BTreeMap::new();
        for m in &asset.materials {
            if out.contains_key(&m.name) {
                continue;
            }
            let c = m.base_color.map(|v| {
                if v.is_finite() {
                    v.clamp(0.0, 1.0)
                } else {
                    1.0
                }
            });
            let tex = m.texture.as_ref().and_then(|t| textures.get(t));
            let masked = m
                .texture
                .as_ref()
                .is_some_and(|t| images.iter().any(|i| &i.key == t && i.alpha_mask));
            let alpha_mode = if tex.is_some() && masked {
                json::material::AlphaMode::Mask
            } else if c[3] < 1.0 {
                json::material::AlphaMode::Blend
            } else {
                json::material::AlphaMode::Opaque
            };
            let idx = self.root.push(json::Material {
                name: Some(m.name.clone()),
                alpha_cutoff: (alpha_mode == json::material::AlphaMode::Mask)
                    .then_some(json::material::AlphaCutoff(0.5)),
                alpha_mode: Valid(alpha_mode),
                pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                    base_color_factor: json::material::PbrBaseColorFactor(c),
                    base_color_texture: tex.map(|&index| json::texture::Info {
                        index,
                        tex_coord: 0,
                        extensions: None,
                        extras: Default::default(),
                    }),
                    metallic_factor: json::material::StrengthFactor(0.0),
                    roughness_factor: json::material::StrengthFactor(1.0),
                    ..Default::default()
                },
                ..Default::default()
            });
            out.insert(m.name.clone(), idx);
        }
        self.report.materials = out.len();
        out
    }

    /// One glTF mesh for one LOD: shared vertex accessors, one primitive per submesh. `None` when the
    /// LOD has no triangles.
    fn mesh(
        &mut self,
        name: &str,
        lod: &Lod,
        skinned: bool,
        materials: &BTreeMap<String, Index<json::Material>>,
    ) -> Option<Index<json::Mesh>> {
        let n = lod.vertex_count();
        if n == 0 || lod.triangle_count() == 0 {
            return None;
        }
        let mut ranges: Vec<(usize, usize, &str)> = lod
            .submeshes
            .iter()
            .map(|s| {
                (
                    s.first_index as usize,
                    s.index_count as usize,
                    s.material.as_str(),
                )
            })
            .filter(|&(f, c, _)| c >= 3 && f.checked_add(c).is_some_and(|e| e <= lod.indices.len()))
            .collect();
        if lod.submeshes.is_empty() {
            ranges.push((0, lod.indices.len() / 3 * 3, ""));
        }
        if ranges.is_empty() {
            return None;
        }
        let mut attributes = BTreeMap::new();
        let positions: Vec<f32> = lod.positions.iter().flat_map(|p| p.to_array()).collect();
        let pos = self
            .bin
            .floats(&mut self.root, &positions, Type::Vec3, Use::Vertices, true);
        attributes.insert(Valid(json::mesh::Semantic::Positions), pos);
        if lod.normals.len() == n {
            let normals: Vec<f32> = lod
                .normals
                .iter()
                .flat_map(|v| {
                    let u = v.normalize_or_zero();
                    if u == Vec3::ZERO {
                        [0.0, 1.0, 0.0]
                    } else {
                        u.to_array()
                    }
                })
                .collect();
            let a = self
                .bin
                .floats(&mut self.root, &normals, Type::Vec3, Use::Vertices, false);
            attributes.insert(Valid(json::mesh::Semantic::Normals), a);
        }
        if lod.uvs.len() == n {
            let uvs: Vec<f32> = lod.uvs.iter().flat_map(|v| v.to_array()).collect();
            let a = self
                .bin
                .floats(&mut self.root, &uvs, Type::Vec2, Use::Vertices, false);
            attributes.insert(Valid(json::mesh::Semantic::TexCoords(0)), a);
        }
        if skinned && lod.joints.len() == n && lod.weights.len() == n {
            let a = self.bin.joints(&mut self.root, &lod.joints);
            attributes.insert(Valid(json::mesh::Semantic::Joints(0)), a);
            let w: Vec<f32> = lod.weights.iter().flatten().copied().collect();
            let a = self
                .bin
                .floats(&mut self.root, &w, Type::Vec4, Use::Vertices, false);
            attributes.insert(Valid(json::mesh::Semantic::Weights(0)), a);
        }
        let primitives = ranges
            .into_iter()
            .map(|(first, count, material)| {
                let indices = self
                    .bin
                    .indices(&mut self.root, &lod.indices[first..first + count]);
                json::mesh::Primitive {
                    attributes: attributes.clone(),
                    extensions: None,
                    extras: Default::default(),
                    indices: Some(indices),
                    material: materials.get(material).copied(),
                    mode: Valid(json::mesh::Mode::Triangles),
                    targets: None,
                }
            })
            .collect();
        Some(self.root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some(name.to_string()),
            primitives,
            weights: None,
        }))
    }

    /// One animation: per driven joint a translation, rotation and scale channel, each with its own
    /// keys (joint node index = joint index); channels with the same key times share one time
    /// accessor.
    fn animation(&mut self, name: &str, k: &KeyedClip) {
        let mut inputs: BTreeMap<Vec<u32>, Index<json::Accessor>> = BTreeMap::new();
        let mut channels = Vec::new();
        let mut samplers = Vec::new();
        for (&joint, keys) in k.joints.iter().zip(&k.channels) {
            let parts = [
                (
                    json::animation::Property::Translation,
                    &keys.translation.times,
                    keys.translation
                        .values
                        .iter()
                        .flat_map(|v| v.to_array())
                        .collect::<Vec<f32>>(),
                    Type::Vec3,
                ),
                (
                    json::animation::Property::Rotation,
                    &keys.rotation.times,
                    keys.rotation
                        .values
                        .iter()
                        .flat_map(|v| v.to_array())
                        .collect(),
                    Type::Vec4,
                ),
                (
                    json::animation::Property::Scale,
                    &keys.scale.times,
                    keys.scale
                        .values
                        .iter()
                        .flat_map(|v| v.to_array())
                        .collect(),
                    Type::Vec3,
                ),
            ];
            for (path, times, values, ty) in parts {
                let bits: Vec<u32> = times.iter().map(|t| t.to_bits()).collect();
                let input = match inputs.get(&bits) {
                    Some(&a) => a,
                    None => {
                        let a =
                            self.bin
                                .floats(&mut self.root, times, Type::Scalar, Use::Other, true);
                        inputs.insert(bits, a);
                        a
                    }
                };
                let output = self
                    .bin
                    .floats(&mut self.root, &values, ty, Use::Other, false);
                let sampler = Index::new(samplers.len() as u32);
                samplers.push(json::animation::Sampler {
                    extensions: None,
                    extras: Default::default(),
                    input,
                    interpolation: Valid(json::animation::Interpolation::Linear),
                    output,
                });
                channels.push(json::animation::Channel {
                    sampler,
                    target: json::animation::Target {
                        extensions: None,
                        extras: Default::default(),
                        node: Index::new(u32::from(joint)),
                        path: Valid(path),
                    },
                    extensions: None,
                    extras: Default::default(),
                });
            }
        }
        self.report.animations += 1;
        self.report.keys += k.key_count();
        self.root.push(json::Animation {
            extensions: None,
            extras: Default::default(),
            channels,
            name: Some(name.to_string()),
            samplers,
        });
    }
}
