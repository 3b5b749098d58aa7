//! The heap the `sinew` binary works in, prepared as the process and each worker thread start:
//! with glibc's allocator, blocks up to 32 MiB come from the heap and stay there once freed, and
//! as much of each heap as most converts need is set aside for transparent huge pages, so
//! that the memory a long clip's encoder touches first is faulted in 2 MiB at a time instead of
//! 4 KiB (docs/performance.md, sessions 17, 25 and 37).

/// The largest block glibc takes from a heap rather than mapping it alone (mallopt(3): the most
/// `M_MMAP_THRESHOLD` may be on a 64-bit system). A long clip's encoder state is megabytes, built
/// and dropped many times: from the heap, its pages are faulted in once and then reused; mapped
/// alone, every build faults them in again.
const MMAP_THRESHOLD: usize = 32 << 20;

/// What glibc keeps of a heap's free top before it gives memory back (`M_TRIM_THRESHOLD`): twice
/// the largest heap block, so that freeing one never trims the heap the next one is built in.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const TRIM_THRESHOLD: usize = 2 * MMAP_THRESHOLD;

/// The block of [`warm_heap`]: 30 MiB, below the 32 MiB that glibc takes from the heap.
pub const WARM_HEAP_BYTES: usize = 30 << 20;

/// The block of [`warm_thread_heap`]: 30 MiB, as [`WARM_HEAP_BYTES`], within a glibc arena heap's
/// 64 MiB.
pub const WARM_THREAD_HEAP_BYTES: usize = 30 << 20;
const _: () = assert!(WARM_THREAD_HEAP_BYTES < MMAP_THRESHOLD && WARM_HEAP_BYTES < MMAP_THRESHOLD);

/// The size transparent huge pages come in where the advice is given (x86-64, and arm64 with 4 KiB
/// pages).
#[cfg(target_os = "linux")]
const HUGE_PAGE: usize = 2 << 20;

/// At the start of the process: with glibc, raises its mmap threshold to 32 MiB and its trim
/// threshold to 64 MiB (mallopt(3)), then sets aside [`RESERVED_BLOCKS`] blocks of
/// [`WARM_HEAP_BYTES`] of the main heap for huge pages ([`reserve`]). Before session 37 a freed
/// 16 MiB block raised the threshold to 16 MiB through glibc's dynamic adjustment (session 17): a
/// process that builds and drops many states of a few hundred kilobytes pays a page fault for
/// each page once instead of on every reuse. With another allocator it is the allocations and the
/// advice. The `sinew` binary calls it first unless
/// `SINEW_NO_WARM_HEAP` is set (for measuring), as does the encoder's timing example.
pub fn warm_heap() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets the allocator's parameters (the values are within its limits);
    // it is called before any other thread starts.
    #[allow(unsafe_code)]
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD as libc::c_int);
        libc::mallopt(libc::M_TRIM_THRESHOLD, TRIM_THRESHOLD as libc::c_int);
    }
    reserve(WARM_HEAP_BYTES);
}

/// Whether the heap warm-ups ([`warm_heap`], [`warm_thread_heap`]) run: unless
/// `SINEW_NO_WARM_HEAP` is set (for measuring).
pub fn heap_warming() -> bool {
    std::env::var_os("SINEW_NO_WARM_HEAP").is_none()
}

