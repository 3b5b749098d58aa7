//! Fuzz target: binary glTF (GLB), with external buffers as companions.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    sinew_fuzz::import("model.glb", data);
});
