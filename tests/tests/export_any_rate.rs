//! What a glTF viewer plays of `sinew export` is what the runtime plays, at frame rates that are not the
//! clip's own: the export is read here by a small glTF reader of its own (GLB chunks, float
//! accessors, node TRS, `LINEAR` channels interpolated as the glTF spec says: lerp for translation and
//! scale, slerp for rotation), posed at every frame of `sinew bake --fps F`, skinned with the plain
//! skinning of `sinew_testdata::geometry`, and compared with the bake vertex by vertex. The rest pose
//! (nodes as written, no animation) is compared with the runtime's bind pose the same way.
#![allow(clippy::unwrap_used)]

use crate::common;
use common::sinew;
use serde_json::Value;
use sinew_core::format::{self, Asset};
use sinew_core::glam::{DQuat, Quat, Vec3};
use sinew_core::Transform;
use sinew_testdata::geometry::{diagonal, model_matrices, skin_positions};
use std::path::{Path, PathBuf};

/// The largest distance a viewer may be from the runtime, relative to the bind-pose diagonal.
const LIMIT: f32 = 1e-5;

/// A GLB split into its JSON and binary chunks.
struct Glb {
    json: Value,
    bin: Vec<u8>,
}

fn read_glb(bytes: &[u8]) -> Glb {
    assert_eq!(&bytes[0..4], b"glTF");
    let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as usize;
    let json_len = u32_at(12);
    assert_eq!(&bytes[16..20], b"JSON");
    let json = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let b = 20 + json_len;
    let bin_len = u32_at(b);
    assert_eq!(&bytes[b + 4..b + 8], b"BIN\0");
    Glb {
        json,
        bin: bytes[b + 8..b + 8 + bin_len].to_vec(),
    }
}

impl Glb {
    /// A float accessor's values (tightly packed: sinew writes no byte stride on these).
    fn floats(&self, accessor: u64) -> Vec<f32> {
        let a = &self.json["accessors"][accessor as usize];
        assert_eq!(a["componentType"], 5126, "float accessor");
        let per = match a["type"].as_str().unwrap() {
            "SCALAR" => 1,
            "VEC3" => 3,
            "VEC4" => 4,
            "MAT4" => 16,
            t => panic!("type {t}"),
        };
        let view = &self.json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        assert!(view
            .get("byteStride")
            .is_none_or(|s| s.as_u64() == Some(per * 4)));
        let start =
            view["byteOffset"].as_u64().unwrap_or(0) + a["byteOffset"].as_u64().unwrap_or(0);
        let n = a["count"].as_u64().unwrap() * per;
        (0..n)
            .map(|i| {
                let o = (start + 4 * i) as usize;
                f32::from_le_bytes(self.bin[o..o + 4].try_into().unwrap())
            })
            .collect()
    }

    /// Node `i`'s translation, rotation and scale as written.
    fn node_trs(&self, i: usize) -> Transform {
        let n = &self.json["nodes"][i];
        let f = |k: &str, d: &[f32]| -> Vec<f32> {
            n.get(k).map_or(d.to_vec(), |v| {
                v.as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap() as f32)
                    .collect()
            })
        };
        let t = f("translation", &[0.0; 3]);
        let r = f("rotation", &[0.0, 0.0, 0.0, 1.0]);
        let s = f("scale", &[1.0; 3]);
        Transform {
            translation: Vec3::new(t[0], t[1], t[2]),
            rotation: Quat::from_xyzw(r[0], r[1], r[2], r[3]),
            scale: Vec3::new(s[0], s[1], s[2]),
        }
    }
}

/// One animation channel: target node, path and its keys.
struct Channel {
    node: usize,
    path: String,
    times: Vec<f32>,
    values: Vec<f32>,
}

fn channels(glb: &Glb, animation: &str) -> Vec<Channel> {
    let a = glb.json["animations"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["name"] == animation)
        .unwrap_or_else(|| panic!("no animation {animation}"));
    a["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let s = &a["samplers"][c["sampler"].as_u64().unwrap() as usize];
            assert_eq!(s["interpolation"].as_str().unwrap_or("LINEAR"), "LINEAR");
            Channel {
                node: c["target"]["node"].as_u64().unwrap() as usize,
                path: c["target"]["path"].as_str().unwrap().to_string(),
                times: glb.floats(s["input"].as_u64().unwrap()),
                values: glb.floats(s["output"].as_u64().unwrap()),
            }
        })
        .collect()
}

