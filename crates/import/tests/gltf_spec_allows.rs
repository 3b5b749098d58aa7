//! Valid glTF 2.0 that the gltf crate refuses, read (crates/import/src/gltf/tolerate.rs and
//! `validated` in document.rs): found by running the Khronos glTF-Validator's own test files,
//! where sinew refused files the validator reports no error in. Small documents written here,
//! every value known.
#![allow(clippy::unwrap_used)]

use sinew_core::glam::{Vec2, Vec3};
use sinew_import::{gltf, ImportOptions};
use sinew_scene::Scene;
use sinew_testdata::gltf_doc::{doc_with_buffer, f32_bytes, no_resolve};

/// One triangle's positions (36 bytes) then, for animations, key times 0 and 1 and two
/// translations.
fn buffer() -> Vec<u8> {
    let mut b = f32_bytes(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 2.0, 0.0]);
    b.extend(f32_bytes(&[0.0, 1.0]));
    b.extend(f32_bytes(&[0.0, 0.0, 0.0, 3.0, 4.0, 5.0]));
    b
}

const VIEWS_AND_POSITIONS: &str = r#""bufferViews":[{"buffer":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":8},{"buffer":0,"byteOffset":44,"byteLength":24}],
    "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,2,0]},
      {"bufferView":1,"componentType":5126,"count":2,"type":"SCALAR","min":[0],"max":[1]},
      {"bufferView":2,"componentType":5126,"count":2,"type":"VEC3"},
      {"componentType":5126,"count":3,"type":"VEC2"}]"#;

fn import(rest: &str) -> Scene {
    let doc = doc_with_buffer(&buffer(), &format!("{VIEWS_AND_POSITIONS},{rest}"));
    gltf::import("allowed.gltf", &doc, &no_resolve, &ImportOptions::default()).unwrap()
}

fn warnings<'a>(s: &'a Scene, code: &str) -> Vec<&'a str> {
    s.diagnostics
        .iter()
        .filter(|d| d.code == code)
        .map(|d| d.message.as_str())
        .collect()
}

fn positions_are_the_triangle(s: &Scene) {
    let g = &s.meshes[0].geometry;
    assert_eq!(g.triangle_count(), 1);
    assert_eq!(g.positions, [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 2.0, 0.0)]);
}

#[test]
fn an_accessor_without_a_buffer_view_reads_as_zeros() {
    // accessors[3]: no bufferView and no sparse, which the specification defines as all zeros.
    let s = import(
        r#""images":[{"uri":"skin.png"}],"textures":[{"source":0}],
        "materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":3},"material":0}]}]"#,
    );
    positions_are_the_triangle(&s);
    assert_eq!(s.meshes[0].geometry.uvs, [Vec2::ZERO; 3]);
    assert_eq!(s.materials[0].texture.as_deref(), Some("skin.png"));
}

#[test]
fn a_primitive_without_position_is_skipped_and_the_others_read() {
    let s = import(
        r#""meshes":[{"primitives":[{"attributes":{"TEXCOORD_0":3}},{"attributes":{"POSITION":0}}]}]"#,
    );
    positions_are_the_triangle(&s);
    let w = warnings(&s, "gltf-primitive-skipped");
    assert_eq!(
        w,
        ["meshes[0].primitives[0] has no POSITION attribute; skipped"]
    );
}

#[test]
fn a_scene_without_nodes_reads_every_root_node() {
    // `scenes[0].nodes` is optional; a scene that lists none would give nothing to convert.
    let s = import(
        r#""scene":0,"scenes":[{"name":"empty"}],"nodes":[{"mesh":0}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]"#,
    );
    positions_are_the_triangle(&s);
    assert_eq!(
        warnings(&s, "gltf-empty-scene"),
        ["scenes[0] lists no nodes: every root node is read instead"]
    );
    // A scene that lists the node: no warning, the same triangle.
    let s = import(
        r#""scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]"#,
    );
    positions_are_the_triangle(&s);
    assert!(warnings(&s, "gltf-empty-scene").is_empty());
}

