//! The studio model: a Half-Life model as studiomdl compiles it and an MDL file holds it, in plain
//! structures. Both readers produce it — the MDL reader from the compiled file, the QC compiler from a
//! QC and its SMD files — and one builder turns it into a sinew scene, so the two paths agree by
//! construction wherever their studio models agree.

/// A bone: parent and default (bind) values, parent-relative.
#[derive(Debug, Clone, PartialEq)]
pub struct StudioBone {
    /// Name as written (may be empty in damaged files; the builder makes names unique).
    pub name: String,
    /// Parent bone, always an earlier bone.
    pub parent: Option<usize>,
    /// Position x, y, z and Euler rotation x, y, z (radians; the rotation is `Rz * Ry * Rx`).
    pub value: [f32; 6],
}

/// One vertex of a submodel: bind-pose model-space position and its joint influences.
#[derive(Debug, Clone, PartialEq)]
pub struct StudioVertex {
    /// Model-space position in the bind pose.
    pub position: [f32; 3],
    /// Up to four (bone, weight) pairs with weights summing to 1; GoldSrc has exactly one.
    pub influences: Vec<(usize, f32)>,
}

/// One corner of a triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Corner {
    /// Index into the submodel's vertices.
    pub vertex: usize,
    /// Model-space normal in the bind pose.
    pub normal: [f32; 3],
    /// Texture coordinate, origin at the top left (u right, v down), in texture sizes.
    pub uv: [f32; 2],
}

/// Triangles that share one skin slot.
#[derive(Debug, Clone, PartialEq)]
pub struct StudioMesh {
    /// Skin slot (index into a skin family's row).
    pub skin_slot: usize,
    /// Triangles, corners in counter-clockwise order seen from the front.
    pub triangles: Vec<[Corner; 3]>,
}

/// One choice of a body part.
#[derive(Debug, Clone, PartialEq)]
pub struct Submodel {
    /// Name (the reference SMD's file stem; `blank` choices have no vertices).
    pub name: String,
    /// Vertices.
    pub vertices: Vec<StudioVertex>,
    /// Meshes, one per skin slot used.
    pub meshes: Vec<StudioMesh>,
}

/// A set of interchangeable submodels; the first is the default.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyPart {
    /// Name.
    pub name: String,
    /// Choices.
    pub submodels: Vec<Submodel>,
}

/// An 8-bit indexed texture with its palette.
#[derive(Debug, Clone, PartialEq)]
pub struct StudioTexture {
    /// Name as written (e.g. `skin.bmp`).
    pub name: String,
    /// Flags (`sinew_core::format::game::material_flags`).
    pub flags: u32,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The pixels as palette indices, rows from the top; empty when the image is not available
    /// (a QC names texture files that sinew does not read).
    pub indices: Vec<u8>,
    /// 256 RGB entries (768 bytes), or empty with `indices`.
    pub palette: Vec<u8>,
}

/// A sequence: frames of every bone, per blend.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StudioSequence {
    /// Label.
    pub label: String,
    /// Frames per second.
    pub fps: f32,
    /// Whether the sequence loops (its last frame repeats its first).
    pub looping: bool,
    /// Activity number and weight.
    pub activity: (i32, i32),
    /// Events: (frame, event, type, options).
    pub events: Vec<(i32, i32, i32, String)>,
    /// Motion extraction flags and bone.
    pub motion_type: u32,
    /// Bone whose motion was extracted.
    pub motion_bone: usize,
    /// Extracted linear movement.
    pub linear_movement: [f32; 3],
    /// Blend control types, starts and ends.
    pub blend_type: [u32; 2],
    /// Blend starts.
    pub blend_start: [f32; 2],
    /// Blend ends.
    pub blend_end: [f32; 2],
    /// Transition graph entry node, exit node, node flags.
    pub nodes: (i32, i32, i32),
    /// Per blend, per frame, per bone: the six values (position, Euler rotation). Empty when the
    /// animation data is missing (a companion file that is not there).
    pub blends: Vec<Vec<Vec<[f32; 6]>>>,
}

/// A bone controller.
#[derive(Debug, Clone, PartialEq)]
pub struct StudioController {
    /// Bone.
    pub bone: usize,
    /// Channel flags.
    pub channel: u32,
    /// Range start.
    pub start: f32,
    /// Range end.
    pub end: f32,
    /// Rest value.
    pub rest: i32,
    /// Controller number.
    pub index: i32,
}

/// A whole studio model.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StudioModel {
    /// Bones, parents first.
    pub bones: Vec<StudioBone>,
    /// Body parts.
    pub body_parts: Vec<BodyPart>,
    /// Textures.
    pub textures: Vec<StudioTexture>,
    /// Skin families: per family, the texture index of each skin slot.
    pub skin_families: Vec<Vec<usize>>,
    /// Sequences.
    pub sequences: Vec<StudioSequence>,
    /// Bone controllers.
    pub controllers: Vec<StudioController>,
    /// Hit boxes: (bone, group, min, max).
    pub hitboxes: Vec<(usize, i32, [f32; 3], [f32; 3])>,
    /// Attachments: (name, bone, offset).
    pub attachments: Vec<(String, usize, [f32; 3])>,
    /// Eye position.
    pub eye_position: Option<[f32; 3]>,
    /// Transition graph, `nodes x nodes`.
    pub transitions: Vec<u8>,
    /// Number of transition nodes.
    pub transition_nodes: u32,
}
