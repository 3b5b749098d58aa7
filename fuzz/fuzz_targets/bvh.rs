//! Fuzz target: BVH motion.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    sinew_fuzz::import("motion.bvh", data);
});
