//! Every corpus OBJ file imports with asserted content; malformed ones fail naming the line.
#![allow(clippy::unwrap_used)]

use sinew_import::{obj, ImportError, ImportOptions, Location};
use sinew_scene::Scene;
use sinew_testdata::{corpus, read_corpus};
use std::collections::{HashMap, HashSet};

fn import(rel: &str) -> Option<Result<Scene, ImportError>> {
    let bytes = read_corpus(rel)?;
    let dir = corpus()?.join(rel).parent().unwrap().to_path_buf();
    let resolve = move |name: &str| std::fs::read(dir.join(name));
    Some(obj::import(
        rel,
        &bytes,
        &resolve,
        &ImportOptions::default(),
    ))
}

/// Independent count of what the test expects from the raw text: triangles (fan of each `f` line) and
/// distinct (v, vt, vn) corner triples, per group/object name.
fn raw_counts(text: &str) -> (usize, usize) {
    let (mut nv, mut nvt, mut nvn) = (0i64, 0i64, 0i64);
    let mut tris = 0;
    let mut corners: HashSet<(String, i64, i64, i64)> = HashSet::new();
    let mut group = String::new();
    for line in text.lines() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => nv += 1,
            Some("vt") => nvt += 1,
            Some("vn") => nvn += 1,
            Some("g") | Some("o") => group = w.collect::<Vec<_>>().join(" "),
            Some("f") => {
                let toks: Vec<&str> = w.collect();
                tris += toks.len() - 2;
                for t in toks {
                    let p: Vec<i64> = t
                        .split('/')
                        .map(|x| x.parse::<i64>().unwrap_or(0))
                        .collect();
                    let fix = |i: i64, n: i64| if i < 0 { n + i + 1 } else { i };
                    corners.insert((
                        group.clone(),
                        fix(p[0], nv),
                        fix(*p.get(1).unwrap_or(&0), nvt),
                        fix(*p.get(2).unwrap_or(&0), nvn),
                    ));
                }
            }
            _ => {}
        }
    }
    (tris, corners.len())
}

fn triangles(s: &Scene) -> usize {
    s.meshes.iter().map(|m| m.geometry.triangle_count()).sum()
}

fn check_invariants(s: &Scene) {
    for m in &s.meshes {
        let g = &m.geometry;
        assert_eq!(g.normals.len(), g.positions.len());
        assert!(g.uvs.is_empty() || g.uvs.len() == g.positions.len());
        assert_eq!(m.source_vertex.len(), g.positions.len());
        assert!(g.indices.iter().all(|&i| (i as usize) < g.positions.len()));
        for n in &g.normals {
            assert!((n.length() - 1.0).abs() < 1e-4, "normal {n} not unit");
        }
        let mut next = 0;
        for sm in &g.submeshes {
            assert_eq!(sm.first_index, next);
            next += sm.index_count;
        }
        assert_eq!(next as usize, g.indices.len());
        for sm in &g.submeshes {
            assert!(sm.material.is_empty() || s.materials.iter().any(|m| m.name == sm.material));
        }
    }
}

#[test]
fn spot() {
    let Some(r) = import("obj/spot.obj") else {
        return;
    };
    let s = r.unwrap();
    check_invariants(&s);
    assert_eq!(s.meshes.len(), 1);
    assert_eq!(triangles(&s), 5856);
    let text = String::from_utf8(read_corpus("obj/spot.obj").unwrap()).unwrap();
    let (tris, corners) = raw_counts(&text);
    assert_eq!(tris, 5856);
    // No `s` lines, no vn: one smoothing group, so vertices split only by UV.
    assert_eq!(s.meshes[0].geometry.vertex_count(), corners);
    assert_eq!(s.meshes[0].source_vertex_count, 2930);
    assert_eq!(s.meshes[0].geometry.uvs.len(), corners);
    // Every vertex of the 2930 is used and maps back to its own position.
    let used: HashSet<u32> = s.meshes[0].source_vertex.iter().copied().collect();
    assert_eq!(used.len(), 2930);
    let first_v: Vec<f32> = text
        .lines()
        .find(|l| l.starts_with("v "))
        .unwrap()
        .split_whitespace()
        .skip(1)
        .map(|t| t.parse().unwrap())
        .collect();
    let k = s.meshes[0]
        .source_vertex
        .iter()
        .position(|&v| v == 0)
        .unwrap();
    assert_eq!(
        s.meshes[0].geometry.positions[k].to_array(),
        [first_v[0], first_v[1], first_v[2]]
    );
}

