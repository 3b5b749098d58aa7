//! EXT_meshopt_compression (gltfpack `-c`) on small documents written here: views compressed with
//! meshoptimizer's encoders (the codecs' other half; the importer's part under test is the glTF
//! plumbing: which bytes are decoded, how, into which view), read back and compared with the same
//! document stored plain; malformed compressed views refused by path before allocating.
#![allow(clippy::unwrap_used)]

use sinew_core::glam::Vec3;
use sinew_import::{gltf, ImportOptions, Location};
use sinew_scene::Scene;
use sinew_testdata::gltf_doc::{base64, no_resolve};

/// One compressed view: its encoded bytes and its extension's fields.
struct View {
    encoded: Vec<u8>,
    length: usize,
    stride: usize,
    count: usize,
    mode: &'static str,
    filter: &'static str,
}

/// A document whose views are `views`, compressed in buffer 0 and decoded into the fallback buffer
/// 1 (no data of its own), laid out one after another; `rest` holds the accessors, meshes and so on.
fn compressed_doc(views: &[View], rest: &str) -> Vec<u8> {
    let mut data = Vec::new();
    let mut json_views = Vec::new();
    let mut at = 0;
    for v in views {
        let offset = data.len();
        data.extend(&v.encoded);
        while data.len() % 4 != 0 {
            data.push(0);
        }
        json_views.push(format!(
            r#"{{"buffer":1,"byteOffset":{at},"byteLength":{},"byteStride":{},"extensions":{{"EXT_meshopt_compression":{{"buffer":0,"byteOffset":{offset},"byteLength":{},"byteStride":{},"count":{},"mode":"{}","filter":"{}"}}}}}}"#,
            v.length,
            v.stride,
            v.encoded.len(),
            v.stride,
            v.count,
            v.mode,
            v.filter
        ));
        at += v.length.div_ceil(4) * 4;
    }
    // Index views have no byteStride in glTF.
    let json_views: Vec<String> = json_views
        .into_iter()
        .zip(views)
        .map(|(j, v)| {
            if v.mode == "ATTRIBUTES" {
                j
            } else {
                j.replacen(&format!(r#""byteStride":{},"ext"#, v.stride), r#""ext"#, 1)
            }
        })
        .collect();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["EXT_meshopt_compression"],"extensionsRequired":["EXT_meshopt_compression"],
        "buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}},{{"byteLength":{at},"extensions":{{"EXT_meshopt_compression":{{"fallback":true}}}}}}],
        "bufferViews":[{}],{rest}}}"#,
        data.len(),
        base64(&data),
        json_views.join(",")
    )
    .into_bytes()
}

const POSITIONS: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.5, 0.0, -0.25],
    [0.0, 2.0, 0.5],
    [1.0, 1.0, 1.0],
];
const INDICES: [u32; 6] = [0, 1, 2, 2, 1, 3];

/// The four float positions' view (12-byte vertices), from their encoded bytes.
fn positions_view(encoded: Vec<u8>, filter: &'static str) -> View {
    View {
        encoded,
        length: 48,
        stride: 12,
        count: 4,
        mode: "ATTRIBUTES",
        filter,
    }
}

/// The six u16 indices' view, from their encoded bytes (`mode` TRIANGLES or INDICES).
fn indices_view(encoded: Vec<u8>, mode: &'static str) -> View {
    View {
        encoded,
        length: 12,
        stride: 2,
        count: 6,
        mode,
        filter: "NONE",
    }
}