/// Slerp along the shorter arc, in f64 (the glTF spec's rotation interpolation); the angle from
/// `atan2`, which stays exact for keys a few ulps apart (where `acos` of the dot product is not).
fn slerp(a: Quat, b: Quat, f: f64) -> Quat {
    let (a, mut b) = (a.as_dquat().normalize(), b.as_dquat().normalize());
    if a.dot(b) < 0.0 {
        b = -b;
    }
    let theta = 2.0 * (a - b).length().atan2((a + b).length());
    let q: DQuat = if theta < 1e-9 {
        a
    } else {
        a * (((1.0 - f) * theta).sin() / theta.sin()) + b * ((f * theta).sin() / theta.sin())
    };
    q.normalize().as_quat()
}

/// A channel's value at `t` as a glTF viewer computes it (clamped at both ends).
fn sample(c: &Channel, t: f32, out: &mut Transform) {
    let per = c.values.len() / c.times.len();
    let get = |k: usize| &c.values[k * per..(k + 1) * per];
    let k = c.times.partition_point(|&x| x <= t);
    let (a, b, f) = if k == 0 {
        (0, 0, 0.0)
    } else if k >= c.times.len() {
        (k - 1, k - 1, 0.0)
    } else {
        let f = f64::from(t - c.times[k - 1]) / f64::from(c.times[k] - c.times[k - 1]);
        (k - 1, k, f)
    };
    let (va, vb) = (get(a), get(b));
    match c.path.as_str() {
        "rotation" => {
            let qa = Quat::from_xyzw(va[0], va[1], va[2], va[3]);
            let qb = Quat::from_xyzw(vb[0], vb[1], vb[2], vb[3]);
            out.rotation = slerp(qa, qb, f);
        }
        p => {
            let v = Vec3::from_slice(va)
                .as_dvec3()
                .lerp(Vec3::from_slice(vb).as_dvec3(), f);
            if p == "translation" {
                out.translation = v.as_vec3();
            } else {
                out.scale = v.as_vec3();
            }
        }
    }
}

fn asset(path: &Path) -> Asset {
    let bytes = if path.extension().is_some_and(|e| e == "sinew") {
        std::fs::read(path).unwrap()
    } else {
        let scene = sinew_import::import_path(path, &Default::default()).unwrap();
        sinew_pipeline::compile::compile_to_bytes(&scene).unwrap()
    };
    format::read(&bytes).unwrap()
}

fn run(args: &[&std::ffi::OsStr]) {
    let r = sinew(args);
    assert_eq!(r.code, 0, "{args:?}: {}", r.stderr);
}

/// Exports `input`, bakes `clip` at each of `rates`, and returns the largest viewer-to-runtime
/// distance over every frame (relative to the diagonal) per rate, and the rest pose's.
fn measure(input: &Path, clip: &str, rates: &[f32]) -> (Vec<f32>, f32) {
    let dir = tempfile::tempdir().unwrap();
    let glb_path = dir.path().join("out.glb");
    run(&[
        "export".as_ref(),
        input.as_os_str(),
        "-o".as_ref(),
        glb_path.as_os_str(),
        "-q".as_ref(),
    ]);
    let glb = read_glb(&std::fs::read(&glb_path).unwrap());
    let a = asset(input);
    let skeleton = a.skeleton.as_ref().unwrap();
    let lod = &a.meshes[0].lods[0];
    let diag = diagonal(&lod.positions);
    let rest: Vec<Transform> = (0..skeleton.len()).map(|j| glb.node_trs(j)).collect();
    let distance = |p: &[Vec3], q: &[Vec3]| {
        p.iter()
            .zip(q)
            .map(|(a, b)| a.distance(*b))
            .fold(0.0f32, f32::max)
            / diag
    };
    let rest_err = distance(
        &skin_positions(lod, skeleton, &model_matrices(skeleton, &rest)),
        &skin_positions(
            lod,
            skeleton,
            &model_matrices(skeleton, skeleton.bind_local()),
        ),
    );
    let chans = channels(&glb, clip);
    let c = a.clips.iter().find(|c| c.name() == clip).unwrap();
    let mut worst = Vec::new();
    for &fps in rates {
        let pc2 = dir.path().join(format!("{fps}.pc2"));
        let fps_s = fps.to_string();
        run(&[
            "bake".as_ref(),
            input.as_os_str(),
            "--clip".as_ref(),
            clip.as_ref(),
            "--fps".as_ref(),
            fps_s.as_ref(),
            "--format".as_ref(),
            "pc2".as_ref(),
            "-o".as_ref(),
            pc2.as_os_str(),
            "-q".as_ref(),
        ]);
        let (_, frames) = sinew_pipeline::cache::pc2::read(&std::fs::read(&pc2).unwrap()).unwrap();
        let n = frames.frame_count;
        assert_eq!(n, sinew_pipeline::bake::frame_count(c.duration(), fps));
        let nv = frames.vertex_count;
        let mut w = 0.0f32;
        for i in 0..n {
            let t = sinew_pipeline::bake::frame_time(i, n, c.duration(), fps);
            let mut locals = rest.clone();
            for ch in &chans {
                sample(ch, t, &mut locals[ch.node]);
            }
            let viewer = skin_positions(lod, skeleton, &model_matrices(skeleton, &locals));
            w = w.max(distance(&viewer, &frames.positions[i * nv..(i + 1) * nv]));
        }
        worst.push(w);
    }
    (worst, rest_err)
}

