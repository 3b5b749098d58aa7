//! Fuzz target: `.sinew` (every section the runtime reads).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    sinew_fuzz::import("asset.sinew", data);
});
