//! Half-Life MDL and SMD import on the shared corpus. Expected values were read from the files' bytes
//! by hand (a hex dump and the layout in docs/formats/halflife.md), not by running the importer.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use sinew_core::format::game::{material_flags, motion_flags};
use sinew_core::glam::{EulerRot, Quat, Vec3};
use sinew_import::{import_bytes, import_path, Format, ImportOptions, Location};
use sinew_scene::Scene;
use sinew_testdata::{corpus_file, read_corpus};

fn import(rel: &str) -> Option<Scene> {
    let path = corpus_file(rel)?;
    Some(import_path(&path, &ImportOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}")))
}

/// Fraction of triangles whose face normal (counter-clockwise corners) points the way of their
/// corner normals.
fn front_facing(scene: &Scene) -> f32 {
    let (mut good, mut all) = (0, 0);
    for m in &scene.meshes {
        let g = &m.geometry;
        for t in g.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| g.positions[i as usize]);
            let face = (b - a).cross(c - a);
            let n = g.normals[t[0] as usize] + g.normals[t[1] as usize] + g.normals[t[2] as usize];
            if face.length() > 1e-6 {
                all += 1;
                if face.dot(n) > 0.0 {
                    good += 1;
                }
            }
        }
    }
    good as f32 / all.max(1) as f32
}

#[test]
fn mdl_triangles_face_the_way_of_their_normals() {
    for f in [
        "man.mdl",
        "chrome_sphere.mdl",
        "alpha_test.mdl",
        "sequence_transitions.mdl",
    ] {
        let Some(s) = import(&format!("mdl/{f}")) else {
            return;
        };
        assert_eq!(front_facing(&s), 1.0, "{f}");
    }
}

#[test]
fn man_mdl_skeleton_meshes_and_companions() {
    let Some(s) = import("mdl/man.mdl") else {
        return;
    };
    let sk = s.skeleton.as_ref().unwrap();
    assert_eq!(
        sk.names(),
        ["Root", "Pelvis", "RightLeg", "LeftLeg", "Spine", "RightArm", "LeftArm", "Neck"]
    );
    let parents: Vec<Option<u16>> = sk.parents().to_vec();
    assert_eq!(
        parents,
        [
            None,
            Some(0),
            Some(1),
            Some(1),
            Some(1),
            Some(4),
            Some(4),
            Some(4)
        ]
    );
    // Pelvis default position y: f32 bits at bone 1, value[1] (file offset 244 + 112 + 68).
    assert_eq!(
        sk.bind_local()[1].translation,
        Vec3::new(0.0, f32::from_bits(0x4081_ADB8), 0.0)
    );
    // Root default rotation: x = 1.5708 (90 degrees), y = -0, z = 0.
    let root = sk.bind_local()[0].rotation;
    assert!(root.angle_between(Quat::from_rotation_x(std::f32::consts::FRAC_PI_2)) < 1e-3);

    // Every submodel is a mesh of its own: reference_headless (40 vertices) of body part "studio",
    // and the three choices of "heads" (8, 5 and 58 vertices); the body groups name them.
    let names: Vec<&str> = s.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "studio/reference_headless",
            "heads/reference_head1",
            "heads/reference_head2",
            "heads/reference_head3"
        ]
    );
    let sources: Vec<u32> = s.meshes.iter().map(|m| m.source_vertex_count).collect();
    assert_eq!(sources, [40, 8, 5, 58]);
    let tris: Vec<usize> = s
        .meshes
        .iter()
        .map(|m| m.geometry.indices.len() / 3)
        .collect();
    // The default body (headless + head1) has the 72 triangles the merged mesh had.
    assert_eq!(tris, [60, 12, 6, 112]);
    // Textures came from manT.mdl: five images at their stored sizes.
    let images: Vec<(&str, u32, u32)> = s
        .images
        .iter()
        .map(|i| (i.name.as_str(), i.width, i.height))
        .collect();
    assert_eq!(
        images,
        [
            ("Material2.bmp", 28, 32),
            ("Material3.bmp", 28, 32),
            ("Material1.bmp", 32, 32),
            ("UpperBody_Yellow.bmp", 28, 32),
            ("LowerBody_Purple.bmp", 28, 32),
        ]
    );
    // Skin table of manT.mdl: [0, 1, 2, 3, 4, 2] over 3 slots and 2 families.
    assert_eq!(
        s.game.skin_families,
        [
            vec!["Material2.bmp", "Material3.bmp", "Material1.bmp"],
            vec![
                "UpperBody_Yellow.bmp",
                "LowerBody_Purple.bmp",
                "Material1.bmp"
            ],
        ]
    );
    let groups: Vec<(&str, Vec<&str>)> = s
        .game
        .body_groups
        .iter()
        .map(|g| {
            (
                g.name.as_str(),
                g.meshes.iter().map(String::as_str).collect(),
            )
        })
        .collect();
    assert_eq!(
        groups,
        [
            ("studio", vec!["studio/reference_headless"]),
            (
                "heads",
                vec![
                    "heads/reference_head1",
                    "heads/reference_head2",
                    "heads/reference_head3"
                ]
            ),
        ]
    );
}