#[test]
fn cornell_box_negative_indices_and_materials() {
    let Some(r) = import("obj/cornell_box.obj") else {
        return;
    };
    let s = r.unwrap();
    check_invariants(&s);
    let names: Vec<&str> = s.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(
        names,
        [
            // front_wall's only face is commented out: no faces, no mesh.
            "floor",
            "light",
            "ceiling",
            "back_wall",
            "green_wall",
            "red_wall",
            "short_block",
            "tall_block"
        ]
    );
    let light = &s.meshes[1];
    // `f -4 -3 -2 -1` after 16 vertices: v 13..16 (0-based 12..15), one quad = 2 triangles.
    let mut sv = light.source_vertex.clone();
    sv.sort();
    assert_eq!(sv, [12, 13, 14, 15]);
    assert_eq!(light.geometry.triangle_count(), 2);
    let k = light.source_vertex.iter().position(|&v| v == 12).unwrap();
    assert_eq!(
        light.geometry.positions[k].to_array(),
        [343.0, 548.0, 227.0]
    );
    assert_eq!(light.geometry.submeshes.len(), 1);
    assert_eq!(light.geometry.submeshes[0].material, "light");
    // Flat quad in the y = 548 plane: generated normal is +-Y.
    for n in &light.geometry.normals {
        assert!((n.y.abs() - 1.0).abs() < 1e-6, "{n}");
    }
    let text = String::from_utf8(read_corpus("obj/cornell_box.obj").unwrap()).unwrap();
    assert_eq!(triangles(&s), raw_counts(&text).0);
    let mat = |n: &str| s.materials.iter().find(|m| m.name == n).unwrap().base_color;
    assert_eq!(mat("red"), [1.0, 0.0, 0.0, 1.0]);
    assert_eq!(mat("blue"), [0.0, 0.0, 1.0, 1.0]);
    assert_eq!(s.materials.len(), 5);
    assert_eq!(s.warnings().count(), 0, "{:?}", s.diagnostics);
}

#[test]
fn spider_groups_smoothing_and_mtl() {
    let Some(r) = import("obj/spider.obj") else {
        return;
    };
    let s = r.unwrap();
    check_invariants(&s);
    assert_eq!(s.meshes.len(), 19);
    let text = String::from_utf8_lossy(&read_corpus("obj/spider.obj").unwrap()).into_owned();
    let (tris, corners) = raw_counts(&text);
    assert_eq!(triangles(&s), tris);
    // All corners carry vn, so vertices are exactly the distinct (group, v, vt, vn).
    let verts: usize = s.meshes.iter().map(|m| m.geometry.vertex_count()).sum();
    assert_eq!(verts, corners);
    let skin = s.materials.iter().find(|m| m.name == "Skin").unwrap();
    assert_eq!(skin.texture.as_deref(), Some(r".\wal67ar_small.jpg"));
    assert_eq!(skin.base_color, [0.827451, 0.792157, 0.772549, 1.0]);
}

#[test]
fn regr01_groups_and_generated_normals() {
    let Some(r) = import("obj/regr01.obj") else {
        return;
    };
    let s = r.unwrap();
    check_invariants(&s);
    let text = String::from_utf8_lossy(&read_corpus("obj/regr01.obj").unwrap()).into_owned();
    assert_eq!(triangles(&s), raw_counts(&text).0);
    let groups: HashSet<String> = text
        .lines()
        .filter(|l| l.starts_with("g ") || *l == "g")
        .map(|l| {
            let n = l[1..].split_whitespace().collect::<Vec<_>>().join(" ");
            if n.is_empty() {
                "obj/regr01".to_string()
            } else {
                n
            }
        })
        .collect();
    let mesh_names: HashSet<String> = s.meshes.iter().map(|m| m.name.clone()).collect();
    assert!(mesh_names.is_subset(&groups));
    assert_eq!(s.materials.iter().filter(|m| m.name == "Roof").count(), 1);
}

#[test]
fn cube_crlf_missing_mtl_is_a_warning() {
    let Some(r) = import("obj/cube_mtllib_after_g.obj") else {
        return;
    };
    let s = r.unwrap();
    check_invariants(&s);
    assert_eq!(s.meshes.len(), 1);
    assert_eq!(s.meshes[0].name, "Object");
    assert_eq!(triangles(&s), 12);
    // Each of 6 sides: 4 positions with one explicit normal.
    assert_eq!(s.meshes[0].geometry.vertex_count(), 24);
    assert!(s
        .warnings()
        .any(|d| d.code == "obj-mtl-missing" && d.message.contains("cube_mtllib_after_g.mat")));
    assert_eq!(s.meshes[0].geometry.submeshes[0].material, "MyMaterial");
    // First face `f 1//2 7//2 5//2`: explicit normal vn 2 = (0, 0, -1).
    let g = &s.meshes[0].geometry;
    assert_eq!(
        g.normals[g.indices[0] as usize].to_array(),
        [0.0, 0.0, -1.0]
    );
}