/// The accessors and mesh of the two triangles over views 0 (positions) and 1 (indices).
const TWO_TRIANGLES: &str = r#""accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,-0.25],"max":[1.5,2,1]},
  {"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}]"#;

/// The two triangles with float positions and u16 indices, compressed (indices as `mode`).
fn two_triangles(mode: &'static str) -> Vec<u8> {
    let positions = positions_view(meshopt::encode_vertex_buffer(&POSITIONS).unwrap(), "NONE");
    let encoded = if mode == "TRIANGLES" {
        meshopt::encode_index_buffer(&INDICES, 4).unwrap()
    } else {
        meshopt::encode_index_sequence(&INDICES, 4).unwrap()
    };
    compressed_doc(&[positions, indices_view(encoded, mode)], TWO_TRIANGLES)
}

fn import(doc: &[u8]) -> Scene {
    gltf::import("c.gltf", doc, &no_resolve, &ImportOptions::default()).unwrap()
}

#[test]
fn compressed_views_decode_to_the_data_they_stand_for() {
    for mode in ["TRIANGLES", "INDICES"] {
        let s = import(&two_triangles(mode));
        let g = &s.meshes[0].geometry;
        let expected: Vec<Vec3> = POSITIONS.iter().map(|p| Vec3::from_array(*p)).collect();
        assert_eq!(g.positions, expected, "{mode}");
        assert_eq!(g.indices, INDICES, "{mode}");
    }
}

#[test]
fn a_fallback_buffer_may_come_first() {
    // The same document with its two buffers swapped: the fallback (no data) is buffer 0.
    let doc = String::from_utf8(two_triangles("TRIANGLES")).unwrap();
    let start = doc.find(r#""buffers":["#).unwrap() + r#""buffers":["#.len();
    let end = doc[start..].find("],").unwrap() + start;
    let split = doc[start..end].find(r#"},{"byteLength""#).unwrap() + start + 1;
    let (data, fallback) = (&doc[start..split], &doc[split + 1..end]);
    let swapped = format!("{}{fallback},{data}{}", &doc[..start], &doc[end..])
        .replace(r#""buffer":1"#, r#""buffer":X"#)
        .replace(r#""buffer":0"#, r#""buffer":1"#)
        .replace(r#""buffer":X"#, r#""buffer":0"#);
    let s = import(swapped.as_bytes());
    let expected: Vec<Vec3> = POSITIONS.iter().map(|p| Vec3::from_array(*p)).collect();
    assert_eq!(s.meshes[0].geometry.positions, expected);
    assert_eq!(s.meshes[0].geometry.indices, INDICES);
}

#[test]
fn filtered_views_decode_to_within_their_encoding() {
    // Normals through the octahedral filter (8 bits, stride 4), positions through the exponential
    // one (stride 12): what gltfpack -cc writes.
    let normals = [
        [0.0f32, 0.0, 1.0, 0.0],
        [0.6, 0.0, 0.8, 0.0],
        [0.0, -1.0, 0.0, 0.0],
        [0.48, 0.6, 0.64, 0.0],
    ];
    let oct: Vec<[i8; 4]> = meshopt::encode_filter_oct(&normals, 8);
    let exp = meshopt::encode_filter_exp::<3>(&POSITIONS, 15, meshopt::EncodeExpMode::Separate);
    let views = [
        positions_view(meshopt::encode_vertex_buffer(&exp).unwrap(), "EXPONENTIAL"),
        View {
            encoded: meshopt::encode_vertex_buffer(&oct).unwrap(),
            length: 16,
            stride: 4,
            count: 4,
            mode: "ATTRIBUTES",
            filter: "OCTAHEDRAL",
        },
        indices_view(
            meshopt::encode_index_buffer(&INDICES, 4).unwrap(),
            "TRIANGLES",
        ),
    ];
    let doc = compressed_doc(
        &views,
        r#""accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,-0.25],"max":[1.5,2,1]},
          {"bufferView":1,"componentType":5120,"normalized":true,"count":4,"type":"VEC3"},
          {"bufferView":2,"componentType":5123,"count":6,"type":"SCALAR"}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0,"NORMAL":1},"indices":2}]}]"#,
    );
    let s = import(&doc);
    let g = &s.meshes[0].geometry;
    for (p, e) in g.positions.iter().zip(POSITIONS) {
        // 15-bit mantissas: within 2^-14 of each value's magnitude.
        assert!(
            (*p - Vec3::from_array(e)).abs().max_element() < 2e-4,
            "{p} against {e:?}"
        );
    }
    for (n, e) in g.normals.iter().zip(normals) {
        let e = Vec3::new(e[0], e[1], e[2]);
        assert!((*n - e).length() < 0.02, "{n} against {e}");
    }
}

fn error_of(doc: &[u8]) -> sinew_import::ImportError {
    gltf::import("bad.gltf", doc, &no_resolve, &ImportOptions::default()).unwrap_err()
}

fn path(e: &sinew_import::ImportError) -> &str {
    match &e.location {
        Location::JsonPath(p) => p,
        other => panic!("expected a JSON path, got {other:?} in {e}"),
    }
}

#[test]
fn malformed_compressed_views_are_refused_by_path() {
    let good = String::from_utf8(two_triangles("TRIANGLES")).unwrap();
    let view0 = "bufferViews[0].extensions.EXT_meshopt_compression";
    for (from, to, at, says) in [
        // A count no file of this size may decode to: refused before allocating 2^40 x 12 bytes.
        (
            r#""count":4,"#,
            r#""count":1099511627776,"#,
            view0,
            "more than the file may decode to",
        ),
        (
            r#""mode":"ATTRIBUTES""#,
            r#""mode":"PACKED""#,
            view0,
            "unknown mode",
        ),
        (
            r#""filter":"NONE""#,
            r#""filter":"QUATERNION""#,
            view0,
            "does not take byteStride 12",
        ),
        (
            r#""byteStride":12,"count""#,
            r#""byteStride":14,"count""#,
            view0,
            "multiple of 4",
        ),
        // The encoded bytes cut short (its byteLength shrunk): the codec refuses them.
        (
            r#""buffer":0,"byteOffset":0,"byteLength":"#,
            r#""buffer":0,"byteOffset":0,"byteLength":3,"x":"#,
            view0,
            "does not decode",
        ),
        (
            r#""buffer":0,"byteOffset":0"#,
            r#""buffer":0,"byteOffset":4000"#,
            view0,
            "are not in buffers[0]",
        ),
    ] {
        assert!(good.contains(from), "{from}");
        let doc = good.replacen(from, to, 1);
        let e = error_of(doc.as_bytes());
        assert_eq!(e.file, "bad.gltf");
        assert_eq!(path(&e), at, "{to}: {e}");
        assert!(e.message.contains(says), "{to}: {e}");
    }
    // A fallback buffer larger than the file could decode to.
    let doc = good.replacen(
        r#"{"byteLength":60,"extensions""#,
        r#"{"byteLength":4000000000000,"extensions""#,
        1,
    );
    assert_ne!(doc, good);
    let e = error_of(doc.as_bytes());
    assert_eq!(path(&e), "buffers[1]", "{e}");
}

#[test]
fn mutated_encoded_bytes_decode_or_are_refused_never_panic() {
    // meshoptimizer's decoders take untrusted input; what they return (garbage vertices, indices
    // out of range, an error) must reach the user as a result or an error naming the file.
    let encoded = [
        meshopt::encode_vertex_buffer(&POSITIONS).unwrap(),
        meshopt::encode_index_buffer(&INDICES, 4).unwrap(),
    ];
    let (mut read, mut refused) = (0, 0);
    for which in 0..2 {
        for i in 0..encoded[which].len() {
            for value in [0x00u8, 0xff, 0x80, encoded[which][i] ^ 1] {
                let mut e = encoded.clone();
                e[which][i] = value;
                let [p, ix] = e;
                let views = [positions_view(p, "NONE"), indices_view(ix, "TRIANGLES")];
                let doc = compressed_doc(&views, TWO_TRIANGLES);
                match gltf::import("m.gltf", &doc, &no_resolve, &ImportOptions::default()) {
                    Ok(_) => read += 1,
                    Err(err) => {
                        assert_eq!(err.file, "m.gltf");
                        refused += 1;
                    }
                }
            }
        }
    }
    // Both outcomes occur (the counts are what this run measured, not a tuned expectation).
    assert!(read > 0 && refused > 0, "read {read}, refused {refused}");
}