#[test]
fn man_mdl_sequences_and_game_data() {
    let Some(s) = import("mdl/man.mdl") else {
        return;
    };
    let clips: Vec<(&str, f32, usize, bool)> = s
        .clips
        .iter()
        .map(|c| {
            (
                c.name.as_str(),
                c.sample_rate,
                c.tracks[0].rotation.times.len(),
                c.looping,
            )
        })
        .collect();
    assert_eq!(
        clips,
        [
            ("reference", 30.0, 2, false),
            ("walk", 30.0, 26, true),
            ("arms_up.blend0", 25.0, 2, false),
            ("arms_up.blend1", 25.0, 2, false),
            ("arms_up.blend2", 25.0, 2, false),
            ("arms_up.blend3", 25.0, 2, false),
        ]
    );
    let walk = s.clip("walk").unwrap();
    assert!((walk.duration - 25.0 / 30.0).abs() < 1e-6);
    // Root z rotation in walk: one run of 26 frames holding the value 32767, scale 9.587672e-5.
    let rz = 0.0f32 + 32767.0 * 9.587_672e-5;
    let r = walk.tracks[0].rotation.values[7].to_euler(EulerRot::ZYX).0;
    assert!((r - rz).abs() < 1e-5, "{r} {rz}");
    // RightLeg x rotation at frame 5: default 1.570804 + 7561 x 1.3316206e-5.
    let rx = 1.570_804_f32 + 7561.0 * 1.331_620_6e-5;
    let q = walk.tracks[2].rotation.values[5];
    let expected = Quat::from_euler(EulerRot::ZYX, -std::f32::consts::FRAC_PI_2, 0.022_526, rx);
    let (_, _, got_x) = q.to_euler(EulerRot::ZYX);
    assert!(
        (got_x - rx).abs() < 1e-4 || q.angle_between(expected) < 1e-3,
        "{got_x} {rx}"
    );

    let g = &s.game;
    assert_eq!(g.eye_position, Some([-0.0, 0.0, 72.0]));
    let att: Vec<(&str, [f32; 3])> = g
        .attachments
        .iter()
        .map(|a| (a.joint.as_str(), a.offset))
        .collect();
    assert_eq!(
        att,
        [("LeftArm", [0.0, 3.5, 0.0]), ("RightArm", [0.0, 3.5, 0.0])]
    );
    let ctl: Vec<(i32, &str, u32, f32, f32)> = g
        .controllers
        .iter()
        .map(|c| (c.index, c.joint.as_str(), c.channel, c.start, c.end))
        .collect();
    assert_eq!(
        ctl,
        [
            (0, "Neck", motion_flags::YR, -60.0, 60.0),
            (1, "Neck", motion_flags::ZR, -45.0, 45.0),
            (2, "Neck", motion_flags::Y, 0.0, 5.0),
        ]
    );
    let hb: Vec<(&str, i32)> = g
        .hitboxes
        .iter()
        .map(|h| (h.joint.as_str(), h.group))
        .collect();
    assert_eq!(
        hb,
        [
            ("LeftArm", 4),
            ("RightArm", 5),
            ("Spine", 2),
            ("Neck", 1),
            ("LeftLeg", 6),
            ("RightLeg", 7)
        ]
    );
    let w = g.clip("walk").unwrap();
    assert_eq!(
        (w.activity, w.motion_type, w.motion_joint.as_str()),
        (3, motion_flags::LX, "Root")
    );
    let ev: Vec<(i32, i32, &str)> = w
        .events
        .iter()
        .map(|e| (e.frame, e.event, e.options.as_str()))
        .collect();
    assert_eq!(
        ev,
        [
            (0, 1004, "common/npc_step1.wav"),
            (13, 1004, "common/npc_step3.wav")
        ]
    );
    let b = g.clip("arms_up.blend2").unwrap().blend.clone().unwrap();
    assert_eq!((b.sequence.as_str(), b.index, b.count), ("arms_up", 2, 4));
    assert_eq!(
        (b.types, b.start, b.end),
        ([motion_flags::YR, 0], [-30.0, 0.0], [30.0, 0.0])
    );
}