#[test]
fn box_utf16be() {
    let Some(r) = import("obj/box_UTF16BE.obj") else {
        return;
    };
    let s = r.unwrap();
    check_invariants(&s);
    let bytes = read_corpus("obj/box_UTF16BE.obj").unwrap();
    assert_eq!(&bytes[..2], &[0xFE, 0xFF]);
    let units: Vec<u16> = bytes[2..]
        .chunks(2)
        .map(|c| u16::from_be_bytes([c[0], c[1]]))
        .collect();
    let text = String::from_utf16(&units).unwrap();
    let (tris, corners) = raw_counts(&text);
    assert!(tris > 0);
    assert_eq!(triangles(&s), tris);
    // Flat cube faces without `s` lines: smoothing merges per position (one group).
    assert_eq!(
        s.meshes
            .iter()
            .map(|m| m.geometry.vertex_count())
            .sum::<usize>(),
        corners
    );
}

#[test]
fn box_without_final_newline_keeps_last_face() {
    let Some(r) = import("obj/box_without_lineending.obj") else {
        return;
    };
    let s = r.unwrap();
    check_invariants(&s);
    assert_eq!(triangles(&s), 12);
    assert_eq!(s.meshes[0].name, "1");
    // The last face `f 6 7 8 5` (0-based 5 6 7 4) is there, as a fan of two triangles.
    let g = &s.meshes[0].geometry;
    let last: Vec<u32> = g.indices[30..]
        .iter()
        .map(|&i| s.meshes[0].source_vertex[i as usize])
        .collect();
    assert_eq!(last, [5, 6, 7, 5, 7, 4]);
}

#[test]
fn testmixed_points_and_lines_warn() {
    let Some(r) = import("obj/testmixed.obj") else {
        return;
    };
    let s = r.unwrap();
    check_invariants(&s);
    assert_eq!(triangles(&s), 12);
    let d = s
        .warnings()
        .find(|d| d.code == "obj-points-lines-ignored")
        .unwrap();
    assert_eq!(
        d.figures,
        [("points".to_string(), 6.0), ("lines".to_string(), 6.0)]
    );
}

#[test]
fn number_formats() {
    let Some(r) = import("obj/number_formats.obj") else {
        return;
    };
    let s = r.unwrap();
    let g = &s.meshes[0].geometry;
    assert_eq!(g.triangle_count(), 1);
    let pos: HashMap<u32, [f32; 3]> = s.meshes[0]
        .source_vertex
        .iter()
        .zip(&g.positions)
        .map(|(&v, p)| (v, p.to_array()))
        .collect();
    assert_eq!(pos[&0], [0.0, 0.0, 0.0]);
    assert_eq!(pos[&1], [1.0, 2.0, 3.0]);
    assert_eq!(pos[&3], [-1.0, -2.0, -3.0]);
    // `3.1+e2` and `3.1-e2` are not decimals: 6 such numbers, read as 3.1, warned about.
    let d = s
        .warnings()
        .find(|d| d.code == "obj-number-format")
        .unwrap();
    assert_eq!(d.figures[0], ("numbers".to_string(), 6.0));
    assert_eq!(d.figures[1], ("first_line".to_string(), 11.0));
}

#[test]
fn skin_weight_groups_and_missing_materials() {
    let Some(r) = import("obj/skin-weight.obj") else {
        return;
    };
    let s = r.unwrap();
    check_invariants(&s);
    let names: Vec<&str> = s.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "front cube",
            "back cube",
            "right cube",
            "top cube",
            "left cube",
            "bottom cube"
        ]
    );
    assert_eq!(triangles(&s), 12);
    assert_eq!(s.meshes[2].geometry.submeshes[0].material, "red");
    assert!(s.warnings().any(|d| d.code == "obj-mtl-missing"));
    let missing = s
        .warnings()
        .find(|d| d.code == "obj-material-missing")
        .unwrap();
    assert_eq!(missing.figures[0].1, 3.0);
    // `back cube` has no usemtl of its own: it keeps `white`.
    assert_eq!(s.meshes[1].geometry.submeshes[0].material, "white");
}

fn line_of(e: &ImportError) -> usize {
    match e.location {
        Location::Line(l) => l,
        ref other => panic!("expected a line, got {other:?} in {e}"),
    }
}

