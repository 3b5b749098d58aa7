//! Drawing an asset in one pose into one cell: the pose through the runtime (local-to-model,
//! skinning palette, [`sinew_core::skin_lod`]), the meshes as z-buffered triangles (textured where
//! their material has an image, flat shaded otherwise), the
//! skeleton drawn over them, and the geometric error of a LOD measured against LOD 0.

use super::camera::Fit;
use super::canvas::{Canvas, Cell, Rgb};
use super::text;
use super::textures::{Blend, Textures};
use sinew_core::format::Asset;
use sinew_core::glam::{Mat4, Vec3};
use sinew_core::{local_to_model, skin_lod, skinning_palette, Lod, Skeleton, Transform};

/// Colours of skeleton bones and joints.
pub const BONE: Rgb = [235, 120, 20];
/// Joint discs.
pub const JOINT: Rgb = [255, 210, 40];
/// Label text.
pub const INK: Rgb = [40, 40, 48];

/// Soft colours for materials that give no useful colour of their own (white, or textured).
const PALETTE: [Rgb; 6] = [
    [176, 188, 206],
    [208, 182, 150],
    [160, 198, 168],
    [204, 164, 182],
    [172, 172, 212],
    [212, 202, 150],
];

/// An asset posed once: joint model matrices and, per mesh and LOD, the posed vertex positions.
pub struct Posed {
    /// Model matrix of each joint (empty without a skeleton).
    pub models: Vec<Mat4>,
    /// `positions[mesh][lod]`.
    pub positions: Vec<Vec<Vec<Vec3>>>,
}

impl Posed {
    /// Joint positions in model space.
    pub fn joints(&self) -> Vec<Vec3> {
        self.models.iter().map(|m| m.w_axis.truncate()).collect()
    }

    /// Every posed point of the LODs up to `max_level` and every joint (for fitting a view).
    pub fn points(&self, max_level: usize) -> Vec<Vec3> {
        let mut v = self.joints();
        for m in &self.positions {
            for l in m.iter().take(max_level + 1) {
                v.extend_from_slice(l);
            }
        }
        v
    }
}

/// Poses `asset` with local transforms `locals` (one per joint; ignored without a skeleton).
/// Skinned LODs are skinned with the runtime's functions; static ones are drawn as stored.
pub fn pose(asset: &Asset, locals: &[Transform]) -> Posed {
    let (models, palette) = match &asset.skeleton {
        Some(s) if s.len() == locals.len() => {
            let mut models = vec![Mat4::IDENTITY; s.len()];
            let mut palette = vec![Mat4::IDENTITY; s.len()];
            let ok = local_to_model(s.parents(), locals, &mut models).is_ok()
                && skinning_palette(&models, s.inverse_bind(), &mut palette).is_ok();
            if ok {
                (models, palette)
            } else {
                (Vec::new(), Vec::new())
            }
        }
        _ => (Vec::new(), Vec::new()),
    };
    let positions = asset
        .meshes
        .iter()
        .map(|m| {
            m.lods
                .iter()
                .map(|l| skinned(l, &palette).unwrap_or_else(|| l.positions.clone()))
                .collect()
        })
        .collect();
    Posed { models, positions }
}

fn skinned(lod: &Lod, palette: &[Mat4]) -> Option<Vec<Vec3>> {
    if !lod.is_skinned() || palette.is_empty() {
        return None;
    }
    let mut p = vec![Vec3::ZERO; lod.vertex_count()];
    let mut n = vec![Vec3::ZERO; lod.normals.len()];
    skin_lod(palette, lod, &mut p, &mut n).ok()?;
    Some(p)
}

/// The bind pose of the asset's skeleton (empty without one).
pub fn bind_pose(asset: &Asset) -> Vec<Transform> {
    asset
        .skeleton
        .as_ref()
        .map(|s| s.bind_local().to_vec())
        .unwrap_or_default()
}

/// The colour a submesh with this material is drawn in.
pub fn material_color(asset: &Asset, name: &str) -> Rgb {
    let index = asset.materials.iter().position(|m| m.name == name);
    let Some(m) = index.and_then(|i| asset.materials.get(i)) else {
        return PALETTE[0];
    };
    let white = m.base_color[..3].iter().all(|&c| c > 0.95);
    if m.texture.is_some() || white {
        return PALETTE[index.unwrap_or(0) % PALETTE.len()];
    }
    let srgb = |c: f32| (c.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0).round() as u8;
    [
        srgb(m.base_color[0]),
        srgb(m.base_color[1]),
        srgb(m.base_color[2]),
    ]
}

