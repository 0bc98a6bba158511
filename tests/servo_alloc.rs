//! The servo loop does not allocate once the run has started: a counting global allocator
//! counts the allocations, reallocations and frees made by the thread that runs the loop,
//! over a realtime run on the simulated mill of a program with lines, arcs, a helix and
//! blended corners; of a dense polyline whose look-ahead holds more pieces than the
//! planner's reserved queue; and of spline blocks. The interpreter runs in the reader thread,
//! the speed step reuses its buffers, the planner's queues are reserved when it is built (a
//! longer look-ahead waits for room instead of growing them), and its corner blends and
//! spline elements go into slots made then (see docs/canopen.md).

use klar::config::MachineConfig;
use klar::runtime::{Run, RunOptions};
use std::io::Write;

mod common;
#[path = "common/counting.rs"]
mod counting;

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

/// What a run counted.
struct Counted {
    report: klar::runtime::RunReport,
    allocs: u64,
    frees: u64,
}

/// Runs `program` on the simulated mill (on the wall clock when `realtime`) in a thread of
/// its own, counting that thread's allocations and frees over its servo loop; checks that
/// the trace has a row per cycle.
fn run_counted(name: &str, program: &str, realtime: bool) -> Counted {
    let path = common::temp_program(name, program);
    let config = MachineConfig::builtin_mill();
    let (mut writer, rx) = klar::rt::chunk_queue();
    let drained = std::thread::spawn(move || {
        let mut out = Vec::new();
        klar::rt::drain(rx, &mut out).map(|()| out)
    });
    let servo = std::thread::spawn(move || {
        let options = RunOptions {
            realtime,
            trace: Some(&mut writer as &mut dyn Write),
        };
        let mut run = Run::start(&path, &config, options).expect("the run starts");
        counting::begin();
        let ended = loop {
            match run.step() {
                Ok(true) => {}
                Ok(false) => break None,
                Err(e) => break Some(e),
            }
        };
        counting::end();
        let counts = counting::counts();
        let report = run.finish(ended).map_err(|f| f.error.to_string());
        drop(writer);
        report.map(|r| (r, counts))
    });
    let (report, (allocs, frees)) = servo.join().expect("servo thread").expect("the run ends");
    let trace = drained.join().expect("writer thread").expect("trace");
    // The run really moved along the whole program and wrote its trace.
    assert!(report.cycles > 100, "{} cycles", report.cycles);
    let rows = trace.iter().filter(|&&b| b == b'\n').count() as u64;
    assert_eq!(
        rows,
        report.cycles + 1,
        "a trace row per cycle and a header"
    );
    Counted {
        report,
        allocs,
        frees,
    }
}

#[test]
fn the_servo_thread_does_not_allocate() {
    let c = run_counted("alloc.h", PROGRAM, true);
    assert!(c.report.cycles > 1000, "{} cycles", c.report.cycles);
    // The program's corners were blended (a stop at each would be allocation-free too).
    assert!(c.report.blends > 0, "no corner was blended");
    assert_eq!(
        (c.allocs, c.frees),
        (0, 0),
        "allocations and frees in the servo thread over {} cycles",
        c.report.cycles
    );
}

/// A zigzag of `chords` chords along X, 0.02 mm forward and 0.02 mm across each: corners of
/// 90° blended one by one, so each chord leaves pieces of its own in the look-ahead, which
/// within the look-ahead distance on the built-in mill (about 210 mm) would hold more than
/// the reserved 4096 (motion's `reserve_tests` counts them on the planner alone).
fn zigzag(chords: usize) -> String {
    let mut p = String::from("0 BEGIN PGM DENSE MM\n1 TOOL CALL 1 Z S2000\n");
    // A line longer than the look-ahead first: the chords are taken in while the servo
    // loop runs, not when the run starts.
    p.push_str("2 L Z+5 R0 FMAX\n3 L X-250 Y+0 FMAX\n4 L Z-1 F3000\n");
    p.push_str("5 L X+0 Y+0 F12000\n");
    for k in 1..=chords {
        let (x, y) = (0.02 * k as f64, 0.02 * (k % 2) as f64);
        p.push_str(&format!("{} L X{x:+.3} Y{y:+.3}\n", k + 5));
    }
    p.push_str(&format!("{} L Z+5 FMAX\n", chords + 6));
    p.push_str(&format!("{} END PGM DENSE MM\n", chords + 7));
    p
}

