//! Round trips, crafted files and error cases of the `.sinew` container (layout: docs/format.md).
#![allow(clippy::unwrap_used)]

use crate::format_support;

use format_support::*;
use sinew_core::format::{self, Asset, Axes, Axis, FormatErrorKind as K, Tag};
use sinew_core::glam::Vec3;
use sinew_core::{ClipBinding, Sampler, Transform};

fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes(b[at..at + 2].try_into().unwrap())
}
fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}
fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

/// An independent assembler written from docs/format.md: header, table, sections at multiples of 16.
fn assemble(major: u16, minor: u16, sections: &[([u8; 4], u32, Vec<u8>)]) -> Vec<u8> {
    let mut offset = (48 + 32 * sections.len()).div_ceil(16) * 16;
    let mut table = Vec::new();
    let mut bodies = Vec::new();
    let mut end = offset;
    for (tag, version, body) in sections {
        table.extend_from_slice(tag);
        table.extend_from_slice(&version.to_le_bytes());
        table.extend_from_slice(&(offset as u64).to_le_bytes());
        table.extend_from_slice(&(body.len() as u64).to_le_bytes());
        table.extend_from_slice(&crc32fast::hash(body).to_le_bytes());
        table.extend_from_slice(&[0; 4]);
        bodies.push((offset, body));
        end = offset + body.len();
        offset = end.div_ceil(16) * 16;
    }
    let mut out = vec![0u8; end];
    out[0..8].copy_from_slice(&[0x89, b'S', b'N', b'W', 0x0D, 0x0A, 0x1A, 0x0A]);
    out[8..10].copy_from_slice(&major.to_le_bytes());
    out[10..12].copy_from_slice(&minor.to_le_bytes());
    out[16..24].copy_from_slice(&(end as u64).to_le_bytes());
    out[24..32].copy_from_slice(&48u64.to_le_bytes());
    out[32..36].copy_from_slice(&(sections.len() as u32).to_le_bytes());
    out[36..40].copy_from_slice(&32u32.to_le_bytes());
    out[48..48 + table.len()].copy_from_slice(&table);
    let mut h = crc32fast::Hasher::new();
    h.update(&out[0..44]);
    h.update(&table);
    let crc = h.finalize();
    out[44..48].copy_from_slice(&crc.to_le_bytes());
    for (o, body) in bodies {
        out[o..o + body.len()].copy_from_slice(body);
    }
    out
}

/// The sections of a file as (tag, version, body), read from the table per docs/format.md.
fn split(bytes: &[u8]) -> Vec<([u8; 4], u32, Vec<u8>)> {
    let count = u32_at(bytes, 32) as usize;
    (0..count)
        .map(|i| {
            let e = 48 + 32 * i;
            let off = u64_at(bytes, e + 8) as usize;
            let size = u64_at(bytes, e + 16) as usize;
            (
                bytes[e..e + 4].try_into().unwrap(),
                u32_at(bytes, e + 4),
                bytes[off..off + size].to_vec(),
            )
        })
        .collect()
}

/// Offset of the section with this tag, from the table.
fn section_offset(bytes: &[u8], tag: &[u8; 4]) -> usize {
    let count = u32_at(bytes, 32) as usize;
    (0..count)
        .map(|i| 48 + 32 * i)
        .find(|&e| &bytes[e..e + 4] == tag)
        .map(|e| u64_at(bytes, e + 8) as usize)
        .unwrap()
}

/// Patches bytes inside a section and recomputes that section's and the header's checksums, so the
/// reader's checks behind the checksums are exercised.
fn patch(bytes: &[u8], tag: &[u8; 4], at: usize, new: &[u8]) -> Vec<u8> {
    let mut sections = split(bytes);
    let s = sections.iter_mut().find(|s| &s.0 == tag).unwrap();
    s.2[at..at + new.len()].copy_from_slice(new);
    assemble(1, 0, &sections)
}

