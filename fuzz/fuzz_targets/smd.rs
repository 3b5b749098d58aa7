//! Fuzz target: SMD (GoldSrc and Source flavours).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    sinew_fuzz::import("model.smd", data);
});