#[test]
fn texture_flags_and_masked_pixels() {
    let Some(s) = import("mdl/chrome_sphere.mdl") else {
        return;
    };
    assert_eq!(s.game.material_flags.len(), 1);
    assert_eq!(
        s.game.material_flags[0].flags,
        material_flags::FLATSHADE | material_flags::CHROME
    );
    let Some(s) = import("mdl/alpha_test.mdl") else {
        return;
    };
    assert_eq!(s.game.material_flags[0].flags, material_flags::MASKED);
    let img = &s.images[0];
    assert_eq!((img.width, img.height), (512, 512));
    // Pixel (0, 0) is palette index 255 (blue, transparent when masked); (256, 256) is index 249, red.
    let px = |x: usize, y: usize| &img.rgba[4 * (y * 512 + x)..4 * (y * 512 + x) + 4];
    assert_eq!(px(0, 0), [0, 0, 255, 0]);
    assert_eq!(px(256, 256), [255, 0, 0, 255]);
}

#[test]
fn transitions_and_nodes() {
    let Some(s) = import("mdl/sequence_transitions.mdl") else {
        return;
    };
    assert_eq!(s.clips.len(), 7);
    assert_eq!(s.game.transition_nodes, 4);
    assert_eq!(
        s.game.transitions,
        [0, 2, 2, 2, 0, 0, 3, 3, 0, 0, 0, 4, 0, 0, 0, 0]
    );
    let idle6 = s.game.clip("idle6").unwrap();
    assert_eq!((idle6.entry_node, idle6.exit_node), (2, 3));
}

#[test]
fn a_missing_companion_is_an_error_naming_it_or_with_allow_missing_a_warning() {
    let Some(bytes) = read_corpus("mdl/man.mdl") else {
        return;
    };
    let none = |_: &str| -> std::io::Result<Vec<u8>> {
        Err(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "not here",
        ))
    };
    // man.mdl keeps its textures in manT.mdl (its texture count, at byte 180, is 0): the game
    // cannot load it without, nor does sinew by default.
    let e = import_bytes(
        Format::Mdl,
        "man.mdl",
        &bytes,
        &none,
        &ImportOptions::default(),
    )
    .unwrap_err();
    assert_eq!(
        (e.file.as_str(), e.section.as_str(), &e.location),
        ("man.mdl", "textures", &Location::Offset(180)),
        "{e}"
    );
    assert!(
        e.message.contains("manT.mdl") && e.message.contains("not here"),
        "{e}"
    );
    // What the header names, used or not (no sequence of man.mdl is in group 1).
    assert_eq!(
        sinew_import::halflife::mdl::companions("models/man.mdl", &bytes).unwrap(),
        ["manT.mdl", "man01.mdl"]
    );
    let allowed = ImportOptions {
        allow_missing: true,
        ..ImportOptions::default()
    };
    let s = import_bytes(Format::Mdl, "man.mdl", &bytes, &none, &allowed).unwrap();
    let w: Vec<&str> = s.warnings().map(|d| d.message.as_str()).collect();
    assert!(w.iter().any(|m| m.contains("manT.mdl")), "{w:?}");
    assert!(s.images.is_empty());
    // Everything else is there.
    assert_eq!(s.skeleton.as_ref().unwrap().len(), 8);
    assert_eq!(s.clips.len(), 6);
    assert_eq!(s.meshes.len(), 4);
}

