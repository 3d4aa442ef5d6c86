//! Software prefetching for the shading pass, whose texels are touched in an order the hardware
//! prefetchers cannot predict.

/// Starts loading the cache line at `address` into the caches (a no-op on architectures other
/// than x86-64).
///
/// The address is never dereferenced: one outside any allocation is harmless (a prefetch
/// cannot fault), so callers may compute it with wrapping arithmetic and skip bounds checks.
#[inline(always)]
pub(crate) fn prefetch<T>(address: *const T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: SSE is part of the x86-64 baseline, and a prefetch has no architectural
        // effect, whatever the address.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(address.cast::<i8>()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = address;
}
