//! Scalar code compiled again for the vector extensions of the CPU it runs on, chosen at run
//! time: AVX-512 (512-bit vectors and mask registers) where present, else AVX2. LLVM then packs
//! independent lanes of arithmetic (a matrix's four rows, a block of pixels) into wide vectors.
//!
//! Rust never fuses or reorders floating-point operations and a vector lane rounds like a scalar
//! operation, so the results are identical whichever build runs.

/// `f()`, compiled for AVX-512 (F, VL, BW, DQ) or else AVX2 on x86-64 CPUs that have them
/// (checked at run time, once per call); plain `f()` elsewhere.
///
/// Pass an `#[inline(always)]` closure: only code inlined into the wide build is compiled for
/// it, and a large closure would be called instead. Keep the loop inside `f`, so that one check
/// serves many elements.
#[inline(always)]
pub(crate) fn with_simd<R>(f: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        if has!("avx512f") && has!("avx512vl") && has!("avx512bw") && has!("avx512dq") {
            #[target_feature(enable = "avx2,avx512f,avx512vl,avx512bw,avx512dq")]
            fn run<R>(f: impl FnOnce() -> R) -> R {
                f()
            }
            // SAFETY: `run` is compiled for AVX2 and AVX-512 F, VL, BW and DQ, all of which the
            // run-time check just above found on this CPU; `f` itself is safe code.
            return unsafe { run(f) };
        }
        if has!("avx2") {
            #[target_feature(enable = "avx2")]
            fn run<R>(f: impl FnOnce() -> R) -> R {
                f()
            }
            // SAFETY: `run` is compiled for AVX2, which the run-time check just above found on
            // this CPU; `f` itself is safe code.
            return unsafe { run(f) };
        }
    }
    f()
}
