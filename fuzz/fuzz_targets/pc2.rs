//! Fuzz target: PC2 point caches as `verify` reads them.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok((header, frames)) = sinew_pipeline::cache::pc2::read(data) {
        // What was read must be what the header declared.
        assert_eq!(
            frames.positions.len(),
            frames.vertex_count * frames.frame_count
        );
        std::hint::black_box(header);
    }
});
