//! glTF extensions the importer reads (KHR_mesh_quantization, KHR_texture_transform) and the ones it
//! refuses by name, on small documents written here (every value known).
#![allow(clippy::unwrap_used)]

use sinew_core::glam::{Vec2, Vec3};
use sinew_import::{gltf, ImportOptions, Location};
use sinew_testdata::gltf_doc::{doc_with_buffer, f32_bytes, no_resolve};

fn u16s(v: &[u16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// One triangle, its attributes quantized as gltfpack writes them (KHR_mesh_quantization): u16
/// positions (stride 8) that the node's translation and scale map back, i8 normalized normals
/// (stride 4) and u16 normalized texture coordinates that the base colour texture's
/// KHR_texture_transform maps back.
fn quantized_triangle(required: &str) -> Vec<u8> {
    let mut buf = u16s(&[0, 0, 0, 0, 1000, 0, 0, 0, 0, 2000, 500, 0]);
    for n in [[0i8, 0, 127, 0], [0, 127, 0, 0], [90, 0, 90, 0]] {
        buf.extend(n.map(|x| x as u8));
    }
    buf.extend(u16s(&[0, 0, 65535, 0, 0, 32768]));
    let json = format!(
        r#""extensionsUsed":["KHR_mesh_quantization","KHR_texture_transform"],
        "extensionsRequired":{required},
        "scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"mesh":0,"translation":[1,-2,0.5],"scale":[0.001,0.001,0.001]}}],
        "bufferViews":[{{"buffer":0,"byteLength":24,"byteStride":8}},{{"buffer":0,"byteOffset":24,"byteLength":12,"byteStride":4}},{{"buffer":0,"byteOffset":36,"byteLength":12,"byteStride":4}}],
        "accessors":[{{"bufferView":0,"componentType":5123,"count":3,"type":"VEC3","min":[0,0,0],"max":[1000,2000,500]}},
          {{"bufferView":1,"componentType":5120,"normalized":true,"count":3,"type":"VEC3"}},
          {{"bufferView":2,"componentType":5123,"normalized":true,"count":3,"type":"VEC2"}}],
        "images":[{{"uri":"skin.png"}}],"textures":[{{"source":0}}],
        "materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0,"extensions":{{"KHR_texture_transform":{{"offset":[0.25,0.5],"scale":[2,4]}}}}}}}}}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2}},"material":0}}]}}]"#
    );
    doc_with_buffer(&buf, &json)
}

fn close2(a: Vec2, b: Vec2) -> bool {
    (a - b).abs().max_element() < 1e-6
}

#[test]
fn quantized_attributes_are_read_back_to_model_units() {
    let doc = quantized_triangle(r#"["KHR_mesh_quantization"]"#);
    let s = gltf::import(
        "quantized.gltf",
        &doc,
        &no_resolve,
        &ImportOptions::default(),
    )
    .unwrap();
    let g = &s.meshes[0].geometry;
    assert_eq!(g.triangle_count(), 1);
    // translation + scale * q, per vertex.
    let expected = [
        Vec3::new(1.0, -2.0, 0.5),
        Vec3::new(2.0, -2.0, 0.5),
        Vec3::new(1.0, 0.0, 1.0),
    ];
    for (p, e) in g.positions.iter().zip(expected) {
        assert!((*p - e).length() < 1e-6, "{p} against {e}");
    }
    // i8 normalized: q / 127, then unit length.
    assert!((g.normals[0] - Vec3::Z).length() < 1e-6, "{}", g.normals[0]);
    assert!((g.normals[1] - Vec3::Y).length() < 1e-6, "{}", g.normals[1]);
    let diagonal = Vec3::new(1.0, 0.0, 1.0).normalize();
    assert!(
        (g.normals[2] - diagonal).length() < 1e-6,
        "{}",
        g.normals[2]
    );
    // offset + scale * (q / 65535).
    let uv = |u: f32, v: f32| Vec2::new(0.25 + 2.0 * u, 0.5 + 4.0 * v);
    for (got, want) in g
        .uvs
        .iter()
        .zip([uv(0.0, 0.0), uv(1.0, 0.0), uv(0.0, 32768.0 / 65535.0)])
    {
        assert!(close2(*got, want), "{got} against {want}");
    }
}

#[test]
fn the_same_file_without_extensions_required_reads_the_same() {
    let with = quantized_triangle(r#"["KHR_mesh_quantization"]"#);
    let without = quantized_triangle("[]");
    let a = gltf::import("a.gltf", &with, &no_resolve, &ImportOptions::default()).unwrap();
    let b = gltf::import("b.gltf", &without, &no_resolve, &ImportOptions::default()).unwrap();
    assert_eq!(a.meshes[0].geometry, b.meshes[0].geometry);
}

#[test]
fn texture_transform_rotation_follows_the_extensions_example() {
    // KHR_texture_transform's example: offset (0, 1), rotation pi/2, scale 0.5 shows the lower left
    // quadrant of the image turned a quarter clockwise: UV (0, 0) -> (0, 1), (1, 0) -> (0, 0.5),
    // (0, 1) -> (0.5, 1).
    let mut buf = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    buf.extend(f32_bytes(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]));
    let json = r#""extensionsUsed":["KHR_texture_transform"],
        "bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":24}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
          {"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}],
        "images":[{"uri":"skin.png"}],"textures":[{"source":0}],
        "materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0,"extensions":{"KHR_texture_transform":{"offset":[0,1],"rotation":1.5707963267948966,"scale":[0.5,0.5]}}}}}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":1},"material":0}]}]"#;
    let doc = doc_with_buffer(&buf, json);
    let s = gltf::import("rotated.gltf", &doc, &no_resolve, &ImportOptions::default()).unwrap();
    let uvs = &s.meshes[0].geometry.uvs;
    for (got, want) in uvs.iter().zip([
        Vec2::new(0.0, 1.0),
        Vec2::new(0.0, 0.5),
        Vec2::new(0.5, 1.0),
    ]) {
        assert!(close2(*got, want), "{got} against {want}");
    }
}

