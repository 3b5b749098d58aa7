//! Fuzz target: QC scripts with the SMDs and includes they name as companions.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    sinew_fuzz::import("model.qc", data);
});
