//! The `GAME` section (format 1.3): round trip, the documented byte layout, and damaged records.
#![allow(clippy::unwrap_used)]

use crate::format_support;

use format_support::*;
use sinew_core::format::game::{
    motion_flags, Attachment, BodyGroup, BoneController, ClipBlend, ClipEvent, ClipGameData,
    GameData, Hitbox, MaterialFlags,
};
use sinew_core::format::{self, Asset, FormatErrorKind as K};

fn game() -> GameData {
    GameData {
        eye_position: Some([0.0, 0.0, 72.0]),
        attachments: vec![Attachment {
            name: String::new(),
            joint: "hip".into(),
            offset: [0.0, 3.5, 0.0],
        }],
        hitboxes: vec![Hitbox {
            joint: "leg".into(),
            group: 6,
            min: [-0.4, 0.0, -0.4],
            max: [0.4, 4.0, 0.4],
        }],
        controllers: vec![BoneController {
            index: 0,
            joint: "leg".into(),
            channel: motion_flags::YR,
            start: -60.0,
            end: 60.0,
            rest: 0,
        }],
        body_groups: vec![
            BodyGroup {
                name: "studio".into(),
                meshes: vec!["body".into()],
            },
            BodyGroup {
                name: "heads".into(),
                meshes: vec!["head1".into(), String::new(), "head3".into()],
            },
        ],
        skin_families: vec![
            vec!["skin".into(), "cloth".into()],
            vec!["cloth".into(), "skin".into()],
        ],
        material_flags: vec![MaterialFlags {
            material: "skin".into(),
            flags: 0x40,
        }],
        clips: vec![
            ClipGameData {
                clip: "walk".into(),
                activity: 3,
                activity_weight: 1,
                events: vec![
                    ClipEvent {
                        frame: 0,
                        event: 1004,
                        kind: 0,
                        options: "common/npc_step1.wav".into(),
                    },
                    ClipEvent {
                        frame: 13,
                        event: 1004,
                        kind: 0,
                        options: "common/npc_step3.wav".into(),
                    },
                ],
                motion_type: motion_flags::LX,
                motion_joint: "hip".into(),
                linear_movement: [12.5, 0.0, 0.0],
                blend: None,
                entry_node: 0,
                exit_node: 0,
                node_flags: 0,
            },
            ClipGameData {
                clip: "wave".into(),
                activity: 1,
                activity_weight: 1,
                blend: Some(ClipBlend {
                    sequence: "arms_up".into(),
                    index: 2,
                    count: 4,
                    types: [motion_flags::YR, 0],
                    start: [-30.0, 0.0],
                    end: [30.0, 0.0],
                }),
                entry_node: 1,
                exit_node: 2,
                node_flags: 1,
                ..ClipGameData::default()
            },
        ],
        transitions: vec![0, 2, 1, 0],
        transition_nodes: 2,
    }
}

