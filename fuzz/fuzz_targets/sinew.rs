//! Fuzz target: `.sinew` (every section the runtime reads).
//!
//! Every section and the header carry a CRC-32, so nearly every mutation would stop at the checksum.
//! When the input's last byte is even the target first writes the file size and every checksum the
//! mutated bytes call for, so the mutations reach the section decoders; odd, the input is read as is.
#![no_main]

fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}

fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// Rewrites the file size, the section checksums and the header checksum (docs/format.md layout).
fn fix_checksums(b: &mut [u8]) -> Option<()> {
    let len = b.len() as u64;
    b.get_mut(16..24)?.copy_from_slice(&len.to_le_bytes());
    let table = usize::try_from(u64_at(b, 24)?).ok()?;
    let count = u32_at(b, 32)? as usize;
    let entry = u32_at(b, 36)? as usize;
    let table_end = table.checked_add(count.checked_mul(entry)?)?;
    if entry < 32 || table_end > b.len() {
        return None;
    }
    for i in 0..count {
        let e = table + i * entry;
        let offset = usize::try_from(u64_at(b, e + 8)?).ok()?;
        let size = usize::try_from(u64_at(b, e + 16)?).ok()?;
        let Some(body) = offset.checked_add(size).and_then(|end| b.get(offset..end)) else {
            continue;
        };
        let crc = crc32fast::hash(body);
        b.get_mut(e + 24..e + 28)?
            .copy_from_slice(&crc.to_le_bytes());
    }
    let mut h = crc32fast::Hasher::new();
    h.update(b.get(..44)?);
    h.update(b.get(table..table_end)?);
    let crc = h.finalize();
    b.get_mut(44..48)?.copy_from_slice(&crc.to_le_bytes());
    Some(())
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if data.last().is_some_and(|b| b % 2 == 0) {
        let mut fixed = data.to_vec();
        let _ = fix_checksums(&mut fixed);
        sinew_fuzz::import("asset.sinew", &fixed);
    } else {
        sinew_fuzz::import("asset.sinew", data);
    }
});