#[test]
fn full_asset_round_trips_and_header_bytes_are_as_documented() {
    let asset = full_asset();
    let bytes = format::write(&asset).unwrap();
    assert_eq!(&bytes[0..8], b"\x89SNW\r\n\x1a\n");
    assert_eq!(u16_at(&bytes, 8), 1);
    assert_eq!(u16_at(&bytes, 10), 1);
    assert_eq!(u32_at(&bytes, 12), 0);
    assert_eq!(u64_at(&bytes, 16), bytes.len() as u64);
    assert_eq!(u64_at(&bytes, 24), 48);
    assert_eq!(u32_at(&bytes, 32), 5);
    assert_eq!(u32_at(&bytes, 36), 32);
    let tags: Vec<&[u8]> = (0..5).map(|i| &bytes[48 + 32 * i..52 + 32 * i]).collect();
    assert_eq!(tags, [b"STRS", b"SKEL", b"MATL", b"MESH", b"CLIP"]);
    // The first section starts right after the 48 + 5 * 32 = 208-byte header and table.
    assert_eq!(u64_at(&bytes, 48 + 8), 208);
    // An independent assembler from the documented layout gives the same bytes.
    assert_eq!(assemble(1, 1, &split(&bytes)), bytes);

    let back = format::read(&bytes).unwrap();
    assert_eq!(back, asset);
    let info = format::sections(&bytes).unwrap();
    assert_eq!(info.len(), 5);
    for s in &info {
        assert_eq!(s.offset % 16, 0, "{}", s.tag);
        assert!(s.checksum_ok && s.known && s.version == 1);
    }
    assert_eq!(info[4].offset + info[4].size, bytes.len() as u64);
}

#[test]
fn string_table_is_in_first_use_order_and_deduplicated() {
    let bytes = format::write(&full_asset()).unwrap();
    let strs = &split(&bytes)[0].2;
    let count = u32_at(strs, 0) as usize;
    let data_size = u32_at(strs, 4) as usize;
    let data_at = (16 + 8 * count).div_ceil(16) * 16;
    let all: Vec<&str> = (0..count)
        .map(|i| {
            let (o, l) = (
                u32_at(strs, 16 + 8 * i) as usize,
                u32_at(strs, 20 + 8 * i) as usize,
            );
            std::str::from_utf8(&strs[data_at + o..data_at + o + l]).unwrap()
        })
        .collect();
    assert_eq!(
        all,
        [
            "root",
            "spine",
            "head",
            "prop", // skeleton
            "skin",
            "textures/skin.png",
            "cloth", // materials
            "body",
            "crate", // meshes ("skin" and "cloth" again from submeshes: reused)
            "walk",
            "tail",
            "wave", // clips and their joints
        ]
    );
    assert_eq!(data_size, all.iter().map(|s| s.len()).sum::<usize>());
    assert_eq!(strs.len(), data_at + data_size);
}

#[test]
fn writing_is_deterministic() {
    let a = format::write(&full_asset()).unwrap();
    let b = format::write(&full_asset()).unwrap();
    assert_eq!(a, b);
    let again = format::write(&format::read(&a).unwrap()).unwrap();
    assert_eq!(again, a);
}

#[test]
fn clip_only_file_binds_by_name_to_a_separate_skeleton() {
    let motion = Asset {
        clips: vec![walk()],
        ..Default::default()
    };
    let bytes = format::write(&motion).unwrap();
    let tags: Vec<_> = format::sections(&bytes)
        .unwrap()
        .iter()
        .map(|s| s.tag)
        .collect();
    assert_eq!(tags, [Tag::STRINGS, Tag::CLIPS]);
    let back = format::read(&bytes).unwrap();
    assert!(back.skeleton.is_none() && back.meshes.is_empty());
    assert_eq!(back.clips, motion.clips);

    let rig = skeleton();
    let clip = &back.clips[0];
    let binding = ClipBinding::new(clip, &rig);
    assert_eq!(binding.unmatched(), ["tail"]);
    assert_eq!(binding.driven(), [0, 1, 2]);
    let mut pose = vec![Transform::IDENTITY; rig.len()];
    Sampler::new()
        .sample(clip, &binding, &rig, 0.5, &mut pose)
        .unwrap();
    assert_eq!(pose[0].translation, Vec3::X);
    assert_eq!(pose[2].scale, Vec3::splat(1.5));
    // "prop" is not driven: left as it was.
    assert_eq!(pose[3], Transform::IDENTITY);
}

