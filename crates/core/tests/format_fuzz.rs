//! Damaged `.sinew` files: bit flips and random mutations are rejected or read back, never panic.
#![allow(clippy::unwrap_used)]

use crate::format_support;

use format_support::*;
use proptest::prelude::*;
use sinew_core::format::{self, Asset};

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}
fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// Recomputes every section checksum and the header checksum (docs/format.md), as far as the table
/// can be followed, so that mutations reach the checks behind the checksums.
fn fix_checksums(b: &mut [u8]) {
    let (Some(table), Some(count), Some(entry)) = (u64_at(b, 24), u32_at(b, 32), u32_at(b, 36))
    else {
        return;
    };
    let (table, count, entry) = (table as usize, count.min(1024) as usize, entry as usize);
    for i in 0..count {
        let Some(e) = table.checked_add(i.saturating_mul(entry)) else {
            return;
        };
        let (Some(off), Some(size)) = (u64_at(b, e + 8), u64_at(b, e + 16)) else {
            return;
        };
        let Some(end) = off.checked_add(size) else {
            continue;
        };
        if let Some(body) = b.get(off as usize..end as usize) {
            let crc = crc32fast::hash(body);
            if let Some(slot) = b.get_mut(e + 24..e + 28) {
                slot.copy_from_slice(&crc.to_le_bytes());
            }
        }
    }
    let table_end = table.saturating_add(count.saturating_mul(entry));
    if b.len() < 48 || table_end > b.len() {
        return;
    }
    let mut h = crc32fast::Hasher::new();
    h.update(&b[..44]);
    h.update(&b[table..table_end]);
    let crc = h.finalize();
    b[44..48].copy_from_slice(&crc.to_le_bytes());
}

/// Byte ranges covered by a checksum: header, table, and every section.
fn checked_ranges(bytes: &[u8]) -> Vec<std::ops::Range<usize>> {
    let count = u32_at(bytes, 32).unwrap() as usize;
    let mut r = Vec::new();
    r.push(0..48 + 32 * count);
    for s in format::sections(bytes).unwrap() {
        r.push(s.offset as usize..(s.offset + s.size) as usize);
    }
    r
}

#[test]
fn every_bit_flip_in_the_header_and_table_is_rejected() {
    let bytes = format::write(&full_asset()).unwrap();
    let table_end = 48 + 32 * 5;
    for byte in 0..table_end {
        for bit in 0..8 {
            let mut b = bytes.clone();
            b[byte] ^= 1 << bit;
            assert!(format::read(&b).is_err(), "flip byte {byte} bit {bit}");
        }
    }
}

#[test]
fn sampled_bit_flips_are_rejected_inside_sections_and_harmless_in_padding() {
    let asset = full_asset();
    let bytes = format::write(&asset).unwrap();
    let ranges = checked_ranges(&bytes);
    // xorshift64, fixed seed: the same 2000 flips every run.
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let (mut rejected, mut padding) = (0, 0);
    for _ in 0..2000 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let byte = (state % bytes.len() as u64) as usize;
        let bit = (state >> 32) % 8;
        let mut b = bytes.clone();
        b[byte] ^= 1 << bit;
        let covered = ranges.iter().any(|r| r.contains(&byte));
        match format::read(&b) {
            Err(_) if covered => rejected += 1,
            Ok(back) if !covered => {
                assert_eq!(back, asset);
                padding += 1;
            }
            other => panic!(
                "flip at byte {byte} (covered: {covered}) gave {:?}",
                other.map(|_| ())
            ),
        }
    }
    assert_eq!(rejected + padding, 2000);
    assert!(
        rejected > 1500,
        "most bytes are checksummed; got {rejected}"
    );
}

#[test]
fn single_byte_changes_behind_repaired_checksums_never_panic() {
    // Every byte of a small file set to a few values, checksums repaired: the reader must decide
    // without panicking, and whatever it accepts must write and read back the same.
    let bytes = format::write(&Asset {
        skeleton: Some(skeleton()),
        meshes: vec![prop_mesh()],
        clips: vec![wave()],
        ..Default::default()
    })
    .unwrap();
    for byte in 48..bytes.len() {
        for value in [0x00, 0x01, 0x7F, 0x80, 0xFF] {
            let mut b = bytes.clone();
            b[byte] = value;
            fix_checksums(&mut b);
            if let Ok(asset) = format::read(&b) {
                let again = format::write(&asset).unwrap();
                assert_eq!(
                    format::read(&again).unwrap(),
                    asset,
                    "byte {byte} = {value}"
                );
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn random_bytes_are_rejected(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        prop_assert!(format::read(&bytes).is_err());
        let _ = format::sections(&bytes);
    }

    #[test]
    fn random_mutations_never_panic(
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..8),
        cut in any::<prop::sample::Index>(),
        truncate in any::<bool>(),
        repair in any::<bool>(),
    ) {
        let mut b = format::write(&full_asset()).unwrap();
        for (at, v) in &edits {
            let i = at.index(b.len());
            b[i] = *v;
        }
        if truncate {
            b.truncate(cut.index(b.len()));
        }
        if repair {
            fix_checksums(&mut b);
        }
        let _ = format::sections(&b);
        if let Ok(asset) = format::read(&b) {
            let again = format::write(&asset).unwrap();
            prop_assert_eq!(format::read(&again).unwrap(), asset);
        }
    }
}
