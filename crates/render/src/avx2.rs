//! Scalar code compiled a second time for AVX2 and chosen at run time, for the per-vertex and
//! per-triangle passes: LLVM then packs independent lanes of arithmetic (a matrix's four rows,
//! a cross product's three components) into 256-bit vectors.
//!
//! Rust never fuses or reorders floating-point operations and a vector lane rounds like a scalar
//! operation, so the results are identical with or without AVX2.

/// `f()`, compiled for AVX2 on x86-64 CPUs that have it (checked at run time, once per call).
///
/// Pass an `#[inline(always)]` closure: only code inlined into the AVX2 build is compiled for
/// AVX2, and a large closure would be called instead. Keep the loop inside `f`, so that one
/// check serves many elements.
#[inline(always)]
pub(crate) fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        #[target_feature(enable = "avx2")]
        fn run<R>(f: impl FnOnce() -> R) -> R {
            f()
        }
        // SAFETY: the CPU supports AVX2 (checked just above).
        return unsafe { run(f) };
    }
    f()
}
