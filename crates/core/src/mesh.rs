//! Skinned meshes as the runtime holds them: flat vertex arrays, triangle indices, submeshes, LODs.

use glam::{Vec2, Vec3};

/// Most joints that influence one vertex.
pub const MAX_INFLUENCES: usize = 4;

/// A range of triangle indices drawn with one material.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Submesh {
    /// First index (into [`Lod::indices`]) of this submesh.
    pub first_index: u32,
    /// Number of indices (three per triangle).
    pub index_count: u32,
    /// Material name; empty when the source gave none.
    pub material: String,
}

/// One level of detail: a vertex buffer and the triangles that use it.
///
/// LOD 0 is the source mesh; further LODs are simplified versions with their own vertex buffers.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Lod {
    /// Vertex positions, model space at bind time.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position, or empty.
    pub uvs: Vec<Vec2>,
    /// Up to four joint indices per vertex; empty for a static mesh.
    pub joints: Vec<[u16; MAX_INFLUENCES]>,
    /// Weights matching `joints`, summing to one; unused slots have weight 0.
    pub weights: Vec<[f32; MAX_INFLUENCES]>,
    /// Triangle list, three indices per triangle.
    pub indices: Vec<u32>,
    /// Material ranges of `indices`, in order, covering it exactly.
    pub submeshes: Vec<Submesh>,
    /// Simplifier error relative to the mesh extent (0 for LOD 0).
    pub error: f32,
}

impl Lod {
    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
    /// True when every vertex has joint influences.
    pub fn is_skinned(&self) -> bool {
        !self.joints.is_empty()
    }
}

/// A mesh with its LOD chain.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    /// Mesh name.
    pub name: String,
    /// LOD 0 first, then simpler versions.
    pub lods: Vec<Lod>,
}

impl Mesh {
    /// LOD `level` (0 is the source mesh), or `None` past the last one.
    pub fn lod(&self, level: usize) -> Option<&Lod> {
        self.lods.get(level)
    }

    /// Number of LODs, LOD 0 included.
    pub fn lod_count(&self) -> usize {
        self.lods.len()
    }

    /// The LOD to skin for an object of bounding radius `radius` at `distance` from the camera,
    /// through a symmetric perspective projection of vertical field of view `fov_y` (radians) into
    /// a viewport `viewport_height` pixels tall. See [`select_lod`].
    pub fn select_lod(
        &self,
        radius: f32,
        distance: f32,
        fov_y: f32,
        viewport_height: f32,
    ) -> usize {
        let errors: Vec<f32> = self.lods.iter().map(|l| l.error).collect();
        select_lod(
            &errors,
            projected_pixels(radius, distance, fov_y, viewport_height),
            DEFAULT_PIXEL_ERROR,
        )
    }
}

/// Screen error, in pixels, that [`Mesh::select_lod`] tolerates: one pixel.
pub const DEFAULT_PIXEL_ERROR: f32 = 1.0;

/// How many pixels tall an object of bounding radius `radius` (model units) appears at `distance` from
/// the camera: `viewport_height * radius / (distance * tan(fov_y / 2))`, its projected diameter.
/// A camera inside the bounding sphere (`distance <= radius`) sees it as infinitely large.
pub fn projected_pixels(radius: f32, distance: f32, fov_y: f32, viewport_height: f32) -> f32 {
    if distance.is_nan() || radius.is_nan() || distance <= radius {
        return f32::INFINITY;
    }
    let t = (fov_y * 0.5).tan();
    if t.is_nan() || t <= 0.0 {
        return f32::INFINITY;
    }
    viewport_height * radius / (distance * t)
}

/// Picks a LOD by screen-space error.
///
/// `errors[k]` is LOD `k`'s simplification error relative to the mesh extent ([`Lod::error`], 0 for
/// LOD 0; errors grow along the chain). An object `screen_size` pixels tall shows a relative error `e`
/// as about `e * screen_size` pixels; the answer is the simplest LOD whose projected error stays at or
/// under `max_pixel_error`, never below LOD 0. Non-finite sizes pick LOD 0; an empty list gives 0.
pub fn select_lod(errors: &[f32], screen_size: f32, max_pixel_error: f32) -> usize {
    if !screen_size.is_finite() || errors.is_empty() {
        return 0;
    }
    let size = screen_size.max(0.0);
    let mut best = 0;
    for (k, &e) in errors.iter().enumerate() {
        if e.is_finite() && e * size <= max_pixel_error {
            best = k;
        } else {
            break;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lod_and_selection_by_screen_size() {
        let errors = [0.0, 0.004, 0.02];
        // 100 px tall: LOD 1 shows 0.4 px, LOD 2 shows 2 px.
        assert_eq!(select_lod(&errors, 100.0, 1.0), 1);
        // 40 px tall: LOD 2 shows 0.8 px.
        assert_eq!(select_lod(&errors, 40.0, 1.0), 2);
        // 1000 px: LOD 1 shows 4 px.
        assert_eq!(select_lod(&errors, 1000.0, 1.0), 0);
        assert_eq!(select_lod(&errors, f32::INFINITY, 1.0), 0);
        assert_eq!(select_lod(&[], 10.0, 1.0), 0);
        // Radius 1 at distance 10, 90 degree field of view, 1000 px: 1000 * 1 / (10 * 1) = 100 px.
        let px = projected_pixels(1.0, 10.0, std::f32::consts::FRAC_PI_2, 1000.0);
        assert!((px - 100.0).abs() < 1e-3, "{px}");
        assert_eq!(projected_pixels(1.0, 0.5, 1.0, 1000.0), f32::INFINITY);
        let mesh = Mesh {
            name: "m".into(),
            lods: errors
                .iter()
                .map(|&error| Lod {
                    error,
                    ..Lod::default()
                })
                .collect(),
        };
        assert_eq!(mesh.lod_count(), 3);
        assert_eq!(mesh.lod(2).map(|l| l.error), Some(0.02));
        assert!(mesh.lod(3).is_none());
        assert_eq!(
            mesh.select_lod(1.0, 10.0, std::f32::consts::FRAC_PI_2, 1000.0),
            1
        );
        assert_eq!(
            mesh.select_lod(1.0, 25.0, std::f32::consts::FRAC_PI_2, 1000.0),
            2
        );
    }
}
