//! A counting global allocator for the tests that prove a thread allocates nothing: it
//! counts the allocations (reallocations included) and frees of the current thread between
//! [`begin`] and [`end`]. Included only by those tests (`#[path]`), since it installs itself
//! as the test binary's global allocator.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

/// The system allocator, counting what a marked thread asks of it.
struct Counting;

thread_local! {
    /// Set while this thread's allocations are counted.
    static MARKED: Cell<bool> = const { Cell::new(false) };
    /// Allocations (and reallocations) of this thread while marked.
    static ALLOCS: Cell<u64> = const { Cell::new(0) };
    /// Frees of this thread while marked.
    static FREES: Cell<u64> = const { Cell::new(0) };
}

fn bump(counter: &'static std::thread::LocalKey<Cell<u64>>) {
    if MARKED.try_with(Cell::get).unwrap_or(false) {
        let _ = counter.try_with(|c| c.set(c.get() + 1));
    }
}

// SAFETY: every call is forwarded unchanged to the system allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        bump(&ALLOCS);
        // SAFETY: the caller's contract is passed on.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        bump(&ALLOCS);
        // SAFETY: the caller's contract is passed on.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        bump(&ALLOCS);
        // SAFETY: the caller's contract is passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        bump(&FREES);
        // SAFETY: the caller's contract is passed on.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Starts counting this thread's allocations and frees (adding to what it counted before).
pub fn begin() {
    MARKED.with(|m| m.set(true));
}

/// Stops counting this thread's allocations and frees.
pub fn end() {
    MARKED.with(|m| m.set(false));
}

/// This thread's counted allocations and frees so far.
pub fn counts() -> (u64, u64) {
    (ALLOCS.with(Cell::get), FREES.with(Cell::get))
}
