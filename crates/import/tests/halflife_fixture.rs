//! The MDL reader on the fixture generator's hand-specified `rig` (`sinew_fixtures::mdl::rig`, written
//! in memory as `rig.mdl` and its sequence group `rig01.mdl`). Every expected number is worked out by
//! hand from the rig's definition: scales 1/16 for positions and 1/1024 for angles, so every decoded
//! value is exact in f32.
#![allow(clippy::unwrap_used)]

use sinew_core::format::game::material_flags;
use sinew_core::glam::{EulerRot, Quat, Vec3};
use sinew_import::halflife::mdl;
use sinew_import::halflife::model::StudioModel;
use sinew_import::{import_bytes, Format, ImportOptions};
use std::f32::consts::FRAC_PI_2;

fn files() -> Vec<(String, Vec<u8>)> {
    sinew_fixtures::mdl::rig_files()
}

fn read_with(files: &[(String, Vec<u8>)], present: &[&str]) -> (StudioModel, Vec<String>) {
    read_allowing(files, present, true).unwrap()
}

/// [`read_with`], missing companions an error unless `allow_missing`.
fn read_allowing(
    files: &[(String, Vec<u8>)],
    present: &[&str],
    allow_missing: bool,
) -> Result<(StudioModel, Vec<String>), sinew_import::ImportError> {
    let resolve = |name: &str| {
        files
            .iter()
            .find(|(n, _)| n == name && present.contains(&name))
            .map(|(_, b)| b.clone())
            .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "not found"))
    };
    let (m, d) = mdl::read("fixtures/rig.mdl", &files[0].1, &resolve, allow_missing)?;
    Ok((m, d.into_iter().map(|d| d.message).collect()))
}

#[test]
fn skeleton_and_bind_pose() {
    let (m, _) = read_with(&files(), &["rig01.mdl"]);
    let names: Vec<_> = m.bones.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["root", "arm", "hand"]);
    assert_eq!(m.bones[0].value, [0.0, 0.0, 10.0, 0.0, 0.0, FRAC_PI_2]);
    assert_eq!(m.controllers[0].bone, 1);
    assert_eq!(m.hitboxes[0].0, 2);
    assert_eq!(m.attachments[0].2, [0.5, 0.0, 0.0]);
    assert_eq!(m.eye_position, Some([0.0, 0.0, 12.0]));
    // root yaws a quarter turn about +z, so arm's offset (4, 0, 0) lands on +y: arm at (0, 4, 10);
    // arm pitches a quarter turn about its y, so hand's offset (3, 0, 0) turns to (0, 0, -3): hand at
    // (0, 4, 7). The scene's skeleton must put them there.
    let none = |_: &str| -> std::io::Result<Vec<u8>> { Err(std::io::Error::other("no")) };
    let allow = ImportOptions {
        allow_missing: true,
        ..ImportOptions::default()
    };
    let scene = import_bytes(Format::Mdl, "rig.mdl", &files()[0].1, &none, &allow).unwrap();
    let sk = scene.skeleton.as_ref().unwrap();
    let world: Vec<Vec3> = sk
        .inverse_bind()
        .iter()
        .map(|m| m.inverse().transform_point3(Vec3::ZERO))
        .collect();
    assert!(
        world[1].abs_diff_eq(Vec3::new(0.0, 4.0, 10.0), 1e-5),
        "{:?}",
        world[1]
    );
    assert!(
        world[2].abs_diff_eq(Vec3::new(0.0, 4.0, 7.0), 1e-5),
        "{:?}",
        world[2]
    );
}

