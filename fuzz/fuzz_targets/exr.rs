//! Fuzz target: EXR vertex-animation textures as `verify` reads them.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    std::hint::black_box(sinew_pipeline::cache::vat::read_exr(data).ok());
});