fn asset() -> Asset {
    Asset {
        game: game(),
        ..full_asset()
    }
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

/// The GAME section's bytes, found through the section table.
fn game_section(bytes: &[u8]) -> &[u8] {
    let info = format::sections(bytes).unwrap();
    let s = info.iter().find(|s| s.tag.0 == *b"GAME").unwrap();
    &bytes[s.offset as usize..(s.offset + s.size) as usize]
}

#[test]
fn game_data_round_trips_in_a_version_1_3_file() {
    let asset = asset();
    let bytes = format::write(&asset).unwrap();
    assert_eq!(
        u16::from_le_bytes([bytes[10], bytes[11]]),
        3,
        "minor version"
    );
    let back = format::read(&bytes).unwrap();
    assert_eq!(back.game, asset.game);
    assert_eq!(back, asset);
    // Without game data nothing is written and the minor version stays 1.
    let plain = format::write(&full_asset()).unwrap();
    assert_eq!(u16::from_le_bytes([plain[10], plain[11]]), 1);
    assert!(format::sections(&plain)
        .unwrap()
        .iter()
        .all(|s| s.tag.0 != *b"GAME"));
}

#[test]
fn game_section_follows_the_documented_layout() {
    let bytes = format::write(&asset()).unwrap();
    let back = format::read(&bytes).unwrap();
    let g = game_section(&bytes);
    // Header: flags, eye position, then eleven counts and a reserved word (docs/format.md).
    assert_eq!(u32_at(g, 0), 1);
    assert_eq!(
        [f32_at(g, 4), f32_at(g, 8), f32_at(g, 12)],
        [0.0, 0.0, 72.0]
    );
    let counts: Vec<u32> = (0..11).map(|i| u32_at(g, 16 + 4 * i)).collect();
    assert_eq!(counts, [1, 1, 1, 2, 4, 2, 2, 1, 2, 2, 2]);
    assert_eq!(u32_at(g, 60), 0);
    // Tables start at 64 and each at a multiple of 16: attachments (20 B) at 64, hit boxes (32 B) at
    // 96, controllers (24 B) at 128, body groups (12 B each) at 160, entries (4 B) at 192, skin
    // table (4 x 4 B) at 208, material flags at 224, clip records (96 B) at 240, events (16 B) at
    // 432, transitions at 464.
    let strings = |i: u32| -> String {
        // The string table is the STRS section; resolve through the reader's own table order by
        // checking names we know appear only once.
        let info = format::sections(&bytes).unwrap();
        let s = info.iter().find(|s| s.tag.0 == *b"STRS").unwrap();
        let t = &bytes[s.offset as usize..(s.offset + s.size) as usize];
        let count = u32_at(t, 0) as usize;
        let data = (16 + 8 * count).div_ceil(16) * 16;
        let (at, len) = (
            u32_at(t, 16 + 8 * i as usize) as usize,
            u32_at(t, 20 + 8 * i as usize) as usize,
        );
        String::from_utf8(t[data + at..data + at + len].to_vec()).unwrap()
    };
    assert_eq!(strings(u32_at(g, 68)), "hip");
    assert_eq!(f32_at(g, 76), 3.5);
    assert_eq!(strings(u32_at(g, 96)), "leg");
    assert_eq!(u32_at(g, 100), 6);
    assert_eq!(f32_at(g, 96 + 24), 4.0);
    assert_eq!(u32_at(g, 136), motion_flags::YR);
    assert_eq!(f32_at(g, 140), -60.0);
    assert_eq!(strings(u32_at(g, 172)), "heads");
    assert_eq!([u32_at(g, 176), u32_at(g, 180)], [1, 3]);
    assert_eq!(u32_at(g, 196 + 4), u32::MAX, "a blank body-group choice");
    assert_eq!(strings(u32_at(g, 208 + 8)), "cloth");
    assert_eq!(u32_at(g, 228), 0x40);
    assert_eq!(strings(u32_at(g, 240)), "walk");
    assert_eq!(u32_at(g, 240 + 4), 3);
    assert_eq!([u32_at(g, 240 + 12), u32_at(g, 240 + 16)], [0, 2]);
    assert_eq!(u32_at(g, 240 + 20), motion_flags::LX);
    assert_eq!(f32_at(g, 240 + 28), 12.5);
    let wave = 240 + 96;
    assert_eq!(u32_at(g, wave + 40), 1, "blend present");
    assert_eq!(strings(u32_at(g, wave + 44)), "arms_up");
    assert_eq!([u32_at(g, wave + 48), u32_at(g, wave + 52)], [2, 4]);
    assert_eq!(f32_at(g, wave + 64), -30.0);
    assert_eq!(u32_at(g, wave + 88), 1);
    assert_eq!(u32_at(g, 432 + 16), 13);
    assert_eq!(strings(u32_at(g, 432 + 12)), "common/npc_step1.wav");
    assert_eq!(&g[464..468], &[0, 2, 1, 0]);
    assert_eq!(g.len(), 468);
    assert_eq!(back.game, game());
}

#[test]
fn damaged_game_records_are_errors_naming_the_section() {
    let bytes = format::write(&asset()).unwrap();
    let info = format::sections(&bytes).unwrap();
    let s = info.iter().find(|s| s.tag.0 == *b"GAME").unwrap();
    let base = s.offset as usize;
    // Rewrite a field and fix the section and header checksums, so the reader's own checks run.
    let patched = |at: usize, value: [u8; 4]| -> Vec<u8> {
        let mut b = bytes.clone();
        b[base + at..base + at + 4].copy_from_slice(&value);
        let crc = crc32fast::hash(&b[base..base + s.size as usize]);
        let count = u32_at(&b, 32) as usize;
        let entry = (0..count)
            .map(|i| 48 + 32 * i)
            .find(|&e| &b[e..e + 4] == b"GAME")
            .unwrap();
        b[entry + 24..entry + 28].copy_from_slice(&crc.to_le_bytes());
        let mut h = crc32fast::Hasher::new();
        h.update(&b[0..44]);
        h.update(&b[48..48 + 32 * count]);
        let hc = h.finalize();
        b[44..48].copy_from_slice(&hc.to_le_bytes());
        b
    };
    let cases: [(usize, [u8; 4], &str); 5] = [
        // A huge attachment count.
        (16, 0x4000_0000u32.to_le_bytes(), "attachments"),
        // A body group's entries past the list.
        (176, 3u32.to_le_bytes(), "body group entries"),
        // A clip's events past the list.
        (240 + 16, 9u32.to_le_bytes(), "clip events"),
        // A string index past the table.
        (68, 0xFFFF_FF00u32.to_le_bytes(), "attachment joint string"),
        // A non-finite hit box corner.
        (96 + 8, f32::NAN.to_le_bytes(), "hit box corner"),
    ];
    for (at, value, what) in cases {
        let err = format::read(&patched(at, value)).unwrap_err();
        assert_eq!(err.section, "GAME", "{what}: {err}");
        let text = err.to_string();
        assert!(
            text.contains(what.split(' ').next().unwrap())
                || matches!(err.kind, K::NonFinite { .. }),
            "{what}: {text}"
        );
    }
    // Every truncation of the file is an error, never a panic.
    for n in 0..bytes.len() {
        assert!(format::read(&bytes[..n]).is_err());
    }
}

#[test]
fn writer_refuses_game_data_the_reader_would_refuse() {
    let mut a = asset();
    a.game.transitions.push(1);
    assert!(format::write(&a).is_err());
    let mut a = asset();
    a.game.skin_families[1].pop();
    assert!(format::write(&a).is_err());
    let mut a = asset();
    a.game.attachments[0].offset[1] = f32::INFINITY;
    assert!(format::write(&a).is_err());
}