#[test]
fn smd_corpus_files() {
    let Some(s) = import("smd/triangle.smd") else {
        return;
    };
    assert_eq!(s.skeleton.as_ref().unwrap().names(), ["TriangleTest0"]);
    let g = &s.meshes[0].geometry;
    assert_eq!(g.indices.len(), 3);
    assert_eq!(g.submeshes[0].material, "none.quak");
    // uv (0,0) (1,0) (1,1) as written, v flipped to the top-left origin.
    let uvs: Vec<[f32; 2]> = g
        .indices
        .iter()
        .map(|&i| g.uvs[i as usize].to_array())
        .collect();
    assert_eq!(uvs, [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0]]);
    let n = g.normals[0];
    assert!((n - Vec3::splat(1.0 / 3f32.sqrt())).length() < 1e-6);
    assert!(s.clips.is_empty());

    let Some(s) = import("smd/holy_grailref.smd") else {
        return;
    };
    let sk = s.skeleton.as_ref().unwrap();
    assert_eq!(sk.names(), ["Cylinder01"]);
    assert_eq!(
        sk.bind_local()[0].translation,
        Vec3::new(0.0, 0.0, 6.268408)
    );
    assert_eq!(s.meshes[0].geometry.indices.len(), 3 * 896);
    assert!(s.meshes[0]
        .geometry
        .weights
        .iter()
        .all(|w| *w == [1.0, 0.0, 0.0, 0.0]));

    let Some(s) = import("smd/WusonSMD.smd") else {
        return;
    };
    assert_eq!(s.meshes[0].geometry.indices.len(), 3 * 3732);
    assert_eq!(s.skeleton.as_ref().unwrap().names(), ["root"]);

    let path = corpus_file("smd/malformed/empty.smd").unwrap();
    let e = import_path(&path, &ImportOptions::default()).unwrap_err();
    assert!(e.message.contains("empty"), "{e}");
}

/// Patches a copy of man.mdl.
fn patched(at: usize, bytes: &[u8]) -> Option<Vec<u8>> {
    let mut b = read_corpus("mdl/man.mdl")?;
    b[at..at + bytes.len()].copy_from_slice(bytes);
    Some(b)
}

fn mdl_error(bytes: &[u8]) -> sinew_import::ImportError {
    let none = |_: &str| -> std::io::Result<Vec<u8>> {
        Err(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "not here",
        ))
    };
    // Missing companions allowed, so that the damage is what is found.
    let allowed = ImportOptions {
        allow_missing: true,
        ..ImportOptions::default()
    };
    import_bytes(Format::Mdl, "man.mdl", bytes, &none, &allowed).unwrap_err()
}

