//! Every MS3D file of the shared corpus imports with the content its MANIFEST entry describes, and
//! damaged or truncated files give errors naming the block and offset.
#![allow(clippy::unwrap_used)]

use sinew_import::{ms3d, ImportOptions, Location};
use sinew_scene::{Level, Scene};

fn no_files(_: &str) -> std::io::Result<Vec<u8>> {
    Err(std::io::ErrorKind::NotFound.into())
}

fn import(bytes: &[u8], name: &str) -> Result<Scene, sinew_import::ImportError> {
    ms3d::import(name, bytes, &no_files, &ImportOptions::default())
}

/// Bounds of the file's vertex positions, read straight from the bytes (vertex i at 16 + 15 i + 1).
fn raw_bounds(b: &[u8]) -> ([f32; 3], [f32; 3]) {
    let n = u16::from_le_bytes([b[14], b[15]]) as usize;
    let mut mn = [f32::MAX; 3];
    let mut mx = [f32::MIN; 3];
    for i in 0..n {
        for k in 0..3 {
            let o = 16 + 15 * i + 1 + 4 * k;
            let v = f32::from_le_bytes(b[o..o + 4].try_into().unwrap());
            mn[k] = mn[k].min(v);
            mx[k] = mx[k].max(v);
        }
    }
    (mn, mx)
}

struct Expect {
    file: &'static str,
    vertices: u32,
    triangles: usize,
    groups: usize,
    materials: &'static [(&'static str, Option<&'static str>)],
    joints: usize,
    first_joints: &'static [&'static str],
    fps: f32,
    frames: u32,
}

const FILES: &[Expect] = &[
    Expect {
        file: "ninja.ms3d",
        vertices: 839,
        triangles: 1007,
        groups: 2,
        materials: &[("Material1", Some(".\\nskinbr.jpg")), ("Material01", None)],
        joints: 28,
        first_joints: &["Joint1", "Joint2"],
        fps: 25.0,
        frames: 300,
    },
    Expect {
        file: "zombie.ms3d",
        vertices: 377,
        triangles: 735,
        groups: 1,
        materials: &[("Material0", Some("zombieskin.jpg"))],
        joints: 19,
        first_joints: &["Joint6", "Joint7"],
        fps: 24.0,
        frames: 200,
    },
    Expect {
        file: "zombie02.ms3d",
        vertices: 377,
        triangles: 735,
        groups: 1,
        materials: &[("Material0", Some("C:/work/mymodels/zombie/Zombie.jpg"))],
        joints: 19,
        first_joints: &["Joint6", "Joint7"],
        fps: 24.0,
        frames: 200,
    },
    Expect {
        file: "animated_cylinder.ms3d",
        vertices: 86,
        triangles: 168,
        groups: 1,
        materials: &[],
        joints: 3,
        first_joints: &["joint1", "joint2", "joint3"],
        fps: 24.0,
        frames: 300,
    },
    Expect {
        file: "cross.ms3d",
        vertices: 40,
        triangles: 76,
        groups: 1,
        materials: &[("Material01", Some("data/Wood.bmp")), ("material1", None)],
        joints: 9,
        first_joints: &["joint1", "joint2"],
        fps: 24.0,
        frames: 24,
    },
    Expect {
        file: "jeep1.ms3d",
        vertices: 1190,
        triangles: 2032,
        groups: 7,
        materials: &[("Material01", Some(".\\jeep1.jpg"))],
        joints: 0,
        first_joints: &[],
        fps: 1.0,
        frames: 0,
    },
    Expect {
        file: "Wuson.ms3d",
        vertices: 2117,
        triangles: 3732,
        groups: 1,
        materials: &[],
        joints: 0,
        first_joints: &[],
        fps: 24.0,
        frames: 0,
    },
    Expect {
        file: "twospheres_withmats.ms3d",
        vertices: 124,
        triangles: 240,
        groups: 2,
        materials: &[("Material01", None), ("Material02", None)],
        joints: 0,
        first_joints: &[],
        fps: 24.0,
        frames: 0,
    },
];

