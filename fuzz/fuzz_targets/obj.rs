//! Fuzz target: Wavefront OBJ with its MTL libraries as companions.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    sinew_fuzz::import("model.obj", data);
});
