#![warn(missing_docs)]

//! Test support shared by the workspace's crates (a dev-dependency only).
//!
//! **The counting allocator.** Every hot loop of the simulator — the physics
//! step, the contact queries, the haptic tick, the device's advance, the
//! link's send and receive, the image render — is proven allocation-free by
//! a test binary `tests/no_alloc.rs` that installs [`CountingAllocator`] as
//! its global allocator and asserts that [`count_allocations`] around the
//! loop returns 0. No crate of the ecosystem does this small job without
//! pulling in a profiler (dhat, stats_alloc's global statistics count every
//! thread); it is written here once instead of once per crate.

pub mod suite;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

thread_local! {
    // Const-initialized cells without destructors: using them inside the
    // allocator never allocates.
    static ACTIVE: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<u64> = const { Cell::new(0) };
}

fn record() {
    // `try_with`: during thread teardown the cells may be gone; such an
    // allocation is outside any counting window anyway.
    let _ = ACTIVE.try_with(|active| {
        if active.get() {
            let _ = COUNT.try_with(|c| c.set(c.get() + 1));
        }
    });
}

/// A global allocator that forwards to the system allocator and counts the
/// allocations and reallocations the *current thread* makes inside
/// [`count_allocations`]. Counting per thread keeps the test harness's
/// other threads (output capture, timers) out of the count.
///
/// Install it in a test binary:
/// `#[global_allocator] static GLOBAL: CountingAllocator = CountingAllocator;`
pub struct CountingAllocator;

// SAFETY: every call is forwarded unchanged to `System`; the bookkeeping
// touches only const-initialized thread-locals.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        record();
        // SAFETY: the caller's contract is passed on to `System`.
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        record();
        // SAFETY: as above.
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        record();
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Runs `f` and returns its result with the number of allocations (and
/// reallocations) this thread made meanwhile.
///
/// # Panics
/// If [`CountingAllocator`] is not the global allocator of the running
/// binary (a probe allocation made first is not seen), so that a
/// no-allocation test can never pass by counting nothing.
pub fn count_allocations<R>(f: impl FnOnce() -> R) -> (R, u64) {
    let was_active = ACTIVE.with(|a| a.replace(true));
    let start = COUNT.with(Cell::get);
    drop(std::hint::black_box(Box::new(0u64)));
    let probe = COUNT.with(Cell::get) - start;
    assert_eq!(
        probe, 1,
        "CountingAllocator is not the global allocator of this test binary"
    );
    let before = COUNT.with(Cell::get);
    let r = f();
    let n = COUNT.with(Cell::get) - before;
    ACTIVE.with(|a| a.set(was_active));
    (r, n)
}

#[cfg(test)]
mod tests {
    /// The unit-test binary runs on the system allocator: counting there
    /// must refuse rather than report a vacuous 0.
    #[test]
    #[should_panic(expected = "not the global allocator")]
    fn refuses_to_count_without_the_allocator_installed() {
        let _ = super::count_allocations(|| ());
    }
}
