//! Documents that make gltf-json 1.4.1 panic are refused before it sees them, with the JSON path
//! (docs/reliability.md); and any panic left in the crate is an error that prints nothing.
#![allow(clippy::unwrap_used)]

use sinew_import::{import_bytes, Format, ImportOptions, Location};

fn import(json: &str) -> sinew_import::ImportError {
    let none = |_: &str| -> std::io::Result<Vec<u8>> { Err(std::io::Error::other("none")) };
    import_bytes(
        Format::Gltf,
        "m.gltf",
        json.as_bytes(),
        &none,
        &ImportOptions::default(),
    )
    .unwrap_err()
}

const BASE: &str = r#"{"asset": {"version": "2.0"}, "nodes": [{"mesh": 0}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": @POS@}}]}],
 "accessors": [{"componentType": 5126, "count": 3, "type": "VEC3", "max": [1, 1, 1], "min": [0, 0, 0]}],
 "animations": [{"samplers": [{"input": 0, "output": 0}], "channels": [{"sampler": 0, "target": {"node": @NODE@, "path": @PATH@}}]}]}"#;

fn doc(pos: &str, node: &str, path: &str) -> String {
    BASE.replace("@POS@", pos)
        .replace("@NODE@", node)
        .replace("@PATH@", path)
}

#[test]
fn the_three_known_panics_are_errors_with_json_paths() {
    // gltf-json mesh.rs: `root.accessors[index]` for POSITION, unchecked.
    let e = import(&doc("99999", "0", "\"rotation\""));
    assert_eq!(
        e.location,
        Location::JsonPath("meshes[0].primitives[0].attributes.POSITION".into())
    );
    assert!(e.message.contains("99999"), "{e}");
    // An animation channel's target node past the nodes: `Option::unwrap()` on None.
    let e = import(&doc("0", "99999", "\"rotation\""));
    assert_eq!(
        e.location,
        Location::JsonPath("animations[0].channels[0].target.node".into())
    );
    // An unknown target path: "attempted to unwrap an invalid item".
    let e = import(&doc("0", "0", "\"BOGUS\""));
    assert_eq!(
        e.location,
        Location::JsonPath("animations[0].channels[0].target.path".into())
    );
    assert_eq!(e.file, "m.gltf");
}

#[test]
fn images_without_the_fields_gltf_unwraps_are_errors_with_json_paths() {
    // Found by the glb fuzz target: gltf 1.4.1 image.rs unwraps an image's mimeType (in a buffer view)
    // or uri (otherwise) when the importer asks for its source.
    let with_image = |image: &str| {
        doc("0", "0", "\"rotation\"").replace(
            "\"animations\"",
            &format!(
                "\"bufferViews\": [{{\"buffer\": 0, \"byteLength\": 4}}], \"buffers\": [{{\"byteLength\": 4, \"uri\": \"data:application/octet-stream;base64,AAAAAA==\"}}], \"images\": [{image}], \"animations\""
            ),
        )
    };
    let e = import(&with_image("{\"bufferView\": 0}"));
    assert_eq!(e.location, Location::JsonPath("images[0].mimeType".into()));
    let e = import(&with_image("{\"name\": \"no source\"}"));
    assert_eq!(e.location, Location::JsonPath("images[0].uri".into()));
}
