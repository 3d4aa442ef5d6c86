//! A global allocator that counts allocations, for the tests that check that a per-frame hot
//! path allocates nothing. Include it with `#[path]` in a test binary of its own.
//!
//! The count is per thread: the hot paths measured run on the calling thread, and a process
//! also has threads of its own (the test harness's, a thread pool starting up late under load)
//! whose allocations are not the hot path's — counting them made the test fail now and then
//! on a busy machine.

#![deny(unsafe_op_in_unsafe_fn, clippy::undocumented_unsafe_blocks)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    // `try_with`: a thread being torn down may still allocate.
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: every method hands its arguments unchanged to `System` and returns its answer, so
// `System`'s adherence to the `GlobalAlloc` contract carries over; the counting beside it only
// bumps a `const` thread-local `Cell` (no lazy initialisation, no destructor), which neither
// allocates nor unwinds.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: our caller upholds `GlobalAlloc::alloc`'s contract (`layout` of non-zero
        // size), which is `System.alloc`'s.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: our caller passes a block this allocator, that is `System`, allocated with
        // `layout`, as `System.dealloc` requires.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: as for `dealloc`, and our caller's `new_size` is valid for `layout`'s
        // alignment, as `System.realloc` requires.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations (and reallocations) made by the calling thread so far.
pub fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}