/// On a worker thread when it starts: [`reserve`] of [`WARM_THREAD_HEAP_BYTES`]. With glibc a
/// thread allocates from an arena of its own, whose heap grows by making more of its reserved
/// address space writable, by what each allocation lacks (an `mprotect` call each time, most of
/// them one page: a Fox convert made about 300 such calls on its two workers, session 25); these
/// blocks grow it once, and with the trim threshold of [`warm_heap`] it stays.
pub fn warm_thread_heap() {
    reserve(WARM_THREAD_HEAP_BYTES);
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

/// Allocates [`RESERVED_BLOCKS`] blocks of `bytes` without touching them, advises the kernel to
/// back their whole 2 MiB pages with transparent huge pages (Linux, `madvise(MADV_HUGEPAGE)`: on
/// systems whose `transparent_hugepage/enabled` is `madvise` or `always`), and frees them. The
/// blocks stay in the heap they came from, and the allocations after them reuse their memory:
/// where they first touch a page of it, the kernel faults in 2 MiB at once. Nothing is touched
/// here, so nothing is faulted in; the advice changes how pages are backed, never what they hold.
///
/// Why: a convert of a 23 s capture at 120 Hz (cmu_01_01.glb, `--effort fast`) faulted in about
/// 14,000 pages, a third of its processor time in the kernel; with the heap's memory advised,
/// about 2,000 (docs/performance.md, session 37).
///
/// A block the allocator refuses (a system that commits memory strictly, many workers) is left
/// out: the warm-up is a hint, never a reason to stop.
fn reserve(bytes: usize) {
    let mut blocks: Vec<Vec<u8>> = Vec::with_capacity(RESERVED_BLOCKS);
    for _ in 0..RESERVED_BLOCKS {
        let mut block = Vec::<u8>::new();
        if block.try_reserve_exact(bytes).is_err() {
            break;
        }
        advise_huge_pages(block.as_ptr(), block.capacity());
        blocks.push(block);
    }
    drop(std::hint::black_box(blocks));
}

/// How many blocks [`reserve`] sets aside: two of 30 MiB fill most of a glibc arena heap's 64 MiB
/// (a block may be at most the 32 MiB of [`MMAP_THRESHOLD`] to come from the heap).
const RESERVED_BLOCKS: usize = 2;

/// [`reserve`]'s advice for the whole huge pages inside `len` bytes from `start`.
fn advise_huge_pages(start: *const u8, len: usize) {
    #[cfg(target_os = "linux")]
    {
        let first = (start as usize).next_multiple_of(HUGE_PAGE);
        let end = (start as usize).saturating_add(len) / HUGE_PAGE * HUGE_PAGE;
        if end > first {
            // SAFETY: the range lies inside a live allocation of this process (the block, not yet
            // freed); MADV_HUGEPAGE changes only how its pages are backed. A failure (a kernel
            // without transparent huge pages) leaves everything as it was.
            #[allow(unsafe_code)]
            unsafe {
                libc::madvise(first as *mut libc::c_void, end - first, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = (start, len);
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::{advise_huge_pages, HUGE_PAGE};

    /// The `VmFlags` of the mapping of this process that holds `address` (`/proc/self/smaps`).
    fn flags_at(address: usize) -> Option<Vec<String>> {
        let smaps = std::fs::read_to_string("/proc/self/smaps").ok()?;
        let mut inside = false;
        for line in smaps.lines() {
            let range = line.split_whitespace().next().unwrap_or("");
            if let Some((lo, hi)) = range.split_once('-') {
                if let (Ok(lo), Ok(hi)) =
                    (usize::from_str_radix(lo, 16), usize::from_str_radix(hi, 16))
                {
                    inside = (lo..hi).contains(&address);
                    continue;
                }
            }
            if inside {
                if let Some(flags) = line.strip_prefix("VmFlags:") {
                    return Some(flags.split_whitespace().map(String::from).collect());
                }
            }
        }
        None
    }

    /// The whole huge pages inside a block are advised (`hg` in the mapping's flags), and the
    /// advice reaches no further than the block's 2 MiB boundaries.
    #[test]
    fn a_block_s_whole_huge_pages_are_advised_and_nothing_around_them() {
        if !std::path::Path::new("/sys/kernel/mm/transparent_hugepage/enabled").exists() {
            return; // a kernel without transparent huge pages: nothing to advise
        }
        let block = Vec::<u8>::with_capacity(12 << 20);
        let start = block.as_ptr() as usize;
        advise_huge_pages(block.as_ptr(), block.capacity());
        let first = start.next_multiple_of(HUGE_PAGE);
        let end = (start + block.capacity()) / HUGE_PAGE * HUGE_PAGE;
        assert!(end - first >= 8 << 20);
        for at in [first, first + HUGE_PAGE, end - 1] {
            let flags = flags_at(at).expect("the block is mapped");
            assert!(flags.iter().any(|f| f == "hg"), "{at:#x}: {flags:?}");
        }
        // Just outside the whole pages (inside the block where it starts or ends off a
        // boundary): not advised.
        if first > start {
            let flags = flags_at(first - 1).expect("the block is mapped");
            assert!(
                !flags.iter().any(|f| f == "hg"),
                "{:#x}: {flags:?}",
                first - 1
            );
        }
        drop(block);
    }
}
