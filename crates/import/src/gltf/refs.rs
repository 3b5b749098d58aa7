//! Our own pass over a glTF document's JSON before the gltf crate validates it: every index the crate
//! follows while validating and walking, and every enumeration it unwraps, checked with errors that
//! name the JSON path. gltf-json 1.4.1 panics on some of these (an out-of-range POSITION accessor, an
//! animation target node or path) instead of reporting them; docs/reliability.md has the details.

use serde_json::Value;

/// A reference that points nowhere, or a value the crate cannot read: JSON path and message.
pub(super) type Problem = (String, String);

struct Counts {
    accessors: usize,
    buffer_views: usize,
    buffers: usize,
    nodes: usize,
    meshes: usize,
    skins: usize,
    materials: usize,
    textures: usize,
    images: usize,
    samplers: usize,
    cameras: usize,
    scenes: usize,
}

fn len(root: &Value, key: &str) -> usize {
    root.get(key).and_then(Value::as_array).map_or(0, Vec::len)
}

fn items<'a>(root: &'a Value, key: &str) -> impl Iterator<Item = (usize, &'a Value)> {
    root.get(key)
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .enumerate()
}

/// An index at `path`: absent is fine; otherwise a non-negative integer below `limit`.
fn index(
    v: Option<&Value>,
    path: impl Fn() -> String,
    what: &str,
    limit: usize,
) -> Result<(), Problem> {
    let Some(v) = v else { return Ok(()) };
    match v.as_u64() {
        Some(i) if (i as usize) < limit && i <= u64::from(u32::MAX) => Ok(()),
        Some(i) => Err((
            path(),
            format!("{what} index {i} is out of range (the file has {limit})"),
        )),
        None => Err((
            path(),
            format!("{what} index must be a non-negative integer"),
        )),
    }
}

/// A value at `path`, when present, must be one of `allowed`.
fn one_of(v: Option<&Value>, path: impl Fn() -> String, allowed: &[Value]) -> Result<(), Problem> {
    match v {
        Some(x) if !allowed.contains(x) => Err((path(), format!("{x} is not a valid value"))),
        _ => Ok(()),
    }
}

/// A texture reference object (`{ "index": n, ... }`).
fn texture_info(v: Option<&Value>, path: impl Fn() -> String, c: &Counts) -> Result<(), Problem> {
    if let Some(t) = v {
        index(
            t.get("index"),
            || format!("{}.index", path()),
            "texture",
            c.textures,
        )?;
    }
    Ok(())
}

