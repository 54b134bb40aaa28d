//! A counting global allocator for the checks that code allocates nothing: a binary installs
//! [`CountingAllocator`] as its `#[global_allocator]`, then [`allocations_in`] counts the
//! allocations (and reallocations) a closure makes on the calling thread. Counting is per thread,
//! so tests running in parallel do not count each other's allocations.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

thread_local! {
    // `const` thread-locals without destructors: reading them never allocates.
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

/// The system allocator, counting on threads inside [`allocations_in`].
pub struct CountingAllocator;

fn count() {
    if COUNTING.try_with(Cell::get).unwrap_or(false) {
        let _ = ALLOCATIONS.try_with(|count| count.set(count.get() + 1));
    }
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Runs `work` and returns its result with the number of allocations it made on this thread.
/// Panics when the binary has not installed [`CountingAllocator`] (a count of 0 would then mean
/// nothing).
pub fn allocations_in<R>(work: impl FnOnce() -> R) -> (R, usize) {
    COUNTING.with(|counting| counting.set(true));
    ALLOCATIONS.with(|count| count.set(0));
    drop(std::hint::black_box(Box::new(0u64)));
    let probe = ALLOCATIONS.with(Cell::get);
    let result = work();
    let total = ALLOCATIONS.with(Cell::get);
    COUNTING.with(|counting| counting.set(false));
    assert_eq!(
        probe, 1,
        "the counting allocator is not this binary's global allocator"
    );
    (result, total - probe)
}
