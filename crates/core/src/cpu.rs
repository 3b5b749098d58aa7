//! Which instruction set the per-frame loops run with.
//!
//! The hot functions are written once, in portable Rust on glam, and on x86_64 compiled twice: for the
//! baseline (SSE2, which every x86_64 CPU has) and with AVX enabled; at run time the AVX copy is used
//! when the CPU has AVX. Both copies perform the same IEEE operations in the same order: AVX changes the
//! instruction encoding (three-operand forms without register copies, broadcasts straight from memory),
//! not the arithmetic, and FMA is never enabled because fusing a multiply with an add changes rounding.
//! So results are the same bits on every x86_64 CPU; unit tests run both copies and compare them.
//!
//! Skinning goes further on AVX: its kernel (`crate::skin_avx`) is written with AVX intrinsics, two
//! vertices per 256-bit register, each half doing the portable loop's operations in its order.
//!
//! One loop has a third form: decoding compressed keys, whose per-lane variable bit shifts have no SSE2
//! or AVX instruction, is also written with AVX2 integer intrinsics and used when the CPU has AVX2.
//! Integer shifts and masks are exact, and its float operations are the portable code's, so it too
//! gives the same bits.

/// Defines a function that runs `$generic` (an `#[inline(always)]` function with the same signature)
/// from an AVX-compiled copy when the CPU has AVX, and from the baseline build otherwise.
macro_rules! multiversion {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty => $generic:path;) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx")]
                fn with_avx($($arg: $ty),*) -> $ret {
                    $generic($($arg),*)
                }
                if $crate::cpu::use_avx() {
                    // SAFETY: `use_avx` is true only when the running CPU has AVX, which is all that
                    // `with_avx` requires.
                    #[allow(unsafe_code)]
                    return unsafe { with_avx($($arg),*) };
                }
            }
            $generic($($arg),*)
        }
    };
}
pub(crate) use multiversion;

/// Defines a function that calls `$avx2` (a `#[target_feature(enable = "avx2")]` function with the
/// same signature, written with AVX2 integer instructions) when the CPU has AVX2, and the portable
/// `$generic` otherwise. As with [`multiversion`], both give the same bits; unit tests compare them.
macro_rules! dispatch_avx2 {
    ($(#[$meta:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty => $generic:path, $avx2:path;) => {
        $(#[$meta])*
        $vis fn $name($($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            if $crate::cpu::use_avx2() {
                // SAFETY: `use_avx2` is true only when the running CPU has AVX2, which is all that
                // the AVX2 function requires.
                #[allow(unsafe_code)]
                return unsafe { $avx2($($arg),*) };
            }
            $generic($($arg),*)
        }
    };
}
pub(crate) use dispatch_avx2;

/// Set by [`set_baseline_only`].
static BASELINE_ONLY: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Makes every multiversioned function run its baseline copy (`true`) or pick by CPU again
/// (`false`), process-wide. Results are the same bits either way; this exists to measure what the
/// AVX and AVX2 copies gain and to check a build on a machine without them.
pub fn set_baseline_only(yes: bool) {
    BASELINE_ONLY.store(yes, std::sync::atomic::Ordering::Relaxed);
}

/// True when the AVX copies may run: the CPU has AVX, [`set_baseline_only`] was not asked for it
/// (and, in this crate's unit tests, the calling thread has not asked for the baseline).
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn use_avx() -> bool {
    #[cfg(test)]
    if BASELINE.with(|b| b.get()) {
        return false;
    }
    !BASELINE_ONLY.load(std::sync::atomic::Ordering::Relaxed)
        && std::arch::is_x86_feature_detected!("avx")
}

/// True when the AVX2 functions may run: as [`use_avx`], for AVX2.
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn use_avx2() -> bool {
    #[cfg(test)]
    if BASELINE.with(|b| b.get()) {
        return false;
    }
    !BASELINE_ONLY.load(std::sync::atomic::Ordering::Relaxed)
        && std::arch::is_x86_feature_detected!("avx2")
}

#[cfg(test)]
thread_local! {
    static BASELINE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f` with the baseline copies on this thread (unit tests compare it with the AVX copies).
#[cfg(test)]
pub(crate) fn baseline<R>(f: impl FnOnce() -> R) -> R {
    BASELINE.with(|b| b.set(true));
    let r = f();
    BASELINE.with(|b| b.set(false));
    r
}
