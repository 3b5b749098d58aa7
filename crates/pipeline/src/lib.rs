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

/// Allocates and frees one block of [`WARM_HEAP_BYTES`] without touching it, at the start of the
/// process. With glibc's allocator this raises its mmap threshold to the block's size (and its trim
/// threshold to twice that): the documented dynamic adjustment when a block it mapped is freed
/// (mallopt(3), `M_MMAP_THRESHOLD`). Blocks below that size then come from the heap and are reused
/// after they are freed, instead of being mapped and unmapped each time, so a process that builds
/// and drops many states of a few hundred kilobytes (the clip encoder's) pays a page fault for
/// each page once instead of on every reuse. The block itself is mapped and unmapped untouched (no
/// page fault). With another allocator it is one allocation and nothing else
/// (docs/performance.md, session 17). The `sinew` binary calls it first unless
/// `SINEW_NO_WARM_HEAP` is set (for measuring), as does the encoder's timing example.
pub fn warm_heap() {
    drop(std::hint::black_box(Vec::<u8>::with_capacity(
        WARM_HEAP_BYTES,
    )));
}

/// Whether the heap warm-ups ([`warm_heap`], [`warm_thread_heap`]) run: unless
/// `SINEW_NO_WARM_HEAP` is set (for measuring).
pub fn heap_warming() -> bool {
    std::env::var_os("SINEW_NO_WARM_HEAP").is_none()
}

/// The block of [`warm_heap`]: 16 MiB (glibc adjusts its threshold up to 32 MiB).
pub const WARM_HEAP_BYTES: usize = 16 << 20;

/// Allocates and frees one block of [`WARM_THREAD_HEAP_BYTES`] without touching it, on a worker
/// thread when it starts. With glibc's allocator a thread allocates from an arena of its own,
/// whose heap grows by making more of its reserved address space writable, by what each
/// allocation lacks (an `mprotect` call each time, most of them one page); after [`warm_heap`]
/// has raised the trim threshold to 32 MiB, this block grows it once to its size and stays, so
/// the thread's allocations below that size neither grow nor shrink it (a Fox convert made about
/// 300 such calls on its two workers, docs/performance.md, session 25). Its pages are not
/// touched, so none is faulted in; without [`warm_heap`] the block is mapped and unmapped
/// untouched. With another allocator it is one allocation and nothing else.
pub fn warm_thread_heap() {
    drop(std::hint::black_box(Vec::<u8>::with_capacity(
        WARM_THREAD_HEAP_BYTES,
    )));
}

/// A thread pool builder whose workers warm their heaps as they start ([`warm_thread_heap`]),
/// unless `SINEW_NO_WARM_HEAP` is set ([`heap_warming`]): the `sinew` binary's pools and the
/// encoder's timing example.
pub fn warmed_pool_builder() -> rayon::ThreadPoolBuilder {
    let warm = heap_warming();
    rayon::ThreadPoolBuilder::new().start_handler(move |_| {
        if warm {
            warm_thread_heap();
        }
    })
}

/// The block of [`warm_thread_heap`]: 8 MiB, below [`WARM_HEAP_BYTES`] (so it comes from the
/// thread's arena) and within a glibc arena heap's 64 MiB.
pub const WARM_THREAD_HEAP_BYTES: usize = 8 << 20;
const _: () =
    assert!(WARM_THREAD_HEAP_BYTES < WARM_HEAP_BYTES && WARM_THREAD_HEAP_BYTES < 64 << 20);
