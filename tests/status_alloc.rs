//! Reading a run's status every servo cycle into the same buffers (`Run::status_into`, what
//! the dashboard's machine thread does between cycles) allocates nothing once the buffers
//! hold the machine's axes, and gives what `Run::status` gives.

use klar::config::MachineConfig;
use klar::runtime::{Run, RunOptions};

mod common;
#[path = "common/counting.rs"]
mod counting;

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
        counting::begin();
        run.status_into(&mut status);
        counting::end();
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
    assert_eq!(counting::counts(), (0, 0), "allocations, frees");
}