#[test]
fn every_corpus_file_imports_with_its_content() {
    for e in FILES {
        let Some(bytes) = sinew_testdata::read_corpus(&format!("ms3d/{}", e.file)) else {
            return;
        };
        let s = import(&bytes, e.file).unwrap_or_else(|err| panic!("{err}"));
        assert_eq!(s.meshes.len(), 1, "{}", e.file);
        let m = &s.meshes[0];
        let g = &m.geometry;
        assert_eq!(m.source_vertex_count, e.vertices, "{}", e.file);
        assert_eq!(g.triangle_count(), e.triangles, "{}", e.file);
        assert_eq!(g.submeshes.len(), e.groups, "{}", e.file);
        // Every file vertex is used, each split copy maps back to it, and positions are the file's.
        let mut used = vec![false; e.vertices as usize];
        for &sv in &m.source_vertex {
            used[sv as usize] = true;
        }
        assert!(used.iter().all(|&u| u), "{}: unused file vertices", e.file);
        assert!(g.vertex_count() >= e.vertices as usize);
        let (mn, mx) = raw_bounds(&bytes);
        for k in 0..3 {
            let lo = g.positions.iter().map(|p| p[k]).fold(f32::MAX, f32::min);
            let hi = g.positions.iter().map(|p| p[k]).fold(f32::MIN, f32::max);
            assert_eq!((lo, hi), (mn[k], mx[k]), "{} bounds axis {k}", e.file);
        }
        for n in &g.normals {
            assert!((n.length() - 1.0).abs() < 1e-4);
        }
        let names: Vec<(&str, Option<&str>)> = s
            .materials
            .iter()
            .map(|m| (m.name.as_str(), m.texture.as_deref()))
            .collect();
        assert_eq!(names, e.materials, "{}", e.file);
        match &s.skeleton {
            None => {
                assert_eq!(e.joints, 0, "{}", e.file);
                assert!(s.clips.is_empty() && g.joints.is_empty());
            }
            Some(sk) => {
                assert_eq!(sk.len(), e.joints, "{}", e.file);
                assert_eq!(
                    &sk.names()[..e.first_joints.len()],
                    e.first_joints,
                    "{}",
                    e.file
                );
                assert_eq!(g.joints.len(), g.vertex_count());
                for w in &g.weights {
                    let sum: f32 = w.iter().sum();
                    assert!((sum - 1.0).abs() < 1e-5, "{}: weight sum {sum}", e.file);
                }
                let c = &s.clips[0];
                assert_eq!(c.sample_rate, e.fps);
                // Clip time 0 is frame 1; the last frame is at (frames - 1) / fps.
                let want = (e.frames - 1) as f32 / e.fps;
                assert!(
                    (c.duration - want).abs() < 1e-4,
                    "{}: {} vs {want}",
                    e.file,
                    c.duration
                );
                // Every frame is a key of every track.
                for t in &c.tracks {
                    assert!(t.rotation.times.len() >= e.frames as usize);
                }
            }
        }
        // Files whose two readings of the position keys agree raise no warning at all.
        if e.file != "cross.ms3d" {
            assert_eq!(s.warnings().count(), 0, "{}: {:?}", e.file, s.diagnostics);
        }
    }
}

#[test]
fn parsed_blocks_match_the_manifest() {
    let Some(b) = sinew_testdata::read_corpus("ms3d/ninja.ms3d") else {
        return;
    };
    let f = ms3d::parse("ninja.ms3d", &b).unwrap();
    let c = f.comments.as_ref().unwrap();
    assert_eq!(c.groups[0].text, "group  ninja comment test");
    assert_eq!(c.materials[0].text, "material 1 comment test");
    assert_eq!(
        (c.joints[0].index, c.joints[0].text.as_str()),
        (23, "joint23 comment test")
    );
    // Read without an index field, the model comment is the text; with one it would be garbage.
    assert_eq!(c.model.as_deref(), Some("model comment test"));
    assert_eq!(f.vertex_extra.as_ref().unwrap().sub_version, 2);
    assert_eq!(f.joint_extra.as_ref().unwrap().1.len(), 28);
    assert!(f.model_extra.is_some() && f.trailing.is_none());
    assert_eq!(f.total_frames, 300);

    let Some(b) = sinew_testdata::read_corpus("ms3d/animated_cylinder.ms3d") else {
        return;
    };
    let f = ms3d::parse("animated_cylinder.ms3d", &b).unwrap();
    for j in &f.joints {
        assert_eq!((j.rotation_keys.len(), j.position_keys.len()), (5, 5));
    }
    let x = f.vertex_extra.as_ref().unwrap();
    // 36 vertices use the extra weights; their stored weights sum to 100 (so the scale is 100).
    let extended: Vec<u32> = x
        .weights
        .iter()
        .filter(|w| w.iter().any(|&v| v > 0))
        .map(|w| w.iter().map(|&v| v as u32).sum())
        .collect();
    assert_eq!(extended.len(), 36);
    assert!(extended.iter().all(|&s| s == 100));
    assert!(f.joint_extra.is_none());

    // Sub-version 3 records are 14 bytes: with 14, Wuson's joint and model extra follow exactly.
    let Some(b) = sinew_testdata::read_corpus("ms3d/Wuson.ms3d") else {
        return;
    };
    let f = ms3d::parse("Wuson.ms3d", &b).unwrap();
    assert_eq!(f.vertex_extra.as_ref().unwrap().sub_version, 3);
    assert_eq!(f.model_extra.unwrap().sub_version, 1);
    assert!(f.trailing.is_none());
}

