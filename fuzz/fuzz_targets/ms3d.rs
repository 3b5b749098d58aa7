//! Fuzz target: MS3D (Milkshape 3D 1.3/1.4 binary).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    sinew_fuzz::import("model.ms3d", data);
});