/// Checks the document; the first problem found, in document order.
pub(super) fn check(root: &Value) -> Result<(), Problem> {
    // A glTF 1.0 document fails everywhere in 2.0's terms (its `scene` is a name, its meshes refer
    // to accessors by id): say what it is instead of the first of those.
    // Some 1.0 exporters wrote the version as a number.
    let version = root.pointer("/asset/version").and_then(|v| match v {
        Value::String(s) => Some(s.clone()),
        Value::Number(n) => Some(n.to_string()),
        _ => None,
    });
    if let Some(version) = version {
        if version.split('.').next() != Some("2") {
            return Err((
                "asset.version".into(),
                format!(
                    "glTF {version:?} is not supported; sinew reads glTF 2.0 \
                     (convert the file to glTF 2.0 first)"
                ),
            ));
        }
    }
    let c = Counts {
        accessors: len(root, "accessors"),
        buffer_views: len(root, "bufferViews"),
        buffers: len(root, "buffers"),
        nodes: len(root, "nodes"),
        meshes: len(root, "meshes"),
        skins: len(root, "skins"),
        materials: len(root, "materials"),
        textures: len(root, "textures"),
        images: len(root, "images"),
        samplers: len(root, "samplers"),
        cameras: len(root, "cameras"),
        scenes: len(root, "scenes"),
    };
    let component_types: Vec<Value> = [5120, 5121, 5122, 5123, 5125, 5126]
        .map(Value::from)
        .to_vec();
    let accessor_types: Vec<Value> = ["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"]
        .map(Value::from)
        .to_vec();
    index(root.get("scene"), || "scene".into(), "scene", c.scenes)?;
    for (i, a) in items(root, "accessors") {
        let p = |f: &str| format!("accessors[{i}].{f}");
        index(
            a.get("bufferView"),
            || p("bufferView"),
            "bufferView",
            c.buffer_views,
        )?;
        one_of(
            a.get("componentType"),
            || p("componentType"),
            &component_types,
        )?;
        one_of(a.get("type"), || p("type"), &accessor_types)?;
        if let Some(s) = a.get("sparse") {
            index(
                s.get("indices").and_then(|x| x.get("bufferView")),
                || p("sparse.indices.bufferView"),
                "bufferView",
                c.buffer_views,
            )?;
            index(
                s.get("values").and_then(|x| x.get("bufferView")),
                || p("sparse.values.bufferView"),
                "bufferView",
                c.buffer_views,
            )?;
            one_of(
                s.get("indices").and_then(|x| x.get("componentType")),
                || p("sparse.indices.componentType"),
                &[5121, 5123, 5125].map(Value::from),
            )?;
        }
    }
    for (i, v) in items(root, "bufferViews") {
        index(
            v.get("buffer"),
            || format!("bufferViews[{i}].buffer"),
            "buffer",
            c.buffers,
        )?;
    }
    for (i, im) in items(root, "images") {
        index(
            im.get("bufferView"),
            || format!("images[{i}].bufferView"),
            "bufferView",
            c.buffer_views,
        )?;
        // gltf's Image::source unwraps the mimeType of an image in a buffer view, and the uri of any
        // other (the fuzzer found the first).
        let text = |key: &str| im.get(key).is_some_and(Value::is_string);
        if im.get("bufferView").is_some() && !text("mimeType") {
            return Err((
                format!("images[{i}].mimeType"),
                "an image in a buffer view needs a mimeType string".into(),
            ));
        }
        if im.get("bufferView").is_none() && !text("uri") {
            return Err((
                format!("images[{i}].uri"),
                "an image needs a uri string or a bufferView".into(),
            ));
        }
    }
    for (i, t) in items(root, "textures") {
        index(
            t.get("source"),
            || format!("textures[{i}].source"),
            "image",
            c.images,
        )?;
        index(
            t.get("sampler"),
            || format!("textures[{i}].sampler"),
            "sampler",
            c.samplers,
        )?;
    }
    for (i, m) in items(root, "materials") {
        let p = |f: &str| format!("materials[{i}].{f}");
        let pbr = m.get("pbrMetallicRoughness");
        texture_info(
            pbr.and_then(|x| x.get("baseColorTexture")),
            || p("pbrMetallicRoughness.baseColorTexture"),
            &c,
        )?;
        texture_info(
            pbr.and_then(|x| x.get("metallicRoughnessTexture")),
            || p("pbrMetallicRoughness.metallicRoughnessTexture"),
            &c,
        )?;
        for t in ["normalTexture", "occlusionTexture", "emissiveTexture"] {
            texture_info(m.get(t), || p(t), &c)?;
        }
    }
    for (i, m) in items(root, "meshes") {
        for (j, prim) in m
            .get("primitives")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
        {
            let p = |f: &str| format!("meshes[{i}].primitives[{j}].{f}");
            if let Some(attrs) = prim.get("attributes").and_then(Value::as_object) {
                for (name, v) in attrs {
                    index(
                        Some(v),
                        || p(&format!("attributes.{name}")),
                        "accessor",
                        c.accessors,
                    )?;
                }
            }
            index(
                prim.get("indices"),
                || p("indices"),
                "accessor",
                c.accessors,
            )?;
            index(
                prim.get("material"),
                || p("material"),
                "material",
                c.materials,
            )?;
            one_of(
                prim.get("mode"),
                || p("mode"),
                &(0..=6).map(Value::from).collect::<Vec<_>>(),
            )?;
            for (k, t) in prim
                .get("targets")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
                .enumerate()
            {
                if let Some(t) = t.as_object() {
                    for (name, v) in t {
                        index(
                            Some(v),
                            || p(&format!("targets[{k}].{name}")),
                            "accessor",
                            c.accessors,
                        )?;
                    }
                }
            }
        }
    }
    for (i, n) in items(root, "nodes") {
        let p = |f: &str| format!("nodes[{i}].{f}");
        index(n.get("mesh"), || p("mesh"), "mesh", c.meshes)?;
        index(n.get("skin"), || p("skin"), "skin", c.skins)?;
        index(n.get("camera"), || p("camera"), "camera", c.cameras)?;
        for (k, ch) in n
            .get("children")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
        {
            index(Some(ch), || p(&format!("children[{k}]")), "node", c.nodes)?;
        }
    }
    for (i, s) in items(root, "skins") {
        let p = |f: &str| format!("skins[{i}].{f}");
        index(
            s.get("inverseBindMatrices"),
            || p("inverseBindMatrices"),
            "accessor",
            c.accessors,
        )?;
        index(s.get("skeleton"), || p("skeleton"), "node", c.nodes)?;
        for (k, j) in s
            .get("joints")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
        {
            index(Some(j), || p(&format!("joints[{k}]")), "node", c.nodes)?;
        }
    }
    for (i, s) in items(root, "scenes") {
        for (k, n) in s
            .get("nodes")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
        {
            index(
                Some(n),
                || format!("scenes[{i}].nodes[{k}]"),
                "node",
                c.nodes,
            )?;
        }
    }
    let paths: Vec<Value> = ["translation", "rotation", "scale", "weights"]
        .map(Value::from)
        .to_vec();
    let interpolations: Vec<Value> = ["LINEAR", "STEP", "CUBICSPLINE"].map(Value::from).to_vec();
    for (i, a) in items(root, "animations") {
        let samplers = a
            .get("samplers")
            .and_then(Value::as_array)
            .map_or(0, Vec::len);
        for (k, s) in a
            .get("samplers")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
        {
            let p = |f: &str| format!("animations[{i}].samplers[{k}].{f}");
            index(s.get("input"), || p("input"), "accessor", c.accessors)?;
            index(s.get("output"), || p("output"), "accessor", c.accessors)?;
            one_of(
                s.get("interpolation"),
                || p("interpolation"),
                &interpolations,
            )?;
        }
        for (k, ch) in a
            .get("channels")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
            .enumerate()
        {
            let p = |f: &str| format!("animations[{i}].channels[{k}].{f}");
            index(ch.get("sampler"), || p("sampler"), "sampler", samplers)?;
            let target = ch.get("target");
            index(
                target.and_then(|t| t.get("node")),
                || p("target.node"),
                "node",
                c.nodes,
            )?;
            one_of(
                target.and_then(|t| t.get("path")),
                || p("target.path"),
                &paths,
            )?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn doc() -> Value {
        json!({
            "asset": {"version": "2.0"},
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "accessors": [{"componentType": 5126, "count": 3, "type": "VEC3"}],
            "animations": [{"samplers": [{"input": 0, "output": 0}], "channels": [{"sampler": 0, "target": {"node": 0, "path": "rotation"}}]}]
        })
    }

    #[test]
    fn good_references_pass_and_bad_ones_are_named_by_path() {
        assert_eq!(check(&doc()), Ok(()));
        let cases: [(&str, Value, &str); 6] = [
            (
                "/meshes/0/primitives/0/attributes/POSITION",
                json!(99999),
                "meshes[0].primitives[0].attributes.POSITION",
            ),
            (
                "/animations/0/channels/0/target/node",
                json!(99999),
                "animations[0].channels[0].target.node",
            ),
            (
                "/animations/0/channels/0/target/path",
                json!("BOGUS"),
                "animations[0].channels[0].target.path",
            ),
            (
                "/animations/0/channels/0/sampler",
                json!(1),
                "animations[0].channels[0].sampler",
            ),
            ("/nodes/0/mesh", json!(-1), "nodes[0].mesh"),
            ("/accessors/0/type", json!("VEC5"), "accessors[0].type"),
        ];
        for (pointer, value, path) in cases {
            let mut d = doc();
            *d.pointer_mut(pointer).unwrap() = value;
            let (p, m) = check(&d).unwrap_err();
            assert_eq!(p, path, "{m}");
        }
    }

    #[test]
    fn a_gltf_1_document_is_named_as_such() {
        let mut d = doc();
        // glTF 1.0's scene is a name, which 2.0's terms would report as a bad index.
        d["scene"] = json!("defaultScene");
        d["asset"]["version"] = json!("1.0");
        let (p, m) = check(&d).unwrap_err();
        assert_eq!(p, "asset.version");
        assert!(m.contains("glTF \"1.0\" is not supported"), "{m}");
        d["asset"]["version"] = json!(1);
        let (p, m) = check(&d).unwrap_err();
        assert_eq!(p, "asset.version");
        assert!(m.contains("glTF \"1\" is not supported"), "{m}");
        d["asset"]["version"] = json!("2.1");
        d["scene"] = json!(0);
        d["scenes"] = json!([{"nodes": [0]}]);
        assert_eq!(check(&d), Ok(()));
    }
}