#[test]
fn a_required_extension_not_read_is_named_before_what_it_explains() {
    // A Draco-compressed primitive: its accessors have no buffer view, which the crate's validation
    // reports too; the extension is the error that explains them.
    let doc = doc_with_buffer(
        &[0u8; 4],
        r#""extensionsUsed":["KHR_draco_mesh_compression"],"extensionsRequired":["KHR_draco_mesh_compression"],
        "accessors":[{"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,1]},{"componentType":5126,"count":3,"type":"VEC3"}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0,"NORMAL":1},"extensions":{"KHR_draco_mesh_compression":{"bufferView":0,"attributes":{"POSITION":0,"NORMAL":1}}}}]}]"#,
    );
    let e = gltf::import("draco.gltf", &doc, &no_resolve, &ImportOptions::default()).unwrap_err();
    assert_eq!(e.file, "draco.gltf");
    let Location::JsonPath(path) = &e.location else {
        panic!("{e}")
    };
    assert!(path.starts_with("extensionsRequired[0]"), "{e}");
    assert!(e.to_string().contains("KHR_draco_mesh_compression"), "{e}");
}

#[test]
fn a_gltf_1_file_is_named_as_such() {
    let doc = br#"{"asset":{"version":"1.0"},"scene":"defaultScene","scenes":{"defaultScene":{"nodes":[]}}}"#;
    let e = gltf::import("old.gltf", doc, &no_resolve, &ImportOptions::default()).unwrap_err();
    assert_eq!(
        e.location,
        Location::JsonPath("asset.version".into()),
        "{e}"
    );
    assert!(e.message.contains("glTF \"1.0\" is not supported"), "{e}");
}

/// A float triangle with two UV sets (set 0: all zeros; set 1: (0.1, 0.2), (0.3, 0.4),
/// (0.5, 0.6)) whose material's base colour texture has `texture_info` (JSON members).
fn two_uv_sets(texture_info: &str) -> Vec<u8> {
    let mut buf = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    buf.extend(f32_bytes(&[0.0; 6]));
    buf.extend(f32_bytes(&[0.1, 0.2, 0.3, 0.4, 0.5, 0.6]));
    let json = format!(
        r#""extensionsUsed":["KHR_texture_transform"],
        "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}},{{"buffer":0,"byteOffset":60,"byteLength":24}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
          {{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}},{{"bufferView":2,"componentType":5126,"count":3,"type":"VEC2"}}],
        "images":[{{"uri":"skin.png"}}],"textures":[{{"source":0}}],
        "materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0{texture_info}}}}}}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1,"TEXCOORD_1":2}},"material":0}}]}}]"#
    );
    doc_with_buffer(&buf, &json)
}

#[test]
fn the_uv_set_is_the_one_the_base_colour_texture_reads() {
    let set1 = [
        Vec2::new(0.1, 0.2),
        Vec2::new(0.3, 0.4),
        Vec2::new(0.5, 0.6),
    ];
    let read = |info: &str| {
        let doc = two_uv_sets(info);
        gltf::import("uv.gltf", &doc, &no_resolve, &ImportOptions::default()).unwrap()
    };
    // Set 0 by default, set 1 by `texCoord`, and by the texture transform's override.
    assert_eq!(read("").meshes[0].geometry.uvs, [Vec2::ZERO; 3]);
    assert_eq!(read(r#","texCoord":1"#).meshes[0].geometry.uvs, set1);
    let overridden = read(r#","extensions":{"KHR_texture_transform":{"texCoord":1}}"#);
    assert_eq!(overridden.meshes[0].geometry.uvs, set1);
    // A set the primitive does not have: set 0, with a warning.
    let missing = read(r#","texCoord":3"#);
    assert_eq!(missing.meshes[0].geometry.uvs, [Vec2::ZERO; 3]);
    assert!(missing
        .diagnostics
        .iter()
        .any(|d| d.code == "gltf-texcoord-missing" && d.message.contains("TEXCOORD_3")));
}