#[test]
fn malformed_files_error_with_line() {
    let Some(r) = import("obj/malformed/malformed.obj") else {
        return;
    };
    let e = r.unwrap_err();
    assert_eq!(line_of(&e), 23, "{e}"); // `f 4 12 2 1`
    assert!(e.to_string().contains("malformed.obj"), "{e}");
    assert!(e.message.contains("12"), "{e}");

    let e = import("obj/malformed/invalid-relative-vertex-index.obj")
        .unwrap()
        .unwrap_err();
    assert_eq!(line_of(&e), 1, "{e}");

    let e = import("obj/malformed/issue-140-zero-face-idx.obj")
        .unwrap()
        .unwrap_err();
    assert_eq!(line_of(&e), 16, "{e}");
    assert!(e.message.contains("index 0"), "{e}");

    let e = import("obj/malformed/empty.obj").unwrap().unwrap_err();
    assert!(e.message.contains("no faces"), "{e}");
}

fn import_str(text: &str, mtl: Option<&str>) -> Result<Scene, ImportError> {
    let mtl = mtl.map(|m| m.as_bytes().to_vec());
    let resolve = move |_: &str| mtl.clone().ok_or_else(|| std::io::Error::other("missing"));
    obj::import(
        "t.obj",
        text.as_bytes(),
        &resolve,
        &ImportOptions::default(),
    )
}

#[test]
fn malformed_mtl_lines_do_not_panic() {
    let mtl = "newmtl a\nKd 1 2\nKd 0.5 0.25 0.125\nd\nmap_Kd\nnewmtl\nKd x y z\nnewmtl b\nd 0.5\n";
    let s = import_str(
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
        Some(mtl),
    )
    .unwrap();
    let a = s.materials.iter().find(|m| m.name == "a").unwrap();
    assert_eq!(a.base_color, [0.5, 0.25, 0.125, 1.0]);
    let b = s.materials.iter().find(|m| m.name == "b").unwrap();
    assert_eq!(b.base_color, [1.0, 1.0, 1.0, 0.5]);
    let d = s
        .warnings()
        .find(|d| d.code == "obj-mtl-malformed")
        .unwrap();
    assert!(d.message.contains("lines 2, 4, 5, 6, 7"), "{}", d.message);
}

#[test]
fn smoothing_groups_split_normals() {
    // Two triangles sharing edge v1-v2 folded at 90 degrees.
    let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";
    let smooth = import_str(&format!("{base}s 1\nf 1 2 3\nf 2 1 4\n"), None).unwrap();
    let split = import_str(&format!("{base}s 1\nf 1 2 3\ns 2\nf 2 1 4\n"), None).unwrap();
    let flat = import_str(&format!("{base}s off\nf 1 2 3\nf 2 1 4\n"), None).unwrap();
    assert_eq!(smooth.meshes[0].geometry.vertex_count(), 4);
    assert_eq!(split.meshes[0].geometry.vertex_count(), 6);
    assert_eq!(flat.meshes[0].geometry.vertex_count(), 6);
    // Shared vertex 0 in the smooth case: both faces have equal area and a 90 degree corner there,
    // so the normal bisects +Z and +Y: (0, 1, 1)/sqrt 2.
    let g = &smooth.meshes[0].geometry;
    let k = smooth.meshes[0]
        .source_vertex
        .iter()
        .position(|&v| v == 0)
        .unwrap();
    let h = std::f32::consts::FRAC_1_SQRT_2;
    assert!(
        (g.normals[k] - sinew_core::glam::Vec3::new(0.0, h, h)).length() < 1e-6,
        "{}",
        g.normals[k]
    );
    let g = &flat.meshes[0].geometry;
    assert_eq!(g.normals[g.indices[0] as usize].to_array(), [0.0, 0.0, 1.0]);
    assert_eq!(g.normals[g.indices[3] as usize].to_array(), [0.0, 1.0, 0.0]);
}

#[test]
fn angle_weighting() {
    // A fan around vertex 1 of a pyramid-less shape: a big triangle in z=0 and a thin sliver tilted.
    // Vertex 1's normal weights each face by area * corner angle; computed by hand here.
    let text = "v 0 0 0\nv 2 0 0\nv 0 2 0\nv 0 0.1 1\nf 1 2 3\nf 1 4 2\n";
    let s = import_str(text, None).unwrap();
    let g = &s.meshes[0].geometry;
    use sinew_core::glam::Vec3;
    let p = [
        Vec3::ZERO,
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
        Vec3::new(0.0, 0.1, 1.0),
    ];
    let n1 = (p[1] - p[0]).cross(p[2] - p[0]);
    let n2 = (p[3] - p[0]).cross(p[1] - p[0]);
    let a1 = std::f32::consts::FRAC_PI_2;
    let a2 = (p[3] - p[0])
        .normalize()
        .dot((p[1] - p[0]).normalize())
        .acos();
    let expect = (n1 * a1 + n2 * a2).normalize();
    let k = s.meshes[0]
        .source_vertex
        .iter()
        .position(|&v| v == 0)
        .unwrap();
    assert!(
        (g.normals[k] - expect).length() < 1e-5,
        "{} vs {expect}",
        g.normals[k]
    );
}

