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