#[test]
fn empty_asset_is_a_header_and_an_empty_string_table() {
    let bytes = format::write(&Asset::default()).unwrap();
    // 48 header + 32 table = 80, then a 16-byte STRS (count 0, data size 0, 8 zero bytes).
    assert_eq!(bytes.len(), 96);
    assert_eq!(&bytes[80..96], &[0u8; 16]);
    assert_eq!(format::read(&bytes).unwrap(), Asset::default());
}

#[test]
fn unknown_sections_are_skipped_and_newer_minor_versions_load() {
    let bytes = format::write(&full_asset()).unwrap();
    let mut sections = split(&bytes);
    sections.insert(2, (*b"XTRA", 7, b"seventeen bytes!!".to_vec()));
    let crafted = assemble(1, 3, &sections);
    let info = format::sections(&crafted).unwrap();
    assert_eq!(info[2].tag, Tag(*b"XTRA"));
    assert!(!info[2].known);
    assert_eq!(info[2].size, 17);
    assert_eq!(format::read(&crafted).unwrap(), full_asset());
}

#[test]
fn future_major_version_is_rejected() {
    let sections = split(&format::write(&full_asset()).unwrap());
    let e = format::read(&assemble(2, 0, &sections)).unwrap_err();
    assert_eq!(e.kind, K::UnsupportedVersion { major: 2, minor: 0 });
    assert_eq!((e.section.as_str(), e.offset), ("header", Some(8)));
    let e = format::sections(&assemble(0, 9, &sections)).unwrap_err();
    assert_eq!(e.kind, K::UnsupportedVersion { major: 0, minor: 9 });
}

#[test]
fn known_section_with_unknown_layout_version_is_rejected() {
    let mut sections = split(&format::write(&full_asset()).unwrap());
    sections[3].1 = 2;
    let e = format::read(&assemble(1, 0, &sections)).unwrap_err();
    assert_eq!(e.kind, K::UnsupportedSectionVersion { version: 2 });
    assert_eq!(e.section, "MESH");
}

#[test]
fn duplicate_known_section_is_rejected() {
    let mut sections = split(&format::write(&full_asset()).unwrap());
    sections.push(sections[4].clone());
    let e = format::read(&assemble(1, 0, &sections)).unwrap_err();
    assert_eq!(e.kind, K::DuplicateSection);
    assert_eq!(e.section, "CLIP");
}

#[test]
fn wrong_magic_and_text_mode_damage_are_rejected() {
    let bytes = format::write(&full_asset()).unwrap();
    let mut b = bytes.clone();
    b[1] = b's';
    assert_eq!(format::read(&b).unwrap_err().kind, K::BadMagic);
    // CR LF turned into LF, as a text-mode transfer does.
    let mut lf = bytes[..4].to_vec();
    lf.extend_from_slice(&bytes[5..]);
    assert_eq!(format::read(&lf).unwrap_err().kind, K::BadMagic);
    // The high bit stripped.
    let mut b = bytes.clone();
    b[0] = 0x09;
    assert_eq!(format::read(&b).unwrap_err().kind, K::BadMagic);
    assert_eq!(format::read(b"hello").unwrap_err().kind, K::BadMagic);
}

