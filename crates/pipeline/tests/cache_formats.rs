//! PC2, MDD and EXR VAT files: byte layouts checked against the published layouts, parsed here by hand.
#![allow(clippy::unwrap_used)]

use sinew_core::glam::Vec3;
use sinew_pipeline::cache::{mdd, pc2, vat, Frames};

fn frames() -> Frames {
    // 3 vertices, 2 frames; vertex v of frame f at (v, f, v * 10 + f) + 0.25.
    let mut positions = Vec::new();
    for f in 0..2 {
        for v in 0..3 {
            positions.push(Vec3::new(v as f32, f as f32, (v * 10 + f) as f32) + 0.25);
        }
    }
    Frames {
        vertex_count: 3,
        frame_count: 2,
        fps: 24.0,
        positions,
        normals: Vec::new(),
    }
}

fn le_f32(b: &[u8], o: usize) -> f32 {
    f32::from_le_bytes(b[o..o + 4].try_into().unwrap())
}
fn be_f32(b: &[u8], o: usize) -> f32 {
    f32::from_be_bytes(b[o..o + 4].try_into().unwrap())
}

#[test]
fn pc2_bytes_follow_the_layout() {
    let b = pc2::write(&frames());
    assert_eq!(&b[0..12], b"POINTCACHE2\0");
    assert_eq!(i32::from_le_bytes(b[12..16].try_into().unwrap()), 1);
    assert_eq!(i32::from_le_bytes(b[16..20].try_into().unwrap()), 3);
    assert_eq!(le_f32(&b, 20), 0.0);
    assert_eq!(le_f32(&b, 24), 1.0);
    assert_eq!(i32::from_le_bytes(b[28..32].try_into().unwrap()), 2);
    assert_eq!(b.len(), 32 + 2 * 3 * 12);
    // Frame 1, vertex 2: (2.25, 1.25, 21.25).
    let o = 32 + (3 + 2) * 12;
    assert_eq!(
        [le_f32(&b, o), le_f32(&b, o + 4), le_f32(&b, o + 8)],
        [2.25, 1.25, 21.25]
    );
    let (h, back) = pc2::read(&b).unwrap();
    assert_eq!(h.points, 3);
    assert_eq!(back.positions, frames().positions);
}

#[test]
fn mdd_bytes_follow_the_layout() {
    let b = mdd::write(&frames());
    assert_eq!(i32::from_be_bytes(b[0..4].try_into().unwrap()), 2);
    assert_eq!(i32::from_be_bytes(b[4..8].try_into().unwrap()), 3);
    assert_eq!(be_f32(&b, 8), 0.0);
    assert_eq!(be_f32(&b, 12), 1.0 / 24.0);
    let o = 16 + (3 + 2) * 12;
    assert_eq!(
        [be_f32(&b, o), be_f32(&b, o + 4), be_f32(&b, o + 8)],
        [2.25, 1.25, 21.25]
    );
    let (times, back) = mdd::read(&b).unwrap();
    assert_eq!(times, [0.0, 1.0 / 24.0]);
    assert_eq!(back.positions, frames().positions);
}

#[test]
fn truncated_or_padded_caches_are_rejected() {
    for bytes in [pc2::write(&frames()), mdd::write(&frames())] {
        let is_pc2 = bytes.starts_with(b"POINTCACHE2");
        for cut in 0..bytes.len() {
            let r = if is_pc2 {
                pc2::read(&bytes[..cut]).map(|_| ())
            } else {
                mdd::read(&bytes[..cut]).map(|_| ())
            };
            assert!(r.is_err(), "truncation to {cut} bytes accepted");
        }
        let mut long = bytes.clone();
        long.push(0);
        assert!(if is_pc2 {
            pc2::read(&long).is_err()
        } else {
            mdd::read(&long).is_err()
        });
    }
    // A header claiming four billion points does not allocate.
    let mut b = pc2::write(&frames());
    b[16..20].copy_from_slice(&i32::MAX.to_le_bytes());
    assert!(pc2::read(&b)
        .unwrap_err()
        .to_string()
        .contains("points need"));
}

#[test]
fn vat_wraps_rows_and_reads_back_through_the_exr_crate() {
    let f = frames();
    // Width 2: each frame takes two rows; vertex 2 sits at x=0 of the frame's second row.
    let lay = vat::layout(3, 2, 2).unwrap();
    assert_eq!((lay.width, lay.rows_per_frame, lay.height), (2, 2, 4));
    let bytes = vat::write_exr(
        &[vat::VatImage {
            layer: "P",
            values: &f.positions,
            half: false,
        }],
        3,
        &lay,
    )
    .unwrap();
    // Read with the exr crate directly, not through sinew's reader.
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(&bytes))
        .unwrap();
    let layer = &image.layer_data[0];
    assert_eq!(layer.size, Vec2(2, 4));
    let chan = |n: &str| -> Vec<f32> {
        let c = layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.to_string() == n)
            .unwrap();
        c.sample_data.values_as_f32().collect()
    };
    let (r, g, b) = (chan("R"), chan("G"), chan("B"));
    // Frame 1 (rows 2-3), vertex 2 -> row 3, x 0.
    let i = 3 * 2;
    assert_eq!([r[i], g[i], b[i]], [2.25, 1.25, 21.25]);
    // The unused pixel after vertex 2 of frame 0 (row 1, x 1) is zero.
    assert_eq!([r[3], g[3], b[3]], [0.0, 0.0, 0.0]);
    let back = vat::read_exr(&bytes).unwrap();
    assert_eq!(vat::unpack(&back[0], 3, 2, &lay).unwrap(), f.positions);
    // Same input, same bytes.
    let again = vat::write_exr(
        &[vat::VatImage {
            layer: "P",
            values: &f.positions,
            half: false,
        }],
        3,
        &lay,
    )
    .unwrap();
    assert_eq!(bytes, again);
    assert!(vat::read_exr(&bytes[..bytes.len() / 2]).is_err());
}