#[test]
fn damaged_mdl_files_are_errors_naming_section_and_offset() {
    let Some(b) = patched(4, &48i32.to_le_bytes()) else {
        return;
    };
    let e = mdl_error(&b);
    assert!(e.message.contains("Source-engine MDL version 48"), "{e}");
    let e = mdl_error(&patched(0, b"IDPO").unwrap());
    assert!(e.message.contains("Quake MDL"), "{e}");
    let e = mdl_error(&patched(0, b"IDSQ").unwrap());
    assert!(e.message.contains("sequence-group file"), "{e}");
    // 200 bones.
    let e = mdl_error(&patched(140, &200i32.to_le_bytes()).unwrap());
    assert_eq!(
        (e.section.as_str(), &e.location),
        ("bones", &Location::Offset(140)),
        "{e}"
    );
    // Bone 0's parent (offset 244 + 32) set to 5: a parent after its child.
    let e = mdl_error(&patched(276, &5i32.to_le_bytes()).unwrap());
    assert_eq!(
        (e.section.as_str(), &e.location),
        ("bones", &Location::Offset(276)),
        "{e}"
    );
    // First triangle command of mesh 0 of model 0 (at 5168) with a vertex index of 999.
    let e = mdl_error(&patched(5170, &999i16.to_le_bytes()).unwrap());
    assert!(e.section.ends_with("tricmds"), "{e}");
    assert!(e.message.contains("vertex 999"), "{e}");
    // The walk's Root rz run (26 frames) made 200 frames long: it runs past the sequence.
    let b = read_corpus("mdl/man.mdl").unwrap();
    let anim = 1680usize;
    let off = u16::from_le_bytes([b[anim + 10], b[anim + 11]]) as usize;
    let mut c = b.clone();
    c[anim + off + 1] = 200;
    let e = mdl_error(&c);
    assert!(e.message.contains("passes the sequence's 26 frames"), "{e}");
    assert_eq!(e.location, Location::Offset((anim + off) as u64));
    // A run of zero frames.
    c[anim + off + 1] = 0;
    assert!(mdl_error(&c).message.contains("0 frames"));
    // Every truncation is an error, none a panic.
    for n in 0..b.len() {
        let _ = mdl_error(&b[..n]);
    }
}

#[test]
fn mutated_half_life_files_never_panic() {
    let Some(corpus) = sinew_testdata::corpus() else {
        return;
    };
    let none = |_: &str| -> std::io::Result<Vec<u8>> {
        Err(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "not here",
        ))
    };
    let mut seed = 0x2545_f491_u32;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed
    };
    for (rel, format) in [
        ("mdl/man.mdl", Format::Mdl),
        ("mdl/chrome_sphere.mdl", Format::Mdl),
        ("mdl/sequence_transitions.mdl", Format::Mdl),
        ("mdl/manT.mdl", Format::Mdl),
        ("smd/triangle.smd", Format::Smd),
        ("smd/holy_grailref.smd", Format::Smd),
    ] {
        let bytes = std::fs::read(corpus.join(rel)).unwrap();
        for _ in 0..400 {
            let mut b = bytes.clone();
            match next() % 4 {
                0 => {
                    let i = next() as usize % b.len();
                    b[i] ^= 1 << (next() % 8);
                }
                1 => {
                    let i = (next() as usize % (b.len() / 4)) * 4;
                    let v = [0u32, 1, 0x7fff_ffff, 0x8000_0000, u32::MAX, 255, 128]
                        [next() as usize % 7];
                    if i + 4 <= b.len() {
                        b[i..i + 4].copy_from_slice(&v.to_le_bytes());
                    }
                }
                2 => {
                    let i = next() as usize % b.len();
                    let n = (next() as usize % 64).min(b.len() - i);
                    let chunk = b[i..i + n].to_vec();
                    b.splice(i..i, chunk);
                }
                _ => {
                    let i = next() as usize % b.len();
                    let n = (next() as usize % 64).min(b.len() - i);
                    b.drain(i..i + n);
                }
            }
            let _ = import_bytes(format, rel, &b, &none, &ImportOptions::default());
        }
    }
}

#[test]
fn a_texture_file_converted_alone_says_which_model_to_convert() {
    let (Some(textures), Some(model)) = (import("mdl/manT.mdl"), import("mdl/man.mdl")) else {
        return;
    };
    // manT.mdl: five textures (header byte 180), no bone, sequence or body part.
    assert!(textures.skeleton.is_none() && textures.meshes.is_empty() && textures.clips.is_empty());
    let warning = textures
        .diagnostics
        .iter()
        .find(|d| d.code == "mdl-textures-only")
        .expect("a warning for a texture file");
    assert!(
        warning.message.contains("holds 5 textures")
            && warning.message.ends_with("convert man.mdl"),
        "{}",
        warning.message
    );
    // The model that reads it gets no such warning.
    assert!(model
        .diagnostics
        .iter()
        .all(|d| d.code != "mdl-textures-only"));
}
