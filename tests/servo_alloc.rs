//! The servo loop does not allocate once the run has started: a counting global allocator
//! counts the allocations, reallocations and frees made by the thread that runs the loop,
//! over a realtime run on the simulated mill of a program with lines, arcs, a helix and
//! blended corners. The interpreter runs in the reader thread, the speed step reuses its
//! buffers, the planner's queues are reserved when it is built and its corner blends go into
//! slots made then (see docs/canopen.md).

use klar::config::MachineConfig;
use klar::runtime::{Run, RunOptions};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::io::Write;
use std::sync::atomic::{AtomicU64, Ordering};

mod common;

/// The system allocator, counting what the marked thread asks of it.
struct Counting;

thread_local! {
    /// Set while the servo thread runs its loop.
    static MARKED: Cell<bool> = const { Cell::new(false) };
}

static ALLOCS: AtomicU64 = AtomicU64::new(0);
static FREES: AtomicU64 = AtomicU64::new(0);

fn marked() -> bool {
    MARKED.try_with(Cell::get).unwrap_or(false)
}

// SAFETY: every call is forwarded unchanged to the system allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if marked() {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: the caller's contract is passed on.
        unsafe { System.alloc(layout) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if marked() {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: the caller's contract is passed on.
        unsafe { System.alloc_zeroed(layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if marked() {
            ALLOCS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: the caller's contract is passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if marked() {
            FREES.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: the caller's contract is passed on.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Lines at several feeds, corners blended within the path tolerance, full and partial arcs,
/// a helix and rounded corners: every kind of segment the planner joins.
const PROGRAM: &str = "\
0 BEGIN PGM ALLOC MM
1 BLK FORM 0.1 Z X-50 Y-50 Z-20
2 BLK FORM 0.2 X+50 Y+50 Z+0
3 TOOL CALL 1 Z S2000
4 L Z+5 R0 FMAX
5 L X+0 Y+0 FMAX
6 L Z-1 F300
7 L X+20 Y+0 F1500
8 L X+20 Y+10
9 RND R2
10 L X+0 Y+10
11 CC X+0 Y+0
12 C X+10 Y+0 DR-
13 CC X+0 Y+0
14 C X+10 Y+0 DR+
15 CC X+0 Y+0
16 CP IPA+360 IZ-1 DR+ F800
17 L X-10 Y-10
18 CHF 1
19 L X-10 Y+5
20 L X+15 Y+5
21 L Z+5 FMAX
22 END PGM ALLOC MM
";

#[test]
fn the_servo_thread_does_not_allocate() {
    let path = common::temp_program("alloc.h", PROGRAM);
    let config = MachineConfig::builtin_mill();
    let (mut writer, rx) = klar::rt::chunk_queue();
    let drained = std::thread::spawn(move || {
        let mut out = Vec::new();
        klar::rt::drain(rx, &mut out).map(|()| out)
    });
    let servo = std::thread::spawn(move || {
        let options = RunOptions {
            realtime: true,
            trace: Some(&mut writer as &mut dyn Write),
        };
        let mut run = Run::start(&path, &config, options).expect("the run starts");
        MARKED.with(|m| m.set(true));
        let ended = loop {
            match run.step() {
                Ok(true) => {}
                Ok(false) => break None,
                Err(e) => break Some(e),
            }
        };
        MARKED.with(|m| m.set(false));
        let report = run.finish(ended).map_err(|f| f.error.to_string());
        drop(writer);
        report
    });
    let report = servo.join().expect("servo thread").expect("the run ends");
    let trace = drained.join().expect("writer thread").expect("trace");
    let allocs = ALLOCS.load(Ordering::Relaxed);
    let frees = FREES.load(Ordering::Relaxed);
    // The run really moved along the whole program and wrote its trace.
    assert!(report.cycles > 1000, "{} cycles", report.cycles);
    let rows = trace.iter().filter(|&&b| b == b'\n').count() as u64;
    assert_eq!(
        rows,
        report.cycles + 1,
        "a trace row per cycle and a header"
    );
    // The program's corners were blended (a stop at each would be allocation-free too).
    assert!(report.blends > 0, "no corner was blended");
    assert_eq!(
        (allocs, frees),
        (0, 0),
        "allocations and frees in the servo thread over {} cycles",
        report.cycles
    );
}
