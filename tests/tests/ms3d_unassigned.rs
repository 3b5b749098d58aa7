//! End-to-end: MS3D vertices without a joint (bone -1, no extra weights) stay where Milkshape leaves
//! them, in every baked frame and through `verify`, while every other vertex keeps the bits it had
//! before the change (when such vertices were bound wholly to the first root joint and walked away
//! with it).
//!
//! The fixture `fixtures/ms3d/unassigned_crate.ms3d` is the Biped walk with a crate beside it whose 8
//! vertices (file vertices 64..72) have no joint. The rest positions are read here from the MS3D bytes
//! themselves; the hash of the other vertices' baked positions was recorded with the binary built from
//! the commit before this change (main at e52a48a) by
//! `sinew bake fixtures/ms3d/unassigned_crate.ms3d --format pc2 --vertex-order source -o base.pc2`
//! (FNV-1a 64 over the f32 bytes of source vertices 0..64 of every frame). On that binary the crate
//! drifted up to 30 units (the root's walk).
#![allow(clippy::unwrap_used)] // unwrap is fine in tests

use crate::common;

use common::sinew;
use std::path::{Path, PathBuf};

/// FNV-1a 64 of the assigned vertices' baked positions, before the change (see the module docs).
const ASSIGNED_HASH_BEFORE: u64 = 0xf9a1_fe89_9ca0_d02d;
/// Source vertices 0..64 have joints; 64..72 have none.
const ASSIGNED: usize = 64;

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../fixtures/ms3d/unassigned_crate.ms3d")
}

/// The MS3D vertex block, read here: (position, bone id) per file vertex.
fn ms3d_vertices(bytes: &[u8]) -> Vec<([f32; 3], i8)> {
    let n = u16::from_le_bytes([bytes[14], bytes[15]]) as usize;
    (0..n)
        .map(|i| {
            let at = 16 + i * 15;
            let f = |k: usize| {
                f32::from_le_bytes(bytes[at + 1 + 4 * k..at + 5 + 4 * k].try_into().unwrap())
            };
            ([f(0), f(1), f(2)], bytes[at + 13] as i8)
        })
        .collect()
}

/// PC2 frames: (points, samples, positions).
fn read_pc2(bytes: &[u8]) -> (usize, usize, Vec<[f32; 3]>) {
    assert_eq!(&bytes[..12], b"POINTCACHE2\0");
    let i = |at: usize| i32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    let (points, samples) = (i(16), i(28));
    let pos = bytes[32..]
        .chunks_exact(12)
        .map(|c| {
            let f = |k: usize| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().unwrap());
            [f(0), f(1), f(2)]
        })
        .collect::<Vec<_>>();
    assert_eq!(pos.len(), points * samples);
    (points, samples, pos)
}

fn fnv1a(bytes: impl Iterator<Item = u8>) -> u64 {
    bytes.fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

#[test]
fn unassigned_vertices_stay_at_rest_and_the_others_keep_their_bits() {
    let src = fixture();
    let file = ms3d_vertices(&std::fs::read(&src).unwrap());
    assert_eq!(file.len(), 72);
    let unassigned: Vec<usize> = (0..file.len()).filter(|&v| file[v].1 < 0).collect();
    assert_eq!(unassigned, (ASSIGNED..72).collect::<Vec<_>>());

    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("crate.pc2");
    let run = sinew([
        "bake".as_ref(),
        src.as_os_str(),
        "--format".as_ref(),
        "pc2".as_ref(),
        "--vertex-order".as_ref(),
        "source".as_ref(),
        "-q".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(run.code, 0, "{}", run.stderr);
    let (points, samples, pos) = read_pc2(&std::fs::read(&out).unwrap());
    assert_eq!((points, samples), (72, 30));
    for f in 0..samples {
        for &v in &unassigned {
            assert_eq!(pos[f * points + v], file[v].0, "frame {f} vertex {v}");
        }
    }
    // The assigned vertices move (the walk), and keep the bits they had before the change.
    let moved = (0..ASSIGNED)
        .map(|v| {
            let (a, b) = (pos[v], pos[(samples - 1) * points + v]);
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .fold(0.0f32, f32::max);
    assert!(moved > 20.0, "the walk moves the body {moved} units");
    let hash = fnv1a((0..samples).flat_map(|f| {
        pos[f * points..f * points + ASSIGNED]
            .iter()
            .flat_map(|p| p.iter().flat_map(|x| x.to_le_bytes()))
            .collect::<Vec<_>>()
    }));
    assert_eq!(
        hash, ASSIGNED_HASH_BEFORE,
        "assigned vertices changed: {hash:#x}"
    );

    // verify re-bakes through the runtime and finds the same bits.
    let run = sinew([
        "verify".as_ref(),
        out.as_os_str(),
        "--against".as_ref(),
        src.as_os_str(),
    ]);
    assert_eq!(run.code, 0, "{}", run.stderr);

    // The skeleton shows the added static joint, and every pose keeps it at the origin.
    let pose = sinew([
        "inspect".as_ref(),
        src.as_os_str(),
        "--json".as_ref(),
        "--pose".as_ref(),
        "unassigned_crate@0..0.9666667".as_ref(),
    ]);
    assert_eq!(pose.code, 0, "{}", pose.stderr);
    let v: serde_json::Value = serde_json::from_str(&pose.stdout).unwrap();
    let joints = v["joints"].as_array().unwrap();
    assert_eq!(joints.len(), 8);
    assert_eq!(joints[7]["name"], "(unassigned)");
    assert!(joints[7]["parent"].is_null());
    for f in v["frames"].as_array().unwrap() {
        let m: Vec<f64> = f["joints"][7]["matrix"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        let identity = [
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        assert_eq!(m, identity);
    }
}

#[test]
fn unassigned_vertices_stay_at_rest_in_split_order_and_in_lod_1() {
    // The split vertex order and the LODs: every crate vertex (rest position from the OBJ written
    // beside the cache) is at rest in every frame of LOD 0 and LOD 1.
    let src = fixture();
    let dir = tempfile::tempdir().unwrap();
    for lod in ["0", "1"] {
        let out = dir.path().join(format!("crate{lod}.pc2"));
        let run = sinew([
            "bake".as_ref(),
            src.as_os_str(),
            "--format".as_ref(),
            "pc2".as_ref(),
            "--lod".as_ref(),
            lod.as_ref(),
            "-q".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
        ]);
        assert_eq!(run.code, 0, "{}", run.stderr);
        let (points, samples, pos) = read_pc2(&std::fs::read(&out).unwrap());
        let obj = std::fs::read_to_string(dir.path().join(format!("crate{lod}.pc2.obj"))).unwrap();
        let rest: Vec<[f32; 3]> = obj
            .lines()
            .filter_map(|l| l.strip_prefix("v "))
            .map(|l| {
                let v: Vec<f32> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
                [v[0], v[1], v[2]]
            })
            .collect();
        assert_eq!(rest.len(), points);
        // Crate vertices: x <= -12 (the body lies at x >= -8 at rest).
        let crate_vertices: Vec<usize> = (0..points).filter(|&v| rest[v][0] <= -12.0).collect();
        assert!(!crate_vertices.is_empty(), "LOD {lod}");
        for f in 0..samples {
            for &v in &crate_vertices {
                assert_eq!(
                    pos[f * points + v],
                    rest[v],
                    "LOD {lod} frame {f} vertex {v}"
                );
            }
        }
    }
}
