//! Fuzz target: MDD point caches as `verify` reads them.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if let Ok((times, frames)) = sinew_pipeline::cache::mdd::read(data) {
        assert_eq!(
            frames.positions.len(),
            frames.vertex_count * frames.frame_count
        );
        assert_eq!(times.len(), frames.frame_count);
    }
});
