//! The MS3D byte layout, read into plain structs without interpretation.
//!
//! Every count is checked against the bytes that remain before anything is allocated, and every error
//! names the block and the byte offset where it was found.

use crate::ImportError;

/// Size of the fixed header (`"MS3D000000"` and the version).
pub const HEADER_SIZE: usize = 14;
/// Size of one vertex record.
pub const VERTEX_SIZE: usize = 15;
/// Size of one triangle record.
pub const TRIANGLE_SIZE: usize = 70;
/// Size of one material record.
pub const MATERIAL_SIZE: usize = 361;
/// Size of the fixed part of a joint record (before its keys).
pub const JOINT_SIZE: usize = 93;
/// Size of one rotation or position key.
pub const KEY_SIZE: usize = 16;

/// One vertex as stored.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vertex {
    /// Editor flags.
    pub flags: u8,
    /// Bind-pose position, model space.
    pub position: [f32; 3],
    /// Joint index (file order) or -1.
    pub bone_id: i8,
    /// Reference count as written by the editor.
    pub reference_count: u8,
}

/// One triangle as stored: corner vertex indices, per-corner normals and texture coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangle {
    /// Editor flags.
    pub flags: u16,
    /// Vertex indices of the three corners.
    pub vertices: [u16; 3],
    /// Per-corner normals.
    pub normals: [[f32; 3]; 3],
    /// Per-corner s coordinates.
    pub s: [f32; 3],
    /// Per-corner t coordinates (as stored, not flipped).
    pub t: [f32; 3],
    /// Smoothing group.
    pub smoothing_group: u8,
    /// Group index as stored (the groups' triangle lists are authoritative).
    pub group: u8,
}

/// A group (submesh).
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    /// Editor flags.
    pub flags: u8,
    /// Group name.
    pub name: String,
    /// Triangle indices.
    pub triangles: Vec<u16>,
    /// Material index or -1.
    pub material: i8,
}

/// A material record.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Material name.
    pub name: String,
    /// Ambient RGBA.
    pub ambient: [f32; 4],
    /// Diffuse RGBA.
    pub diffuse: [f32; 4],
    /// Specular RGBA.
    pub specular: [f32; 4],
    /// Emissive RGBA.
    pub emissive: [f32; 4],
    /// Shininess 0..128.
    pub shininess: f32,
    /// Opacity 0..1 (1 = opaque).
    pub transparency: f32,
    /// Mode byte.
    pub mode: i8,
    /// Texture path as written.
    pub texture: String,
    /// Alpha map path as written.
    pub alphamap: String,
}

/// A rotation (Euler radians) or position key.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Key {
    /// Time, seconds.
    pub time: f32,
    /// Euler angles (x, y, z) or a position.
    pub value: [f32; 3],
}

/// A joint with its keys.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Editor flags.
    pub flags: u8,
    /// Joint name.
    pub name: String,
    /// Parent name; empty for a root.
    pub parent: String,
    /// Bind rotation, Euler (x, y, z) radians, `Rz * Ry * Rx`.
    pub rotation: [f32; 3],
    /// Bind position in the parent's space.
    pub position: [f32; 3],
    /// Rotation keys, as stored.
    pub rotation_keys: Vec<Key>,
    /// Position keys, as stored.
    pub position_keys: Vec<Key>,
    /// Byte offset of the joint record.
    pub offset: usize,
}

/// A comment attached to a group, material or joint by index.
#[derive(Debug, Clone, PartialEq)]
pub struct Comment {
    /// Index of the commented item.
    pub index: i32,
    /// Text.
    pub text: String,
}

/// The comment block.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Comments {
    /// Block sub-version (1).
    pub sub_version: i32,
    /// Group comments.
    pub groups: Vec<Comment>,
    /// Material comments.
    pub materials: Vec<Comment>,
    /// Joint comments.
    pub joints: Vec<Comment>,
    /// The model comment, if present.
    pub model: Option<String>,
}

/// The vertex extra block: up to three more joints per vertex and their weights.
#[derive(Debug, Clone, PartialEq)]
pub struct VertexExtra {
    /// Sub-version 1 (6-byte records, weights 0..255), 2 (10 bytes, 0..100) or 3 (14 bytes, 0..100).
    pub sub_version: i32,
    /// Per vertex: `boneIds[3]`.
    pub bone_ids: Vec<[i8; 3]>,
    /// Per vertex: `weights[3]`.
    pub weights: Vec<[u8; 3]>,
    /// Per vertex: the `extra` words (none at sub-version 1, one at 2, two at 3).
    pub extra: Vec<[u32; 2]>,
}