#[test]
fn wrong_checksum_names_the_section_and_its_offset() {
    let bytes = format::write(&full_asset()).unwrap();
    let mesh = section_offset(&bytes, b"MESH");
    let mut b = bytes.clone();
    b[mesh + 100] ^= 0x10;
    let e = format::read(&b).unwrap_err();
    assert_eq!(e.section, "MESH");
    assert_eq!(e.offset, Some(mesh as u64));
    let K::Checksum { stored, computed } = e.kind else {
        panic!("{e}")
    };
    assert_eq!(stored, crc32fast::hash(&split(&bytes)[3].2));
    assert_ne!(stored, computed);
    // sections() still lists it, flagged.
    let info = format::sections(&b).unwrap();
    assert!(!info[3].checksum_ok && info[2].checksum_ok);

    // A damaged section table entry fails the header checksum.
    let mut b = bytes.clone();
    b[48 + 32 * 3 + 16] ^= 1;
    let e = format::read(&b).unwrap_err();
    assert!(matches!(e.kind, K::Checksum { .. }), "{e}");
    assert_eq!((e.section.as_str(), e.offset), ("header", Some(44)));
}

#[test]
fn trailing_bytes_are_rejected() {
    let mut bytes = format::write(&full_asset()).unwrap();
    let len = bytes.len() as u64;
    bytes.push(0);
    let e = format::read(&bytes).unwrap_err();
    assert_eq!(
        e.kind,
        K::FileSize {
            declared: len,
            actual: len + 1
        }
    );
}

#[test]
fn every_truncation_is_rejected_as_truncated() {
    for asset in [
        full_asset(),
        Asset {
            clips: vec![wave()],
            ..Default::default()
        },
    ] {
        let bytes = format::write(&asset).unwrap();
        for n in 0..bytes.len() {
            let e = format::read(&bytes[..n]).unwrap_err();
            assert!(matches!(e.kind, K::Truncated { .. }), "length {n}: {e}");
        }
    }
}

// Offsets inside the MESH section of full_asset(), from the layout in docs/format.md: 16-byte section
// header, mesh record at 16, LOD header at 32, metadata 64..96, positions 96..144, normals 144..192,
// uvs 192..224, joints 224..256, weights 256..320, indices 320..344, submeshes at 352.
const LOD0_VERTEX_COUNT: usize = 32;
const LOD0_FIRST_POSITION: usize = 96;
const LOD0_FIRST_JOINT: usize = 224;
const LOD0_FIRST_INDEX: usize = 320;
const LOD0_FIRST_SUBMESH: usize = 352;

#[test]
fn mesh_layout_offsets_match_the_documentation() {
    let bytes = format::write(&full_asset()).unwrap();
    let mesh = &split(&bytes)[3].2;
    assert_eq!(u32_at(mesh, 0), 2); // two meshes
    assert_eq!(u32_at(mesh, 20), 2); // two LODs of "body"
    assert_eq!(u32_at(mesh, LOD0_VERTEX_COUNT), 4);
    assert_eq!(u32_at(mesh, LOD0_VERTEX_COUNT + 4), 7); // normals | uvs | skin
    assert_eq!(u32_at(mesh, LOD0_VERTEX_COUNT + 8), 6);
    assert_eq!(u32_at(mesh, LOD0_VERTEX_COUNT + 12), 2);
    assert_eq!(u32_at(mesh, LOD0_VERTEX_COUNT + 16), 32);
    let pos3 = LOD0_FIRST_POSITION + 3 * 12;
    assert_eq!(&mesh[pos3 + 8..pos3 + 12], &0.5f32.to_le_bytes());
    assert_eq!(u16_at(mesh, LOD0_FIRST_JOINT + 8 + 2), 2); // vertex 1, second joint
    assert_eq!(u32_at(mesh, LOD0_FIRST_INDEX + 5 * 4), 3);
    assert_eq!(u32_at(mesh, LOD0_FIRST_SUBMESH + 16), 3); // second submesh starts at index 3
                                                          // LOD 1 starts at the next multiple of 16 after the two 16-byte submesh records.
    let lod1 = LOD0_FIRST_SUBMESH + 32;
    assert_eq!(u32_at(mesh, lod1), 3);
    assert_eq!(u32_at(mesh, lod1 + 4), 5); // normals | skin
    assert_eq!(&mesh[lod1 + 32..lod1 + 36], &0.125f32.to_le_bytes());
    assert_eq!(&mesh[lod1 + 40..lod1 + 44], &0.5f32.to_le_bytes());
    assert_eq!(u32_at(mesh, lod1 + 48), 1); // stopped by the error limit
}