#[test]
fn cross_is_read_with_the_viewer_rule_and_others_need_no_decision() {
    let Some(b) = sinew_testdata::read_corpus("ms3d/cross.ms3d") else {
        return;
    };
    let s = import(&b, "cross.ms3d").unwrap();
    let d = s
        .diagnostics
        .iter()
        .find(|d| d.code == "ms3d-position-keys")
        .unwrap();
    assert!(d.message.contains("read as viewer"), "{}", d.message);
    assert!(d.message.contains("--ms3d-position-keys parent"));
    for f in ["ninja.ms3d", "animated_cylinder.ms3d", "zombie.ms3d"] {
        let b = sinew_testdata::read_corpus(&format!("ms3d/{f}")).unwrap();
        let s = import(&b, f).unwrap();
        let d = s
            .diagnostics
            .iter()
            .find(|d| d.code == "ms3d-position-keys")
            .unwrap();
        assert_eq!(d.level, Level::Info);
        assert!(
            d.message.contains("no decision was needed"),
            "{f}: {}",
            d.message
        );
    }
}

#[test]
fn the_damaged_wuson_names_the_block_and_offset() {
    let Some(b) = sinew_testdata::read_corpus("ms3d/malformed/Wuson_crlf_damaged.ms3d") else {
        return;
    };
    let e = import(&b, "Wuson_crlf_damaged.ms3d").unwrap_err();
    assert_eq!(e.file, "Wuson_crlf_damaged.ms3d");
    assert_eq!(e.section, "joints");
    let Location::Offset(o) = e.location else {
        panic!("{e}")
    };
    assert!(o > 298_000 && (o as usize) < b.len(), "{e}");
    assert!(e.message.contains("65280"), "{e}");
    assert!(e.to_string().contains("at byte"));
}

fn check_truncations(file: &str, from: usize, step: usize, ok_lengths: &[usize]) {
    let Some(b) = sinew_testdata::read_corpus(&format!("ms3d/{file}")) else {
        return;
    };
    let mut ok = Vec::new();
    let mut len = from;
    while len <= b.len() {
        match import(&b[..len], file) {
            Ok(_) => ok.push(len),
            Err(e) => {
                assert!(!e.section.is_empty());
                if let Location::Offset(o) = e.location {
                    assert!(o as usize <= len, "{file} cut at {len}: {e}");
                }
            }
        }
        len += step;
    }
    let expected: Vec<usize> = ok_lengths
        .iter()
        .copied()
        .filter(|&l| l >= from && (l - from) % step == 0)
        .collect();
    assert_eq!(ok, expected, "{file}: lengths that imported");
}

#[test]
fn every_truncation_of_cross_is_an_error_except_the_whole_file() {
    check_truncations("cross.ms3d", 0, 1, &[8375]);
}

#[test]
fn truncations_of_animated_cylinder_import_only_at_block_ends() {
    // Joints end at 14217, the comment block at 14237, the vertex extra block at the end (15101).
    check_truncations(
        "animated_cylinder.ms3d",
        14_000,
        1,
        &[14_217, 14_237, 15_101],
    );
    check_truncations("animated_cylinder.ms3d", 0, 37, &[14_217, 14_237, 15_101]);
}

#[test]
fn thousands_of_mutated_files_never_panic() {
    let start = std::time::Instant::now();
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let mut errors = 0;
    let mut total = 0;
    for file in ["cross.ms3d", "animated_cylinder.ms3d"] {
        let Some(b) = sinew_testdata::read_corpus(&format!("ms3d/{file}")) else {
            return;
        };
        for _ in 0..2500 {
            let mut m = b.clone();
            for _ in 0..1 + next() % 6 {
                let at = (next() % m.len() as u64) as usize;
                m[at] = match next() % 3 {
                    0 => m[at] ^ (1 << (next() % 8)),
                    1 => 0xFF,
                    _ => next() as u8,
                };
            }
            if next() % 4 == 0 {
                m.truncate((next() % m.len() as u64) as usize);
            }
            total += 1;
            if import(&m, file).is_err() {
                errors += 1;
            }
        }
    }
    assert_eq!(total, 5000);
    assert!(errors > 0);
    assert!(
        start.elapsed().as_secs() < 60,
        "mutation test took {:?}",
        start.elapsed()
    );
}
