//! Compiling a QC script and its SMD files into a studio model the way GoldSrc's studiomdl does, so
//! that converting the QC gives what converting the MDL studiomdl would write gives: the union of the
//! bones that vertices use (and their ancestors) in first-use order, vertices moved into their bone's
//! space and kept to two decimals, normals merged within 2 degrees, the default 90-degree turn of
//! every root bone in animations, motion extraction, looping sequences closed, and animation values
//! quantised to 16 bits per channel with studiomdl's per-bone scales. docs/formats/halflife.md lists
//! each rule with where it comes from.

mod math;
mod reference;
mod script;
mod simplify;
mod state;

pub use script::compile;
pub use state::{activity_number, control, ACTIVITIES, MAX_BONES, MAX_FRAMES};
#[cfg(test)]
mod tests;