#[test]
fn a_look_ahead_longer_than_the_reserve_waits_instead_of_allocating() {
    let chords = 12_000;
    // On simulated time: the zigzag's corners are slow, and the loop is the same.
    let c = run_counted("dense.h", &zigzag(chords), false);
    assert!(
        c.report.blocks as usize > chords,
        "{} blocks",
        c.report.blocks
    );
    assert_eq!(
        (c.allocs, c.frees),
        (0, 0),
        "allocations and frees in the servo thread over {} cycles",
        c.report.cycles
    );
}

/// Spline blocks as a CAM post-processor writes them (see programs/spline.h), several in a
/// row so that the look-ahead holds more than one, after a line longer than the look-ahead
/// (they are taken in while the servo loop runs).
const SPLINES: &str = "\
0 BEGIN PGM SPLINES MM
1 TOOL CALL 1 Z S8000
2 L Z+5 R0 FMAX
3 L X-250 Y+19.385 FMAX
4 L Z-0.5 F500
4 L X+28.338 Y+19.385 F12000
5 SPL X24.875 Y15.924 Z-0.5 K3X-4.688E-002 K2X2.459E-002 K1X3.486E+000 K3Y-4.563E-002 K2Y2.155E-002 K1Y3.486E+000 K3Z0.000E+000 K2Z0.000E+000 K1Z0.000E+000 F1000
6 SPL X+21.875 Y+12.924 K3X+0 K2X+0 K1X+3 K3Y+0 K2Y+0 K1Y+3
7 SPL X+18.875 Y+9.924 K3X+0.05 K2X-0.05 K1X+3 K3Y+0 K2Y+0 K1Y+3
8 SPL X+15.875 Y+6.924 K3X-0.05 K2X+0.05 K1X+3 K3Y+0 K2Y+0 K1Y+3
9 L Z+5 FMAX
10 END PGM SPLINES MM
";

#[test]
fn spline_blocks_do_not_allocate_in_the_servo_thread() {
    let c = run_counted("splines.h", SPLINES, true);
    assert_eq!(
        (c.allocs, c.frees),
        (0, 0),
        "allocations and frees in the servo thread over {} cycles",
        c.report.cycles
    );
}

/// Coolant switched on and off between the moves of a blended contour, after a line longer
/// than the look-ahead (the blocks are taken in while the servo loop runs): each switch is
/// an event that waits with the move before it for that move's corner.
fn coolant_between_moves(moves: usize) -> String {
    let mut p = String::from("0 BEGIN PGM EVENTS MM\n1 TOOL CALL 1 Z S2000\n");
    p.push_str("2 L Z+5 R0 FMAX\n3 L X-250 Y+0 FMAX\n4 L Z-1 F3000\n5 L X+0 Y+0 F6000\n");
    let mut n = 6;
    for k in 1..=moves {
        let y = if k % 2 == 1 { 2.0 } else { 0.0 };
        p.push_str(&format!("{n} L X{:+.3} Y{y:+.3}\n", 2.0 * k as f64));
        let m = if k % 2 == 1 { "M8" } else { "M9" };
        p.push_str(&format!("{} {m}\n", n + 1));
        n += 2;
    }
    p.push_str(&format!("{n} L Z+5 FMAX\n{} END PGM EVENTS MM\n", n + 1));
    p
}

#[test]
fn events_between_moves_do_not_allocate_in_the_servo_thread() {
    let c = run_counted("events.h", &coolant_between_moves(60), false);
    assert!(c.report.blocks > 120, "{} blocks", c.report.blocks);
    assert_eq!(
        (c.allocs, c.frees),
        (0, 0),
        "allocations and frees in the servo thread over {} cycles",
        c.report.cycles
    );
}