#[test]
fn polygons_fan_and_utf8_bom_crlf() {
    let text = "\u{feff}v 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0.5 1.5 0\r\nv 0 1 0\r\nf 1 2 3 4 5";
    let s = import_str(text, None).unwrap();
    let g = &s.meshes[0].geometry;
    let sv: Vec<u32> = g
        .indices
        .iter()
        .map(|&i| s.meshes[0].source_vertex[i as usize])
        .collect();
    assert_eq!(sv, [0, 1, 2, 0, 2, 3, 0, 3, 4]);
    assert_eq!(g.vertex_count(), 5);
    assert_eq!(s.meshes[0].name, "t");
}

#[test]
fn utf16le_decodes() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let mut bytes = vec![0xFF, 0xFE];
    for u in text.encode_utf16() {
        bytes.extend(u.to_le_bytes());
    }
    let s = obj::import(
        "t.obj",
        &bytes,
        &|_| Err(std::io::Error::other("no")),
        &ImportOptions::default(),
    )
    .unwrap();
    assert_eq!(s.meshes[0].geometry.triangle_count(), 1);
}

#[test]
fn bad_numbers_and_indices_name_the_line() {
    let e = import_str("v 0 0 0\nv 1 nan 0\n", None).unwrap_err();
    assert_eq!((line_of(&e), e.section.as_str()), (2, "v"));
    let e = import_str("v 0 0 0\nv 1 0\n", None).unwrap_err();
    assert_eq!(line_of(&e), 2);
    let e = import_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n\nf 1/2 2/1 3/1\n", None).unwrap_err();
    assert_eq!(line_of(&e), 6);
    assert!(e.message.contains("texture coordinate"), "{e}");
    let e = import_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/x\n", None).unwrap_err();
    assert_eq!(line_of(&e), 4);
    let e = import_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3//-2\n", None).unwrap_err();
    assert_eq!(line_of(&e), 4);
    let e = import_str("v 0 0 0\nv 1 0 0\nv 0 1 0\ns maybe\nf 1 2 3\n", None).unwrap_err();
    assert_eq!(line_of(&e), 4);
    let e = import_str("v 1e39 0 0\n", None).unwrap_err();
    assert_eq!(line_of(&e), 1);
}

#[test]
fn fixture_prop() {
    let path = sinew_testdata::fixtures().join("prop.obj");
    let s = sinew_import::import_path(&path, &ImportOptions::default()).unwrap();
    check_invariants(&s);
    assert_eq!(s.warnings().count(), 0, "{:?}", s.diagnostics);
    let names: Vec<&str> = s.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["crate", "lid"]);
    let crate_ = &s.meshes[0].geometry;
    assert_eq!(crate_.triangle_count(), 12);
    // `s off`: every quad has its own 4 vertices with the face's outward axis normal.
    assert_eq!(crate_.vertex_count(), 24);
    for (p, n) in crate_.positions.iter().zip(&crate_.normals) {
        let c = *p - sinew_core::glam::Vec3::splat(0.5);
        assert!((c.dot(*n) - 0.5).abs() < 1e-6, "{p} {n}");
    }
    assert_eq!(crate_.submeshes[0].material, "wood");
    let lid = &s.meshes[1];
    assert_eq!(lid.geometry.triangle_count(), 4);
    assert_eq!(lid.source_vertex, [8, 9, 10, 11, 12, 13]);
    assert!(lid
        .geometry
        .normals
        .iter()
        .all(|n| n.to_array() == [0.0, 1.0, 0.0]));
    assert!(lid.geometry.uvs.is_empty());
    let wood = s.materials.iter().find(|m| m.name == "wood").unwrap();
    assert_eq!(wood.base_color, [0.6, 0.4, 0.2, 1.0]);
    assert_eq!(wood.texture.as_deref(), Some("wood.png"));
    let metal = s.materials.iter().find(|m| m.name == "metal").unwrap();
    assert_eq!(metal.base_color, [0.7, 0.7, 0.75, 0.5]);
}
