//! Streaming (non-temporal) fills of the frame's background.
//!
//! Most of a frame is background, and its colour and depth are written once per frame and not
//! read back by the renderer. Ordinary stores first read every cache line they write (read for
//! ownership); streaming stores write whole lines without reading them, halving that memory
//! traffic.

/// Sets every value of `values` to `value`: the whole 64-byte lines inside the slice with
/// streaming stores (x86-64, where SSE is part of the baseline), the partial lines at its ends
/// plainly. Call [`fence`] before the data is handed to another thread.
#[inline]
pub(crate) fn fill(values: &mut [f32], value: f32) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_set1_ps, _mm_stream_ps};
        const LINE: usize = 64 / std::mem::size_of::<f32>();
        let head = values.as_ptr().align_offset(64).min(values.len());
        let (head, rest) = values.split_at_mut(head);
        let mut lines = rest.chunks_exact_mut(LINE);
        head.fill(value);
        // SAFETY: SSE is part of the x86-64 baseline.
        let quad = unsafe { _mm_set1_ps(value) };
        for line in &mut lines {
            for quad_of_line in line.chunks_exact_mut(4) {
                // SAFETY: SSE is part of the x86-64 baseline. `quad_of_line` is four `f32` of
                // the exclusively borrowed slice, so writable, and 16-byte aligned: `rest`
                // starts where `align_offset` says the pointer is 64-byte aligned (when it
                // cannot say, `head` is the whole slice and there are no lines), and lines and
                // quads are 64 and 16 bytes long.
                unsafe { _mm_stream_ps(quad_of_line.as_mut_ptr(), quad) };
            }
        }
        lines.into_remainder().fill(value);
    }
    #[cfg(not(target_arch = "x86_64"))]
    values.fill(value);
}

/// Orders the streaming stores of [`fill`] before every later store of this thread, such as
/// the release that publishes a finished tile to the thread that joins it.
#[inline]
pub(crate) fn fence() {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE is part of the x86-64 baseline; a fence touches no memory.
    unsafe {
        std::arch::x86_64::_mm_sfence()
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[cfg_attr(miri, ignore = "Miri cannot run the streaming store's inline assembly")]
    fn fills_every_alignment_and_length() {
        for offset in 0..20 {
            for len in [0, 1, 3, 15, 16, 17, 40, 100, 180] {
                let mut v = vec![f32::NAN; 200];
                fill(&mut v[offset..offset + len], 2.5);
                fence();
                assert!(v[offset..offset + len].iter().all(|&x| x == 2.5));
                assert!(v[..offset]
                    .iter()
                    .chain(&v[offset + len..])
                    .all(|x| x.is_nan()));
            }
        }
    }
}
