//! Valid glTF 2.0 that gltf-json 1.4.1 refuses, made readable before it deserializes and validates
//! the document: a scene without `nodes` (optional in the specification, a required field for the
//! crate), an animation channel whose target names no node (KHR_animation_pointer's channels,
//! which the specification allows; the crate requires `node`; such channels are skipped), and
//! required extensions that only supply textures in formats sinew does not decode
//! (KHR_texture_basisu, EXT_texture_webp, EXT_texture_avif): their textures are left out, as is
//! any texture without an image sinew reads.
//! Each change to the document comes with a warning; docs/formats/gltf.md lists them. The Khronos
//! glTF-Validator's own test files are where these were found (docs/formats/gltf.md, session 28).

use serde_json::Value;
use sinew_scene::Diagnostic;

/// Required extensions that only say where a texture's image is (in a format sinew does not
/// decode): the file is read without those textures.
pub(super) const TEXTURE_ONLY: [&str; 3] =
    ["KHR_texture_basisu", "EXT_texture_webp", "EXT_texture_avif"];

/// What [`tolerate`] did to the document.
#[derive(Default)]
pub(super) struct Tolerated {
    /// True when the JSON values changed (the caller serializes them again for the crate).
    pub(super) changed: bool,
    pub(super) warnings: Vec<Diagnostic>,
}

/// Adds `"nodes": []` to scenes without it (and says so when the scene read lists no nodes),
/// removes the animation channels whose target names no node, and reports the texture-only
/// required extensions and the textures without a core image (which the crate reads as textures
/// without a source, [`gltf::texture::Texture::source`]).
pub(super) fn tolerate(root: &mut Value) -> Tolerated {
    let mut out = Tolerated::default();
    let Some(root) = root.as_object_mut() else {
        return out;
    };
    // The scene sinew reads (`scene`, else the first): one that lists no nodes would give nothing,
    // so every root node is read instead (mesh.rs), and said.
    let used = root.get("scene").and_then(Value::as_u64).unwrap_or(0);
    let empty = root
        .get("scenes")
        .and_then(|s| s.get(usize::try_from(used).ok()?))
        .is_some_and(|s| {
            s.get("nodes")
                .and_then(Value::as_array)
                .is_none_or(Vec::is_empty)
        });
    if empty {
        out.warnings.push(Diagnostic::warning(
            "gltf-empty-scene",
            format!("scenes[{used}] lists no nodes: every root node is read instead"),
        ));
    }
    if let Some(Value::Array(scenes)) = root.get_mut("scenes") {
        for scene in scenes.iter_mut().filter_map(Value::as_object_mut) {
            if !scene.contains_key("nodes") {
                scene.insert("nodes".into(), Value::Array(Vec::new()));
                out.changed = true;
            }
        }
    }
    let mut skipped = Vec::new();
    if let Some(Value::Array(animations)) = root.get_mut("animations") {
        for (a, animation) in animations.iter_mut().enumerate() {
            let Some(Value::Array(channels)) = animation.get_mut("channels") else {
                continue;
            };
            let mut c = 0;
            channels.retain(|channel| {
                let keep = channel
                    .get("target")
                    .is_none_or(|t| t.get("node").is_some());
                if !keep {
                    skipped.push(format!("animations[{a}].channels[{c}]"));
                }
                c += 1;
                keep
            });
        }
    }
    if !skipped.is_empty() {
        out.changed = true;
        out.warnings.push(
            Diagnostic::warning(
                "gltf-channel-without-node",
                format!(
                    "{} {} no node (an extension's target, such as KHR_animation_pointer's): skipped",
                    skipped.join(", "),
                    if skipped.len() == 1 { "targets" } else { "target" }
                ),
            )
            .with_figure("channels", skipped.len() as f64),
        );
    }
    let unread: Vec<String> = match root.get("extensionsRequired") {
        Some(Value::Array(required)) => required
            .iter()
            .filter_map(Value::as_str)
            .filter(|e| TEXTURE_ONLY.contains(e))
            .map(str::to_owned)
            .collect(),
        _ => Vec::new(),
    };
    if !unread.is_empty() {
        out.warnings.push(Diagnostic::warning(
            "gltf-texture-format-unread",
            format!(
                "the file requires {}, which only give{} textures in formats sinew does not decode: \
                 read without those textures",
                unread.join(", "),
                if unread.len() == 1 { "s" } else { "" }
            ),
        ));
    }
    let sourceless: Vec<String> = match root.get("textures") {
        Some(Value::Array(textures)) => textures
            .iter()
            .enumerate()
            .filter(|(_, t)| t.get("source").is_none())
            .map(|(i, _)| format!("textures[{i}]"))
            .collect(),
        _ => Vec::new(),
    };
    if !sourceless.is_empty() {
        out.warnings.push(
            Diagnostic::warning(
                "gltf-texture-without-image",
                format!(
                    "{} {} no image sinew reads (no `source`; an extension may give one in another \
                     format): the materials using {} keep no texture",
                    sourceless.join(", "),
                    if sourceless.len() == 1 { "has" } else { "have" },
                    if sourceless.len() == 1 { "it" } else { "them" }
                ),
            )
            .with_figure("textures", sourceless.len() as f64),
        );
    }
    out
}