#[test]
fn sequences_decode_runs_held_values_and_constants() {
    let (m, d) = read_with(&files(), &["rig01.mdl"]);
    assert!(d.is_empty(), "{d:?}");
    let idle = &m.sequences[0];
    assert_eq!(
        (idle.label.as_str(), idle.blends[0].len(), idle.looping),
        ("idle", 1, false)
    );
    // idle: root z = 10 + 16 / 16.
    assert_eq!(idle.blends[0][0][0][2], 11.0);
    let wave = &m.sequences[1];
    assert_eq!(
        (wave.label.as_str(), wave.fps, wave.blends[0].len()),
        ("wave", 10.0, 5)
    );
    assert!(wave.looping);
    assert_eq!((wave.nodes.0, wave.nodes.1), (1, 2));
    assert_eq!(wave.events, [(2, 5004, 0, "hand".to_string())]);
    let frames = &wave.blends[0];
    // root z: one run of 1 value over 5 frames: 10 + 32 / 16 = 12 throughout.
    assert!(frames.iter().all(|f| f[0][2] == 12.0));
    // arm zr: 0, 100, 200 and 200 held: k / 1024; arm yr keeps its default, a quarter turn.
    let arm_zr: Vec<f32> = frames.iter().map(|f| f[1][5]).collect();
    assert_eq!(
        arm_zr,
        [
            0.0,
            100.0 / 1024.0,
            200.0 / 1024.0,
            200.0 / 1024.0,
            200.0 / 1024.0
        ]
    );
    assert!(frames.iter().all(|f| f[1][4] == FRAC_PI_2));
    // hand xr: runs (-50, 50) then 7 held, over a default of 0.25: 206/1024, 306/1024, 263/1024 x3.
    let hand_xr: Vec<f32> = frames.iter().map(|f| f[2][3]).collect();
    assert_eq!(
        hand_xr,
        [
            206.0 / 1024.0,
            306.0 / 1024.0,
            263.0 / 1024.0,
            263.0 / 1024.0,
            263.0 / 1024.0
        ]
    );
    // In the scene, the wave clip's arm rotation at frame 1 is Rz(100/1024) Ry(pi/2) Rx(0).
    let none = |_: &str| -> std::io::Result<Vec<u8>> { Err(std::io::Error::other("no")) };
    let files = files();
    let resolve = |n: &str| {
        files
            .iter()
            .find(|(f, _)| f == n)
            .map(|(_, b)| b.clone())
            .ok_or_else(|| std::io::Error::other("no"))
    };
    let scene = import_bytes(
        Format::Mdl,
        "rig.mdl",
        &files[0].1,
        &resolve,
        &ImportOptions::default(),
    )
    .unwrap();
    let clip = scene.clip("wave").unwrap();
    let q = clip.tracks[1].rotation.values[1];
    let expected = Quat::from_euler(EulerRot::ZYX, 100.0 / 1024.0, FRAC_PI_2, 0.0);
    assert!(q.dot(expected).abs() > 1.0 - 1e-6, "{q} {expected}");
    assert!((clip.duration - 0.4).abs() < 1e-6);
    let _ = none;
}

#[test]
fn strip_fan_texture_and_transitions() {
    let (m, _) = read_with(&files(), &["rig01.mdl"]);
    let part = &m.body_parts[0];
    assert_eq!(part.name, "body");
    let names: Vec<_> = part.submodels.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["full", "blank"]);
    assert!(part.submodels[1].vertices.is_empty());
    let full = &part.submodels[0];
    let bones: Vec<usize> = full.vertices.iter().map(|v| v.influences[0].0).collect();
    assert_eq!(bones, [1, 1, 1, 2, 2]);
    // Stored strip 0 1 2 3: (0,1,2) (2,1,3); fan 4 0 1 3 2: (4,0,1) (4,1,3) (4,3,2) — each turned
    // back to counter-clockwise.
    let tris: Vec<[usize; 3]> = full.meshes[0]
        .triangles
        .iter()
        .map(|t| [t[0].vertex, t[1].vertex, t[2].vertex])
        .collect();
    assert_eq!(
        tris,
        [[2, 1, 0], [3, 1, 2], [1, 0, 4], [3, 1, 4], [2, 3, 4]]
    );
    // Stored corners (vertex 1, s 3, t 0) and (vertex 2, s 0, t 1) of the 4 x 2 texture.
    let corner = |v: usize| {
        full.meshes[0].triangles[0]
            .iter()
            .find(|c| c.vertex == v)
            .unwrap()
            .uv
    };
    assert_eq!(corner(1), [0.75, 0.0]);
    assert_eq!(corner(2), [0.0, 0.5]);
    let t = &m.textures[0];
    assert_eq!((t.name.as_str(), t.width, t.height), ("skin.bmp", 4, 2));
    assert_eq!(t.flags, material_flags::ADDITIVE);
    assert_eq!(t.indices, [0, 1, 2, 3, 252, 253, 254, 255]);
    assert_eq!(&t.palette[600..603], [200, 55, 100]);
    assert_eq!(m.skin_families, [vec![0]]);
    assert_eq!(m.transitions, [0, 2, 1, 0]);
}

#[test]
fn a_missing_group_file_leaves_out_only_its_sequences() {
    // By default it is an error naming the file and the sequence that needs it.
    let e = read_allowing(&files(), &[], false).unwrap_err();
    assert_eq!(e.file, "fixtures/rig.mdl");
    assert!(e.section.starts_with("sequences["), "{e}");
    assert!(
        e.message.contains("rig01.mdl") && e.message.contains("wave"),
        "{e}"
    );
    let (m, d) = read_with(&files(), &[]);
    assert_eq!(d.len(), 1);
    assert!(d[0].contains("rig01.mdl") && d[0].contains("wave"), "{d:?}");
    assert_eq!(m.sequences[0].blends.len(), 1);
    assert!(m.sequences[1].blends.is_empty());
    assert_eq!(m.textures.len(), 1);
    assert_eq!(m.body_parts[0].submodels[0].meshes[0].triangles.len(), 5);
}
