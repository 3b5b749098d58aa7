//! Fuzz target: glTF JSON with external buffers and images as companions.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    sinew_fuzz::import("model.gltf", data);
});