impl VertexExtra {
    /// The value a full weight is stored as: 255 at sub-version 1, 100 otherwise.
    pub fn weight_scale(&self) -> f32 {
        if self.sub_version == 1 {
            255.0
        } else {
            100.0
        }
    }
}

/// The model extra block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelExtra {
    /// Block sub-version.
    pub sub_version: i32,
    /// Joint display size.
    pub joint_size: f32,
    /// Transparency mode.
    pub transparency_mode: i32,
    /// Alpha reference.
    pub alpha_ref: f32,
}

/// A whole MS3D file as stored.
#[derive(Debug, Clone, PartialEq)]
pub struct File {
    /// Format version (3 or 4).
    pub version: i32,
    /// Vertices.
    pub vertices: Vec<Vertex>,
    /// Triangles.
    pub triangles: Vec<Triangle>,
    /// Groups.
    pub groups: Vec<Group>,
    /// Materials.
    pub materials: Vec<Material>,
    /// Keyframer: frames per second.
    pub animation_fps: f32,
    /// Keyframer: the editor's current time.
    pub current_time: f32,
    /// Keyframer: number of frames on the timeline.
    pub total_frames: i32,
    /// Joints in file order.
    pub joints: Vec<Joint>,
    /// The comment block, if present.
    pub comments: Option<Comments>,
    /// The vertex extra block, if present.
    pub vertex_extra: Option<VertexExtra>,
    /// The joint extra block (sub-version, per-joint colour), if present.
    pub joint_extra: Option<(i32, Vec<[f32; 3]>)>,
    /// The model extra block, if present.
    pub model_extra: Option<ModelExtra>,
    /// Bytes after the last block that was understood, and where they start.
    pub trailing: Option<(usize, usize)>,
}

struct Reader<'a> {
    file: &'a str,
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }
    fn err(&self, section: &str, offset: usize, message: impl Into<String>) -> ImportError {
        ImportError::at_offset(self.file, section, offset as u64, message)
    }
    fn take(&mut self, section: &str, n: usize) -> Result<&'a [u8], ImportError> {
        if self.remaining() < n {
            return Err(self.err(
                section,
                self.pos,
                format!("file ends: {} bytes needed, {} left", n, self.remaining()),
            ));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn array<const N: usize>(&mut self, section: &str) -> Result<[u8; N], ImportError> {
        let s = self.take(section, N)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }
    fn u8(&mut self, section: &str) -> Result<u8, ImportError> {
        Ok(self.array::<1>(section)?[0])
    }
    fn i8(&mut self, section: &str) -> Result<i8, ImportError> {
        Ok(self.array::<1>(section)?[0] as i8)
    }
    fn u16(&mut self, section: &str) -> Result<u16, ImportError> {
        Ok(u16::from_le_bytes(self.array(section)?))
    }
    fn i32(&mut self, section: &str) -> Result<i32, ImportError> {
        Ok(i32::from_le_bytes(self.array(section)?))
    }
    fn u32(&mut self, section: &str) -> Result<u32, ImportError> {
        Ok(u32::from_le_bytes(self.array(section)?))
    }
    fn f32(&mut self, section: &str) -> Result<f32, ImportError> {
        Ok(f32::from_le_bytes(self.array(section)?))
    }
    fn vec3(&mut self, section: &str) -> Result<[f32; 3], ImportError> {
        Ok([self.f32(section)?, self.f32(section)?, self.f32(section)?])
    }
    fn vec4(&mut self, section: &str) -> Result<[f32; 4], ImportError> {
        Ok([
            self.f32(section)?,
            self.f32(section)?,
            self.f32(section)?,
            self.f32(section)?,
        ])
    }
    fn string(&mut self, section: &str, n: usize) -> Result<String, ImportError> {
        Ok(latin1(self.take(section, n)?))
    }
    /// Checks that `count` records of `size` bytes fit in what remains, before allocating them.
    fn check_count(
        &self,
        section: &str,
        count: usize,
        size: usize,
        what: &str,
    ) -> Result<(), ImportError> {
        let need = count.saturating_mul(size);
        if need > self.remaining() {
            return Err(self.err(
                section,
                self.pos,
                format!(
                    "{count} {what} need {need} bytes, only {} left in the file",
                    self.remaining()
                ),
            ));
        }
        Ok(())
    }
}