/// Draws every mesh of `posed` at LOD `level` (or its last LOD) into `cell`, flat shaded; a submesh
/// whose material has a texture (and whose LOD has texture coordinates) is drawn textured, opaque and
/// masked textures first, additive ones after them so that they add to what is behind.
pub fn draw_meshes(
    canvas: &mut Canvas,
    asset: &Asset,
    posed: &Posed,
    level: usize,
    fit: &Fit,
    cell: Cell,
    textures: &Textures,
) {
    let view = fit.view();
    let light = (view.toward * 0.8 + view.up * 0.5 - view.right * 0.3).normalize();
    canvas.clear_depth();
    for additive_pass in [false, true] {
        for (m, positions) in asset.meshes.iter().zip(&posed.positions) {
            let li = level.min(m.lods.len().saturating_sub(1));
            let (Some(lod), Some(pos)) = (m.lods.get(li), positions.get(li)) else {
                continue;
            };
            let screen: Vec<Vec3> = pos.iter().map(|&p| fit.project(p)).collect();
            let has_uvs = lod.uvs.len() == lod.positions.len();
            let draw_range = |canvas: &mut Canvas, idx: &[u32], material: &str| {
                let tex = textures.get(material).filter(|_| has_uvs);
                if additive_pass != tex.is_some_and(|t| t.blend == Blend::Additive) {
                    return;
                }
                let base = material_color(asset, material);
                for t in idx.chunks_exact(3) {
                    let (Some(&a), Some(&b), Some(&c)) = (
                        pos.get(t[0] as usize),
                        pos.get(t[1] as usize),
                        pos.get(t[2] as usize),
                    ) else {
                        continue;
                    };
                    let n = (b - a).cross(c - a).normalize_or_zero();
                    let shade = 0.3 + 0.7 * n.dot(light).abs();
                    let corners = [
                        screen[t[0] as usize],
                        screen[t[1] as usize],
                        screen[t[2] as usize],
                    ];
                    match tex {
                        Some(tex) => {
                            let uv = [
                                lod.uvs[t[0] as usize],
                                lod.uvs[t[1] as usize],
                                lod.uvs[t[2] as usize],
                            ];
                            canvas.textured_triangle(corners, uv, tex, shade, cell);
                        }
                        None => {
                            let col = base
                                .map(|v| (f32::from(v) * shade).round().clamp(0.0, 255.0) as u8);
                            canvas.triangle(corners[0], corners[1], corners[2], col, cell);
                        }
                    }
                }
            };
            if lod.submeshes.is_empty() {
                draw_range(canvas, &lod.indices, "");
            }
            for s in &lod.submeshes {
                let end = (s.first_index as usize).saturating_add(s.index_count as usize);
                if let Some(idx) = lod.indices.get(s.first_index as usize..end) {
                    draw_range(canvas, idx, &s.material);
                }
            }
        }
    }
}

/// Draws the skeleton of `posed` over the cell: bones from each joint to its parent, a disc per joint,
/// and with `names` each joint's name beside it.
pub fn draw_skeleton(
    canvas: &mut Canvas,
    skeleton: &Skeleton,
    posed: &Posed,
    fit: &Fit,
    names: bool,
) {
    let joints: Vec<Vec3> = posed.joints().iter().map(|&p| fit.project(p)).collect();
    if joints.len() != skeleton.len() {
        return;
    }
    for (j, p) in skeleton.parents().iter().enumerate() {
        if let Some(p) = p {
            let (a, b) = (joints[*p as usize], joints[j]);
            canvas.line((a.x, a.y), (b.x, b.y), BONE, 2.0);
        }
    }
    for p in &joints {
        canvas.dot((p.x, p.y), 2.5, JOINT);
    }
    if names {
        for (p, name) in joints.iter().zip(skeleton.names()) {
            text::draw(canvas, p.x + 4.0, p.y - 3.0, 9.0, name, INK);
        }
    }
}

/// The measured error of a LOD: the larger of the two one-sided vertex-to-surface distances between
/// `lod` and `base` (model units). A simplifier that collapses edges keeps LOD vertices on the
/// original surface, so the distance from the original's vertices to the LOD's surface is the one
/// that shows lost detail; both are taken so neither kind of change hides.
pub fn measured_error(base: &Lod, lod: &Lod) -> f32 {
    one_sided(base, lod).max(one_sided(lod, base))
}

/// Largest distance from a vertex of `from` to the surface of `to` (model units).
pub fn one_sided(from: &Lod, to: &Lod) -> f32 {
    if to.indices.is_empty() || from.positions.is_empty() {
        return 0.0;
    }
    let grid = crate::surface::TriangleGrid::new(&to.positions, &to.indices);
    from.positions
        .iter()
        .map(|&p| grid.distance(p))
        .filter(|d| d.is_finite())
        .fold(0.0, f32::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lod_on_the_surface_has_no_error_and_a_moved_one_does() {
        let base = Lod {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)],
            indices: vec![0, 1, 2, 1, 3, 2],
            ..Default::default()
        };
        let mut lod = base.clone();
        assert_eq!(measured_error(&base, &lod), 0.0);
        lod.positions[3].z = 0.25;
        assert_eq!(measured_error(&base, &lod), 0.25);
        // A LOD that drops a corner: its vertices lie on the original, the original's do not lie on it.
        let cut = Lod {
            positions: base.positions.clone(),
            indices: vec![0, 1, 2],
            ..Default::default()
        };
        assert_eq!(one_sided(&cut, &base), 0.0);
        let d = measured_error(&base, &cut);
        assert!((d - 0.5f32.sqrt()).abs() < 1e-6, "{d}");
    }
}
