//! Fuzz target: GoldSrc MDL v10 with its T and 01.. companions.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    sinew_fuzz::import("model.mdl", data);
});