#[test]
fn bad_values_behind_valid_checksums_are_typed_errors() {
    let bytes = format::write(&full_asset()).unwrap();
    let mesh_at = section_offset(&bytes, b"MESH") as u64;

    let b = patch(&bytes, b"MESH", LOD0_FIRST_INDEX, &99u32.to_le_bytes());
    let e = format::read(&b).unwrap_err();
    assert_eq!(
        e.kind,
        K::IndexOutOfRange {
            what: "vertex",
            index: 99,
            limit: 4
        }
    );
    assert_eq!(e.offset, Some(mesh_at + LOD0_VERTEX_COUNT as u64));

    let b = patch(&bytes, b"MESH", LOD0_FIRST_JOINT, &4u16.to_le_bytes());
    assert_eq!(
        format::read(&b).unwrap_err().kind,
        K::IndexOutOfRange {
            what: "joint",
            index: 4,
            limit: 4
        }
    );

    let b = patch(
        &bytes,
        b"MESH",
        LOD0_FIRST_POSITION,
        &f32::NAN.to_le_bytes(),
    );
    assert_eq!(
        format::read(&b).unwrap_err().kind,
        K::NonFinite { what: "a position" }
    );

    let b = patch(
        &bytes,
        b"MESH",
        LOD0_VERTEX_COUNT,
        &0x4000_0000u32.to_le_bytes(),
    );
    let e = format::read(&b).unwrap_err();
    assert!(
        matches!(
            e.kind,
            K::CountTooLarge {
                what: "positions",
                count: 0x4000_0000,
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(e.offset, Some(mesh_at + LOD0_FIRST_POSITION as u64));

    let b = patch(&bytes, b"MESH", LOD0_FIRST_SUBMESH + 4, &7u32.to_le_bytes());
    assert_eq!(
        format::read(&b).unwrap_err().kind,
        K::IndexOutOfRange {
            what: "submesh end index",
            index: 7,
            limit: 6
        }
    );

    // A joint name index past the string table.
    let b = patch(&bytes, b"SKEL", 16, &1000u32.to_le_bytes());
    let e = format::read(&b).unwrap_err();
    assert_eq!(
        e.kind,
        K::IndexOutOfRange {
            what: "joint name string",
            index: 1000,
            limit: 12
        }
    );
    assert_eq!(e.section, "SKEL");

    // A parent that does not come before its child: joint 1's parent set to 1. Parents are at 32
    // (16-byte header, 4 name indices of 4 bytes).
    let b = patch(&bytes, b"SKEL", 32 + 2, &1u16.to_le_bytes());
    assert!(matches!(
        format::read(&b).unwrap_err().kind,
        K::IndexOutOfRange {
            what: "parent joint",
            ..
        }
    ));

    // A quantised encoding (reserved for later) in the first track's translation channel. CLIP layout:
    // 16-byte header; clip "walk" header at 16; 3 key times (0, 0.5, 0.75) at 48; tracks at 64 (the
    // head's single translation key is a constant and adds no key time).
    let clip = &split(&bytes)[4].2;
    assert_eq!(u32_at(clip, 16 + 16), 3);
    assert_eq!(&clip[48 + 4..48 + 8], &0.5f32.to_le_bytes());
    assert_eq!(clip[64 + 4], 2); // root translation: animated
    let b = patch(&bytes, b"CLIP", 64 + 5, &[1]);
    assert_eq!(
        format::read(&b).unwrap_err().kind,
        K::UnsupportedEncoding { encoding: 1 }
    );
    let b = patch(&bytes, b"CLIP", 64 + 4, &[3]);
    assert!(matches!(
        format::read(&b).unwrap_err().kind,
        K::BadValue {
            what: "channel kind",
            value: 3
        }
    ));
    // Frame count larger than the section: stride set to 2^30.
    let b = patch(&bytes, b"CLIP", 16 + 20, &(1u32 << 30).to_le_bytes());
    assert!(matches!(
        format::read(&b).unwrap_err().kind,
        K::CountTooLarge {
            what: "frame floats",
            ..
        }
    ));
    // Invalid UTF-8 in the string table data (which starts at 16 + 12 * 8 = 112).
    let b = patch(&bytes, b"STRS", 112, &[0xFF]);
    assert_eq!(format::read(&b).unwrap_err().kind, K::BadUtf8 { index: 0 });
}

#[test]
fn writer_rejects_what_the_reader_would_reject() {
    let mut asset = full_asset();
    asset.meshes[0].lods[0].indices[1] = 4;
    let e = format::write(&asset).unwrap_err();
    assert_eq!(e.section, "MESH");
    assert!(e.to_string().contains("\"body\" LOD 0"), "{e}");

    let mut asset = full_asset();
    asset.meshes[0].lods[1].joints[0][0] = 9;
    assert!(format::write(&asset).is_err());

    let mut asset = full_asset();
    asset.meshes[1].lods.clear();
    assert!(format::write(&asset)
        .unwrap_err()
        .to_string()
        .contains("no LODs"));

    let mut asset = full_asset();
    asset.meshes[0].lods[0].uvs.pop();
    assert!(format::write(&asset)
        .unwrap_err()
        .to_string()
        .contains("3 uvs for 4 vertices"));

    // Joint indices are only checked against a skeleton when there is one.
    let mut asset = full_asset();
    asset.skeleton = None;
    asset.meshes[0].lods[1].joints[0][0] = 9;
    let back = format::read(&format::write(&asset).unwrap()).unwrap();
    assert_eq!(back.meshes[0].lods[1].joints[0], [9, 0, 0, 0]);
}

#[test]
fn lod_info_defaults_are_written_for_missing_entries() {
    let mut asset = full_asset();
    asset.lod_info.clear();
    let back = format::read(&format::write(&asset).unwrap()).unwrap();
    assert_eq!(back.lod_info.len(), 2);
    assert_eq!(back.lod_info[0].len(), 2);
    assert_eq!(back.lod_info[0][1], format::LodInfo::default());
    assert_eq!(back.lod_info[0][1].target_ratio, 1.0);
    assert_eq!(back.meshes, asset.meshes);
}

#[test]
fn checksum_is_crc32_iso_hdlc_as_documented() {
    // The standard check value of CRC-32/ISO-HDLC.
    assert_eq!(crc32fast::hash(b"123456789"), 0xCBF4_3926);
    let bytes = format::write(&full_asset()).unwrap();
    let strs = &split(&bytes)[0].2;
    assert_eq!(u32_at(&bytes, 48 + 24), crc32fast::hash(strs));
}

#[test]
fn track_records_hold_kind_encoding_and_payload_as_documented() {
    let bytes = format::write(&Asset {
        clips: vec![walk()],
        ..Default::default()
    })
    .unwrap();
    let clip = &split(&bytes)[1].2;
    assert_eq!(u32_at(clip, 0), 1);
    assert_eq!(u32_at(clip, 4), 64);
    assert_eq!(u32_at(clip, 16 + 4), 1); // looping
    assert_eq!(&clip[16 + 8..16 + 12], &1.0f32.to_le_bytes());
    assert_eq!(&clip[16 + 12..16 + 16], &30.0f32.to_le_bytes());
    let stride = u32_at(clip, 16 + 20);
    assert_eq!(stride, 7); // root translation (3) + spine rotation (4)
    assert_eq!(u32_at(clip, 16 + 24), 4);
    let tracks = 64;
    // Track 0, root: translation animated at offset 0, rotation and scale bind.
    assert_eq!(&clip[tracks + 4..tracks + 6], &[2, 0]);
    assert_eq!(u32_at(clip, tracks + 8), 0);
    assert_eq!(clip[tracks + 24], 0);
    assert_eq!(clip[tracks + 44], 0);
    // Track 1, spine: rotation animated at offset 3.
    assert_eq!(clip[tracks + 64 + 24], 2);
    assert_eq!(u32_at(clip, tracks + 64 + 28), 3);
    // Track 2, head: constant translation (0, 0.25, 0) and constant scale 1.5.
    let head = tracks + 128;
    assert_eq!(clip[head + 4], 1);
    assert_eq!(&clip[head + 12..head + 16], &0.25f32.to_le_bytes());
    assert_eq!(clip[head + 44], 1);
    assert_eq!(&clip[head + 48..head + 52], &1.5f32.to_le_bytes());
    // Frames after the 4 track records: 3 keys x 7 floats; frame 1 starts with root x = 1.
    let frames = tracks + 4 * 64;
    assert_eq!(clip.len(), frames + 3 * 7 * 4);
    assert_eq!(&clip[frames + 28..frames + 32], &1.0f32.to_le_bytes());
}

// The `AXES` section (format 1.6).

fn half_life() -> Asset {
    Asset {
        axes: Some(Axes::new(Axis::PosZ, Axis::PosX, Axis::NegY).unwrap()),
        ..Default::default()
    }
}

#[test]
fn axes_round_trip_in_a_version_1_6_file_with_the_documented_bytes() {
    let bytes = format::write(&half_life()).unwrap();
    assert_eq!(u16_at(&bytes, 10), 6, "minor version");
    let back = format::read(&bytes).unwrap();
    assert_eq!(back.axes, half_life().axes);
    let sections = split(&bytes);
    let axes = sections.iter().find(|s| &s.0 == b"AXES").unwrap();
    // up +Z (4), forward +X (0), bind forward -Y (3), 13 zero bytes.
    let mut want = vec![4u8, 0, 3];
    want.extend([0u8; 13]);
    assert_eq!(axes.2, want);
    // No axes: no section, and the minor version of the rest (1.1 here).
    let plain = format::write(&Asset::default()).unwrap();
    assert!(split(&plain).iter().all(|s| &s.0 != b"AXES"));
    assert_eq!(u16_at(&plain, 10), 1);
    assert_eq!(format::read(&plain).unwrap().axes, None);
}

#[test]
fn bad_axes_are_errors_naming_the_section() {
    let bytes = format::write(&half_life()).unwrap();
    let mut sections = split(&bytes);
    let at = sections.iter().position(|s| &s.0 == b"AXES").unwrap();
    for (byte, value) in [(0usize, 6u8), (1, 5), (2, 4), (1, 255)] {
        let mut s = sections.clone();
        s[at].2[byte] = value;
        let e = format::read(&assemble(1, 6, &s)).unwrap_err();
        assert_eq!(e.section, "AXES", "byte {byte} = {value}: {e}");
        assert!(matches!(e.kind, K::Invalid(_)), "{e}");
    }
    // Shorter than 16 bytes: truncated.
    sections[at].2.truncate(15);
    let e = format::read(&assemble(1, 6, &sections)).unwrap_err();
    assert!(matches!(e.kind, K::Truncated { .. }), "{e}");
    // The writer refuses what the reader refuses.
    let bad = Asset {
        axes: Some(Axes {
            up: Axis::PosY,
            forward: Axis::NegY,
            bind_forward: Axis::PosZ,
        }),
        ..Default::default()
    };
    assert!(format::write(&bad).is_err());
}
