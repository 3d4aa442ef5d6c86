//! Software prefetching for the shading pass, whose data (set-up planes, texels) is touched in
//! an order the hardware prefetchers cannot predict.

/// Starts loading the cache lines of `*value` into the caches (a no-op on architectures other
/// than x86-64).
#[inline(always)]
pub(crate) fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let start = (value as *const T).cast::<i8>();
        for offset in (0..std::mem::size_of::<T>()).step_by(64) {
            // SAFETY: SSE is part of the x86-64 baseline; the addresses lie within `*value`,
            // and a prefetch has no architectural effect.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(start.add(offset)) };
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}
