//! studiomdl's rules on small hand-made QC and SMD files, with every expected value worked out by hand.
#![allow(clippy::unwrap_used)]

use crate::halflife::model::StudioModel;
use crate::halflife::qc;
use sinew_core::format::game::motion_flags;
use sinew_scene::Diagnostic;

/// Files by name; a name not listed is missing.
fn files<'a>(list: &'a [(&'static str, String)]) -> impl Fn(&str) -> std::io::Result<Vec<u8>> + 'a {
    move |name: &str| {
        list.iter()
            .find(|(n, _)| *n == name)
            .map(|(_, t)| t.as_bytes().to_vec())
            .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "missing"))
    }
}

fn compile(qc_text: &str, list: &[(&'static str, String)]) -> (StudioModel, Vec<Diagnostic>) {
    let r = files(list);
    let script = qc::load("m.qc", qc_text.as_bytes(), &r).unwrap();
    super::compile("m.qc", &script, &r, true).unwrap()
}

/// A reference SMD: nodes `root` (0), `a` (1, under root), `b` (2, under root), `spare` (3, unused),
/// bind pose at the origin except `a` at (2, 0, 0); triangles given as (bone, position) corners.
fn reference(corners: &[(usize, [f32; 3])]) -> String {
    let mut s = String::from(
        "version 1\nnodes\n0 \"root\" -1\n1 \"a\" 0\n2 \"b\" 0\n3 \"spare\" 0\nend\nskeleton\ntime 0\n\
         0 0 0 0 0 0 0\n1 2 0 0 0 0 0\n2 0 0 0 0 0 0\n3 0 0 0 0 0 0\nend\ntriangles\n",
    );
    for tri in corners.chunks(3) {
        s.push_str("skin.bmp\n");
        for (bone, p) in tri {
            s.push_str(&format!("{bone} {} {} {} 0 0 1 0 0\n", p[0], p[1], p[2]));
        }
    }
    s.push_str("end\n");
    s
}

/// An animation SMD over `root` and `a`, one line per frame: (root position, root rotation z).
fn animation(frames: &[([f32; 3], f32)]) -> String {
    let mut s = String::from("version 1\nnodes\n0 \"root\" -1\n1 \"a\" 0\nend\nskeleton\n");
    for (t, (p, rz)) in frames.iter().enumerate() {
        s.push_str(&format!(
            "time {t}\n0 {} {} {} 0 0 {rz}\n1 2 0 0 0.3 0 0\n",
            p[0], p[1], p[2]
        ));
    }
    s.push_str("end\n");
    s
}

#[test]
fn bones_are_the_union_of_used_bones_in_first_use_order() {
    // Model 1 uses `b`, model 2 uses `a`; `spare` is used by nobody and is dropped.
    let one = reference(&[
        (2, [0.0, 0.0, 0.0]),
        (2, [1.0, 0.0, 0.0]),
        (2, [0.0, 1.0, 0.0]),
    ]);
    let two = reference(&[
        (1, [2.0, 0.0, 0.0]),
        (1, [3.0, 0.0, 0.0]),
        (1, [2.0, 1.0, 0.0]),
    ]);
    let (m, _) = compile(
        "$body one \"one\"\n$body two \"two\"\n$sequence idle \"one\"\n",
        &[("one.smd", one), ("two.smd", two)],
    );
    let names: Vec<&str> = m.bones.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(names, ["root", "b", "a"]);
    let parents: Vec<Option<usize>> = m.bones.iter().map(|b| b.parent).collect();
    assert_eq!(parents, [None, Some(0), Some(0)]);
    assert_eq!(m.bones[2].value, [2.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    // Model two's vertex (3, 0, 0) on `a` (at 2, 0, 0) is (1, 0, 0) in bone space: back at (3, 0, 0).
    let v: Vec<[f32; 3]> = m.body_parts[1].submodels[0]
        .vertices
        .iter()
        .map(|v| v.position)
        .collect();
    assert!(v.contains(&[3.0, 0.0, 0.0]), "{v:?}");
    assert!(m.body_parts[1].submodels[0]
        .vertices
        .iter()
        .all(|v| v.influences == [(2, 1.0)]));
}

#[test]
fn vertices_keep_two_decimals_in_bone_space() {
    // On `a` at (2, 0, 0): 3.456 - 2 = 1.456 -> 1.45; -1.239 -> -1.23 (towards zero); 0.999 -> 0.99.
    let r = reference(&[
        (1, [3.456, -1.239, 0.999]),
        (1, [2.0, 0.0, 0.0]),
        (1, [2.0, 1.0, 0.0]),
    ]);
    let (m, _) = compile("$body b \"r\"\n$sequence idle \"r\"\n", &[("r.smd", r)]);
    let p = m.body_parts[0].submodels[0].vertices[0].position;
    assert_eq!(p, [2.0 + 1.45, -1.23, 0.99]);
}

#[test]
fn animations_turn_root_bones_extract_motion_and_close_loops() {
    let r = reference(&[
        (1, [2.0, 0.0, 0.0]),
        (1, [3.0, 0.0, 0.0]),
        (1, [2.0, 1.0, 0.0]),
    ]);
    // Root moves along x from 0 to 4 over three frames, z rotation 0.
    let walk = animation(&[
        ([0.0, 0.0, 0.0], 0.0),
        ([2.0, 0.0, 0.0], 0.0),
        ([4.0, 0.0, 0.0], 0.0),
    ]);
    let (m, _) = compile(
        "$body b \"r\"\n$sequence walk \"walk\" LY loop fps 10 ACT_WALK 1\n$sequence turn \"walk\" rotate -90\n",
        &[("r.smd", r), ("walk.smd", walk)],
    );
    let walk = &m.sequences[0];
    assert_eq!(
        (walk.fps, walk.looping, walk.activity),
        (10.0, true, (3, 1))
    );
    assert_eq!(walk.motion_type, motion_flags::LY);
    // The default turn is 90 degrees: x (0, 2, 4) becomes y (0, 2, 4); LY takes y's 4 units out.
    assert_eq!(walk.linear_movement, [0.0, 4.0, 0.0]);
    let root_y: Vec<f32> = walk.blends[0].iter().map(|f| f[0][1]).collect();
    // y - 4 * k / 2 is 0 at every frame; the loop closes rotations and x, z (not LY's y).
    for y in &root_y {
        assert!(y.abs() < 1e-5, "{root_y:?}");
    }
    // Rotation z gained the turn: pi/2, quantised.
    let rz = walk.blends[0][1][0][5];
    assert!((rz - std::f32::consts::FRAC_PI_2).abs() < 1e-4, "{rz}");
    // `rotate -90` cancels the turn: x moves, no rotation.
    let turn = &m.sequences[1];
    assert!((turn.blends[0][2][0][0] - 4.0).abs() < 0.01);
    assert!(turn.blends[0][2][0][5].abs() < 1e-6);
}

#[test]
fn animation_values_are_quantised_as_studiomdl_stores_them() {
    let r = reference(&[
        (1, [2.0, 0.0, 0.0]),
        (1, [3.0, 0.0, 0.0]),
        (1, [2.0, 1.0, 0.0]),
    ]);
    let anim = animation(&[([0.0, 0.0, 0.0], 0.0), ([0.0, 0.0, 0.0], 0.0)]);
    let (m, _) = compile(
        "$body b \"r\"\n$sequence s \"a\" rotate -90\n",
        &[("r.smd", r), ("a.smd", anim)],
    );
    // Bone `a` x rotation 0.3 against default 0: the range is at least pi/8, so the scale is
    // (pi/8) / 32767 and 0.3 is stored as trunc(0.3 / scale) steps.
    let scale = (std::f64::consts::PI / 8.0) as f32 / 32767.0;
    let steps = (0.3f32 / scale) as i16;
    let expected = 0.0 + f32::from(steps) * scale;
    assert_eq!(m.sequences[0].blends[0][0][1][3], expected);
    assert_ne!(expected, 0.3);
}

#[test]
fn skins_controllers_events_blends_and_eyes() {
    let r = reference(&[
        (1, [2.0, 0.0, 0.0]),
        (1, [3.0, 0.0, 0.0]),
        (1, [2.0, 1.0, 0.0]),
    ]);
    let qc_text = "$eyeposition 1 2 3\n$body b \"r\"\n$texturegroup skins\n{\n{ \"skin.bmp\" }\n{ \"alt.bmp\" }\n}\n\
        $controller mouth \"a\" XR 0 360\n$controller 1 \"A\" Y -2 2\n\
        $attachment 0 \"a\" 1 2 3 X 0\n\
        $sequence s \"xa\" \"xa\" blend XR -10 10 \"xa\" blend YR -30 30 { event 1004 99 \"step.wav\" } { event 5001 1 }\n";
    let x = animation(&[([0.0, 0.0, 0.0], 0.0), ([0.0, 0.0, 0.0], 0.0)]);
    let (m, _) = compile(qc_text, &[("r.smd", r), ("xa.smd", x)]);
    // studiomdl turns the eye position: (1, 2, 3) -> (-2, 1, 3).
    assert_eq!(m.eye_position, Some([-2.0, 1.0, 3.0]));
    assert_eq!(
        m.textures
            .iter()
            .map(|t| t.name.as_str())
            .collect::<Vec<_>>(),
        ["skin.bmp", "alt.bmp"]
    );
    assert_eq!(m.skin_families, [vec![0], vec![1]]);
    // `mouth` is controller 4; a full circle wraps (RLOOP); bone names match case-insensitively.
    let c: Vec<(i32, usize, u32)> = m
        .controllers
        .iter()
        .map(|c| (c.index, c.bone, c.channel))
        .collect();
    assert_eq!(
        c,
        [
            (4, 1, motion_flags::XR | motion_flags::RLOOP),
            (1, 1, motion_flags::Y)
        ]
    );
    assert_eq!(m.attachments, [(String::new(), 1, [1.0, 2.0, 3.0])]);
    let s = &m.sequences[0];
    assert_eq!(s.blends.len(), 3);
    // The last `blend` wins and goes to slot 0, as in studiomdl.
    assert_eq!(
        (s.blend_type, s.blend_start, s.blend_end),
        ([motion_flags::YR, 0], [-30.0, 0.0], [30.0, 0.0])
    );
    // An event past the last frame is clamped to it.
    assert_eq!(
        s.events,
        [
            (1, 1004, 0, "step.wav".to_string()),
            (1, 5001, 0, String::new())
        ]
    );
}

#[test]
fn a_missing_smd_is_an_error_naming_file_line_and_command_unless_allowed() {
    let r = reference(&[
        (1, [2.0, 0.0, 0.0]),
        (1, [3.0, 0.0, 0.0]),
        (1, [2.0, 1.0, 0.0]),
    ]);
    let list = [
        ("r.smd", r),
        ("inc.qci", "\n$sequence s \"lost\"\n".to_string()),
    ];
    let have = files(&list);
    // By default the first missing SMD stops the compile, as in studiomdl; an SMD named in an
    // included file is reported at that file's line.
    let text = "$body b \"r\"\n$include \"inc.qci\"\n$sequence t \"r\"\n";
    let script = qc::load("m.qc", text.as_bytes(), &have).unwrap();
    let e = super::compile("m.qc", &script, &have, false).unwrap_err();
    assert_eq!(
        (e.file.as_str(), e.section.as_str(), &e.location),
        ("inc.qci", "$sequence", &crate::Location::Line(2)),
        "{e}"
    );
    assert!(e.message.contains("cannot read lost.smd"), "{e}");
    assert!(e.message.contains("--allow-missing"), "{e}");
    // Allowed, the model is built without it.
    let (m, d) = super::compile("m.qc", &script, &have, true).unwrap();
    assert_eq!(m.sequences.len(), 2);
    assert!(m.sequences[0].blends.is_empty());
    assert_eq!(d.iter().filter(|x| x.code == "qc-missing-smd").count(), 1);
    // When none of the SMDs can be read, it is an error even when allowed: the first one named.
    let none = files(&[]);
    let text = "// a model\n$cd \".\"\n$body b \"gone\"\n$sequence s \"lost\"\n";
    let script = qc::load("m.qc", text.as_bytes(), &none).unwrap();
    for allow in [false, true] {
        let e = super::compile("m.qc", &script, &none, allow).unwrap_err();
        assert_eq!(
            (e.file.as_str(), e.section.as_str(), &e.location),
            ("m.qc", "$body", &crate::Location::Line(3)),
            "{e}"
        );
        assert!(e.message.contains("cannot read gone.smd"), "{e}");
        assert_eq!(
            e.message.contains("no SMD the script names can be read"),
            allow,
            "{e}"
        );
    }
}

#[test]
fn missing_files_and_unknown_commands_are_warnings_naming_them() {
    let r = reference(&[
        (1, [2.0, 0.0, 0.0]),
        (1, [3.0, 0.0, 0.0]),
        (1, [2.0, 1.0, 0.0]),
    ]);
    let (m, d) = compile(
        "$body b \"r\"\n$body c \"gone\"\n$frobnicate 1 2\n$sequence s \"lost\"\n$sequence t \"r\"\n",
        &[("r.smd", r)],
    );
    let text: Vec<String> = d
        .iter()
        .map(|x| format!("{} {}", x.code, x.message))
        .collect();
    assert!(
        text.iter()
            .any(|t| t.contains("qc-missing-smd") && t.contains("gone.smd")),
        "{text:?}"
    );
    assert!(text.iter().any(|t| t.contains("lost.smd")), "{text:?}");
    assert!(
        text.iter().any(|t| t.contains("qc-unknown-command")
            && t.contains("line 3")
            && t.contains("$frobnicate")),
        "{text:?}"
    );
    // What needed the missing files is left out; the rest is there.
    assert!(m.body_parts[1].submodels[0].vertices.is_empty());
    assert!(m.sequences[0].blends.is_empty());
    assert_eq!(m.sequences[1].blends.len(), 1);
}

#[test]
fn bad_scripts_are_errors_naming_the_line() {
    let r = files(&[]);
    for (text, line, what) in [
        ("$body b \"r\"\n$sequence s\n", 2, "names no animation"),
        ("\n\n$hbox 1 \"bone\" 0 0\n", 3, "corner"),
        ("$bodygroup g\n{\nstudio \"x\"\n", 3, "before `}`"),
        ("$texrendermode \"a.bmp\" glowing\n", 1, "glowing"),
    ] {
        let script = qc::load("m.qc", text.as_bytes(), &r).unwrap();
        let e = super::compile("m.qc", &script, &r, true).unwrap_err();
        assert_eq!(e.location, crate::Location::Line(line), "{text:?}: {e}");
        assert!(
            e.to_string().contains(what) || e.to_string().contains("expected"),
            "{e}"
        );
    }
}