#[test]
fn channels_that_target_no_node_are_skipped_and_the_others_read() {
    // channels[1] animates a node through KHR_animation_pointer (no `node`, path "pointer").
    let s = import(
        r#""extensionsUsed":["KHR_animation_pointer"],"nodes":[{"name":"a"}],
        "animations":[{"channels":[
            {"sampler":0,"target":{"node":0,"path":"translation"}},
            {"sampler":0,"target":{"path":"pointer","extensions":{"KHR_animation_pointer":{"pointer":"/nodes/0/translation"}}}},
            {"sampler":0,"target":{"node":0,"path":"scale"}}],
          "samplers":[{"input":1,"output":2}]}]"#,
    );
    let tracks = &s.clips[0].tracks;
    assert_eq!(tracks.len(), 1);
    assert_eq!(tracks[0].joint, "a");
    assert_eq!(tracks[0].translation.times, [0.0, 1.0]);
    assert_eq!(tracks[0].translation.values[1], Vec3::new(3.0, 4.0, 5.0));
    assert_eq!(tracks[0].scale.values[1], Vec3::new(3.0, 4.0, 5.0));
    let w = warnings(&s, "gltf-channel-without-node");
    assert_eq!(w.len(), 1, "{:?}", s.diagnostics);
    assert!(
        w[0].starts_with("animations[0].channels[1] targets no node"),
        "{}",
        w[0]
    );
}

const TEXTURED_TRIANGLE: &str = r#""meshes":[{"primitives":[{"attributes":{"POSITION":0,"TEXCOORD_0":3},"material":0}]}],
    "materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}]"#;

#[test]
fn textures_only_in_formats_sinew_does_not_decode_are_left_out() {
    for ext in ["EXT_texture_webp", "KHR_texture_basisu", "EXT_texture_avif"] {
        // Required: the texture has no core source, only the extension's image.
        let s = import(&format!(
            r#""extensionsUsed":["{ext}"],"extensionsRequired":["{ext}"],
            "images":[{{"uri":"skin.img"}}],"textures":[{{"extensions":{{"{ext}":{{"source":0}}}}}}],
            {TEXTURED_TRIANGLE}"#
        ));
        positions_are_the_triangle(&s);
        assert_eq!(s.materials[0].texture, None, "{ext}");
        let unread = warnings(&s, "gltf-texture-format-unread");
        assert_eq!(unread.len(), 1, "{ext}: {:?}", s.diagnostics);
        assert!(unread[0].contains(ext), "{}", unread[0]);
        assert_eq!(
            warnings(&s, "gltf-texture-without-image").len(),
            1,
            "{ext}: {:?}",
            s.diagnostics
        );
    }
    // Used but not required: the core source is the fallback sinew reads.
    let s = import(&format!(
        r#""extensionsUsed":["EXT_texture_webp"],
        "images":[{{"uri":"skin.webp"}},{{"uri":"skin.png"}}],
        "textures":[{{"source":1,"extensions":{{"EXT_texture_webp":{{"source":0}}}}}}],
        {TEXTURED_TRIANGLE}"#
    ));
    assert_eq!(s.materials[0].texture.as_deref(), Some("skin.png"));
    assert!(warnings(&s, "gltf-texture-without-image").is_empty());
    assert!(warnings(&s, "gltf-texture-format-unread").is_empty());
}

#[test]
fn what_the_specification_does_not_allow_is_still_refused() {
    // A required extension sinew does not read at all, and a channel whose path is unknown.
    let doc = doc_with_buffer(
        &buffer(),
        &format!(
            r#"{VIEWS_AND_POSITIONS},"extensionsRequired":["KHR_draco_mesh_compression"],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}]"#
        ),
    );
    let e = gltf::import("draco.gltf", &doc, &no_resolve, &ImportOptions::default()).unwrap_err();
    assert!(e.to_string().contains("extensionsRequired[0]"), "{e}");
    let doc = doc_with_buffer(
        &buffer(),
        &format!(
            r#"{VIEWS_AND_POSITIONS},"nodes":[{{"name":"a"}}],
            "animations":[{{"channels":[{{"sampler":0,"target":{{"node":0,"path":"pointer"}}}}],"samplers":[{{"input":1,"output":2}}]}}]"#
        ),
    );
    let e = gltf::import("path.gltf", &doc, &no_resolve, &ImportOptions::default()).unwrap_err();
    assert!(
        e.to_string()
            .contains("animations[0].channels[0].target.path"),
        "{e}"
    );
}
