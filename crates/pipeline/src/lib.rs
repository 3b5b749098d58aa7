//! sinew-pipeline is everything between import and output: joint-name mapping, partial-body splitting,
//! LOD generation, keyframe reduction and quantization, compiling a Scene into the `.sinew` runtime
//! format, baking vertex caches and verifying them against the runtime.

pub mod bake;
pub mod body;
pub mod cache;
pub mod compile;
pub mod compress;
pub mod cut;
pub mod export;
mod heap;
pub mod lod;
mod lod_parts;
pub mod mapping;
pub mod pose;
pub mod preview;
pub mod retarget;
pub mod split;
pub mod surface;
pub mod texture;
pub mod verify;

pub use cut::{cut_clips, CutError};

pub use heap::{
    heap_warming, warm_heap, warm_thread_heap, warmed_pool_builder, WARM_HEAP_BYTES,
    WARM_THREAD_HEAP_BYTES,
};