fn convert(input: &Path, out: &Path, extra: &[&str]) {
    let mut args: Vec<&std::ffi::OsStr> =
        vec!["convert".as_ref(), input.as_os_str(), "-o".as_ref()];
    args.push(out.as_os_str());
    args.push("-q".as_ref());
    args.extend(extra.iter().map(|s| std::ffi::OsStr::new(*s)));
    run(&args);
}

fn check(label: &str, input: &Path, clip: &str, rates: &[f32]) {
    let (worst, rest) = measure(input, clip, rates);
    eprintln!("{label}: {clip} at {rates:?} fps: {worst:?} of the diagonal; rest {rest:e}");
    assert!(rest <= LIMIT, "{label}: rest pose {rest:e}");
    for (fps, w) in rates.iter().zip(&worst) {
        assert!(
            *w <= LIMIT,
            "{label}: {clip} at {fps} fps: {w:e} of the diagonal"
        );
    }
}

#[test]
fn a_24_fps_clip_plays_the_runtime_at_30_and_60_fps_compressed_or_not() {
    let Some(zombie) = sinew_testdata::corpus_file("ms3d/zombie.ms3d") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let compressed = dir.path().join("zombie.sinew");
    let plain = dir.path().join("zombie_plain.sinew");
    convert(&zombie, &compressed, &["--lod", "none"]);
    convert(&zombie, &plain, &["--lod", "none", "--no-compress"]);
    assert!(asset(&compressed).clips[0].is_compressed());
    assert!(!asset(&plain).clips[0].is_compressed());
    check("zombie.ms3d", &zombie, "zombie", &[30.0, 60.0]);
    check(
        "zombie.sinew (compressed)",
        &compressed,
        "zombie",
        &[30.0, 60.0],
    );
    check(
        "zombie.sinew (--no-compress)",
        &plain,
        "zombie",
        &[30.0, 60.0],
    );
}

#[test]
fn a_37_5_hz_clip_plays_the_runtime_at_30_fps() {
    // zombie.ms3d with its animation rate set to 37.5 (the file's `animationFps` after the
    // materials): the same keys at other times, a rate nothing was tuned for.
    let Some(bytes) = sinew_testdata::read_corpus("ms3d/zombie.ms3d") else {
        return;
    };
    let mut b = bytes.clone();
    let u16_at = |b: &[u8], o: usize| u16::from_le_bytes([b[o], b[o + 1]]) as usize;
    let mut o = 14;
    o += 2 + u16_at(&b, o) * 15;
    o += 2 + u16_at(&b, o) * 70;
    let groups = u16_at(&b, o);
    o += 2;
    for _ in 0..groups {
        o += 1 + 32;
        o += 2 + 2 * u16_at(&b, o) + 1;
    }
    o += 2 + u16_at(&b, o) * 361;
    assert_eq!(f32::from_le_bytes(b[o..o + 4].try_into().unwrap()), 24.0);
    b[o..o + 4].copy_from_slice(&37.5f32.to_le_bytes());
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("zombie375.ms3d");
    std::fs::write(&src, &b).unwrap();
    assert_eq!(asset(&src).clips[0].sample_rate(), 37.5);
    let compressed = dir.path().join("zombie375.sinew");
    convert(&src, &compressed, &["--lod", "none"]);
    check("zombie375.ms3d", &src, "zombie375", &[30.0]);
    check(
        "zombie375.sinew (compressed)",
        &compressed,
        "zombie375",
        &[30.0],
    );
}

#[test]
fn a_30_fps_looping_clip_plays_the_runtime_at_24_and_60_fps() {
    // The biped's walk loops and its last key is not its first pose: the runtime jumps at the
    // duration, which the export must keep.
    let biped: PathBuf = sinew_testdata::fixtures().join("biped.sinew");
    check("biped.sinew", &biped, "walk", &[24.0, 60.0]);
    check("biped.sinew", &biped, "wave", &[24.0]);
}

#[test]
fn corpus_characters_play_the_runtime_at_other_rates() {
    // A glTF (24 fps, slerp keys turned into nlerp keys on import) and a Half-Life model (a looping
    // 30 fps walk, Z-up).
    for (file, clip, rates) in [
        ("gltf/CesiumMan.glb", "animation0", &[30.0, 60.0][..]),
        ("mdl/man.mdl", "walk", &[24.0, 60.0][..]),
    ] {
        let Some(path) = sinew_testdata::corpus_file(file) else {
            return;
        };
        check(file, &path, clip, rates);
    }
}