/// Decodes a NUL-padded string; bytes are read as Latin-1 so that every name survives unchanged.
fn latin1(bytes: &[u8]) -> String {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    bytes[..end].iter().map(|&b| b as char).collect()
}

/// Reads an MS3D file's blocks without interpreting them.
pub fn parse(file_name: &str, bytes: &[u8]) -> Result<File, ImportError> {
    let mut r = Reader {
        file: file_name,
        bytes,
        pos: 0,
    };
    let id = r.take("header", 10)?;
    if id != b"MS3D000000" {
        return Err(r.err("header", 0, "not an MS3D file (id is not \"MS3D000000\")"));
    }
    let version = r.i32("header")?;
    if version != 3 && version != 4 {
        return Err(r.err(
            "header",
            10,
            format!("unsupported version {version} (3 and 4 are read)"),
        ));
    }

    let n = r.u16("vertices")? as usize;
    r.check_count("vertices", n, VERTEX_SIZE, "vertices")?;
    let mut vertices = Vec::with_capacity(n);
    for _ in 0..n {
        vertices.push(Vertex {
            flags: r.u8("vertices")?,
            position: r.vec3("vertices")?,
            bone_id: r.i8("vertices")?,
            reference_count: r.u8("vertices")?,
        });
    }

    let n = r.u16("triangles")? as usize;
    r.check_count("triangles", n, TRIANGLE_SIZE, "triangles")?;
    let mut triangles = Vec::with_capacity(n);
    for _ in 0..n {
        let flags = r.u16("triangles")?;
        let v = [
            r.u16("triangles")?,
            r.u16("triangles")?,
            r.u16("triangles")?,
        ];
        let normals = [
            r.vec3("triangles")?,
            r.vec3("triangles")?,
            r.vec3("triangles")?,
        ];
        let s = r.vec3("triangles")?;
        let t = r.vec3("triangles")?;
        triangles.push(Triangle {
            flags,
            vertices: v,
            normals,
            s,
            t,
            smoothing_group: r.u8("triangles")?,
            group: r.u8("triangles")?,
        });
    }

    let n = r.u16("groups")? as usize;
    // Smallest group: flags, name, count, material = 36 bytes.
    r.check_count("groups", n, 36, "groups")?;
    let mut groups = Vec::with_capacity(n);
    for _ in 0..n {
        let flags = r.u8("groups")?;
        let name = r.string("groups", 32)?;
        let k = r.u16("groups")? as usize;
        r.check_count("groups", k, 2, "triangle indices")?;
        let mut tris = Vec::with_capacity(k);
        for _ in 0..k {
            tris.push(r.u16("groups")?);
        }
        groups.push(Group {
            flags,
            name,
            triangles: tris,
            material: r.i8("groups")?,
        });
    }

    let n = r.u16("materials")? as usize;
    r.check_count("materials", n, MATERIAL_SIZE, "materials")?;
    let mut materials = Vec::with_capacity(n);
    for _ in 0..n {
        let s = "materials";
        materials.push(Material {
            name: r.string(s, 32)?,
            ambient: r.vec4(s)?,
            diffuse: r.vec4(s)?,
            specular: r.vec4(s)?,
            emissive: r.vec4(s)?,
            shininess: r.f32(s)?,
            transparency: r.f32(s)?,
            mode: r.i8(s)?,
            texture: r.string(s, 128)?,
            alphamap: r.string(s, 128)?,
        });
    }

    let animation_fps = r.f32("keyframer")?;
    let current_time = r.f32("keyframer")?;
    let total_frames = r.i32("keyframer")?;

    let n = r.u16("joints")? as usize;
    r.check_count("joints", n, JOINT_SIZE, "joints")?;
    let mut joints = Vec::with_capacity(n);
    for _ in 0..n {
        let s = "joints";
        let offset = r.pos;
        let flags = r.u8(s)?;
        let name = r.string(s, 32)?;
        let parent = r.string(s, 32)?;
        let rotation = r.vec3(s)?;
        let position = r.vec3(s)?;
        let nr = r.u16(s)? as usize;
        let np = r.u16(s)? as usize;
        r.check_count(
            s,
            nr + np,
            KEY_SIZE,
            &format!("keys of joint {name:?} ({nr} rotation, {np} position)"),
        )?;
        let mut keys = |n: usize| -> Result<Vec<Key>, ImportError> {
            let mut v = Vec::with_capacity(n);
            for _ in 0..n {
                v.push(Key {
                    time: r.f32(s)?,
                    value: r.vec3(s)?,
                });
            }
            Ok(v)
        };
        let rotation_keys = keys(nr)?;
        let position_keys = keys(np)?;
        joints.push(Joint {
            flags,
            name,
            parent,
            rotation,
            position,
            rotation_keys,
            position_keys,
            offset,
        });
    }

    let mut file = File {
        version,
        vertices,
        triangles,
        groups,
        materials,
        animation_fps,
        current_time,
        total_frames,
        joints,
        comments: None,
        vertex_extra: None,
        joint_extra: None,
        model_extra: None,
        trailing: None,
    };
    if r.remaining() == 0 {
        return Ok(file);
    }

    // Comments.
    let s = "comments";
    let at = r.pos;
    let sub_version = r.i32(s)?;
    if sub_version != 1 {
        return Err(r.err(
            s,
            at,
            format!("unknown comment block subVersion {sub_version} (1 is read)"),
        ));
    }
    let mut comments = Comments {
        sub_version,
        ..Comments::default()
    };
    for what in ["group", "material", "joint"] {
        let count = r.u32(s)? as usize;
        r.check_count(s, count, 8, &format!("{what} comments"))?;
        let mut list = Vec::with_capacity(count);
        for _ in 0..count {
            let index = r.i32(s)?;
            let len_at = r.pos;
            let len = r.i32(s)?;
            if len < 0 {
                return Err(r.err(s, len_at, format!("negative comment length {len}")));
            }
            let text = r.string(s, len as usize)?;
            list.push(Comment { index, text });
        }
        match what {
            "group" => comments.groups = list,
            "material" => comments.materials = list,
            _ => comments.joints = list,
        }
    }
    // The model comment has no index field (see docs/formats/ms3d.md: ninja.ms3d).
    let has_model = r.i32(s)?;
    if has_model != 0 {
        let len_at = r.pos;
        let len = r.i32(s)?;
        if len < 0 {
            return Err(r.err(s, len_at, format!("negative model comment length {len}")));
        }
        comments.model = Some(r.string(s, len as usize)?);
    }
    file.comments = Some(comments);
    if r.remaining() == 0 {
        return Ok(file);
    }

    // Vertex extra.
    let s = "vertex extra";
    let at = r.pos;
    let sub_version = r.i32(s)?;
    let size = match sub_version {
        1 => 6,
        2 => 10,
        3 => 14,
        _ => {
            return Err(r.err(
                s,
                at,
                format!("unknown vertex extra subVersion {sub_version} (1, 2 and 3 are read)"),
            ))
        }
    };
    let n = file.vertices.len();
    r.check_count(s, n, size, "vertex extra records")?;
    let mut extra = VertexExtra {
        sub_version,
        bone_ids: Vec::with_capacity(n),
        weights: Vec::with_capacity(n),
        extra: Vec::with_capacity(n),
    };
    for _ in 0..n {
        extra.bone_ids.push([r.i8(s)?, r.i8(s)?, r.i8(s)?]);
        extra.weights.push([r.u8(s)?, r.u8(s)?, r.u8(s)?]);
        let mut words = [0u32; 2];
        for w in words.iter_mut().take((size - 6) / 4) {
            *w = r.u32(s)?;
        }
        extra.extra.push(words);
    }
    file.vertex_extra = Some(extra);
    if r.remaining() == 0 {
        return Ok(file);
    }

    // Joint extra.
    let s = "joint extra";
    let at = r.pos;
    let sub_version = r.i32(s)?;
    if sub_version != 1 && sub_version != 2 {
        // Unknown layout: stop here and report the rest as trailing bytes.
        r.pos = at;
        file.trailing = Some((at, r.remaining()));
        return Ok(file);
    }
    let n = file.joints.len();
    r.check_count(s, n, 12, "joint colours")?;
    let mut colors = Vec::with_capacity(n);
    for _ in 0..n {
        colors.push(r.vec3(s)?);
    }
    file.joint_extra = Some((sub_version, colors));
    if r.remaining() == 0 {
        return Ok(file);
    }

    // Model extra.
    let s = "model extra";
    let at = r.pos;
    let sub_version = r.i32(s)?;
    if sub_version != 1 && sub_version != 2 {
        r.pos = at;
        file.trailing = Some((at, r.remaining()));
        return Ok(file);
    }
    file.model_extra = Some(ModelExtra {
        sub_version,
        joint_size: r.f32(s)?,
        transparency_mode: r.i32(s)?,
        alpha_ref: r.f32(s)?,
    });
    if r.remaining() > 0 {
        file.trailing = Some((r.pos, r.remaining()));
    }
    Ok(file)
}
