//! Reading a run's status every servo cycle into the same buffers (`Run::status_into`, what
//! the dashboard's machine thread does between cycles) allocates nothing once the buffers
//! hold the machine's axes, and gives what `Run::status` gives.

use klar::config::MachineConfig;
use klar::runtime::{Run, RunOptions};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicU64, Ordering};

mod common;

/// The system allocator, counting what the marked thread asks of it.
struct Counting;

thread_local! {
    /// Set around the calls being counted.
    static MARKED: Cell<bool> = const { Cell::new(false) };
}

static EVENTS: AtomicU64 = AtomicU64::new(0);

fn count() {
    if MARKED.try_with(Cell::get).unwrap_or(false) {
        EVENTS.fetch_add(1, Ordering::Relaxed);
    }
}

// SAFETY: every call is forwarded unchanged to the system allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller's contract is passed on.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        // SAFETY: the caller's contract is passed on.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        // SAFETY: the caller's contract is passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        count();
        // SAFETY: the caller's contract is passed on.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Lines, an arc and the spindle turning: every field of the status changes.
const PROGRAM: &str = "\
0 BEGIN PGM STATUS MM
1 BLK FORM 0.1 Z X-50 Y-50 Z-20
2 BLK FORM 0.2 X+50 Y+50 Z+0
3 TOOL CALL 1 Z S2000
4 L Z+5 R0 FMAX M3
5 L X+10 Y+0 F1200
6 CC X+0 Y+0
7 C X-10 Y+0 DR+
8 L X-10 Y-10 F600
9 L Z+5 FMAX M5
10 END PGM STATUS MM
";

#[test]
fn reading_the_status_every_cycle_allocates_nothing() {
    let path = common::temp_program("status.h", PROGRAM);
    let config = MachineConfig::builtin_mill();
    let options = RunOptions {
        realtime: false,
        trace: None,
    };
    let mut run = Run::start(&path, &config, options).expect("the run starts");
    let mut status = run.status();
    let (mut cycles, mut moved, mut turning) = (0u64, false, false);
    let ended = loop {
        let stepped = run.step();
        MARKED.with(|m| m.set(true));
        run.status_into(&mut status);
        MARKED.with(|m| m.set(false));
        // The same as a status made anew.
        assert_eq!(status, run.status(), "cycle {cycles}");
        cycles += 1;
        moved |= status.path_speed > 0.0;
        turning |= status.spindle_rpm.is_some_and(|r| r > 0.0);
        match stepped {
            Ok(true) => {}
            Ok(false) => break None,
            Err(e) => break Some(e),
        }
    };
    run.finish(ended)
        .map_err(|f| f.error.to_string())
        .expect("the run ends");
    assert!(cycles > 1000 && moved && turning, "{cycles} cycles");
    assert_eq!(status.commanded.len(), config.axes.len());
    assert_eq!(EVENTS.load(Ordering::Relaxed), 0, "allocations or frees");
}
