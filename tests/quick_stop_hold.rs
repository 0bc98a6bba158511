//! A quick stop on the 5-axis mill during a move that turns the table: the faulted axis is
//! held where it stands (its command does not ramp on), every other axis brakes within its
//! own braking distance from the speed it had, and the stop report says the machine came to
//! rest as soon as it did (a rotary axis dithering by a few encoder counts is at rest).

mod common;

use common::{commanded, run, temp_program};
use klar::config::{BUILTIN_MILL5, MachineConfig};
use klar::faults::{FaultConfig, FaultKind};
use klar_interp::AxisLetter;

const TURNING: &str = "BEGIN PGM Q MM\nL X+0 Y+0 Z+100 A+0 C+0 R0 FMAX\n\
    L X+40 A+30 C+120 F3000\nEND PGM Q MM\n";

#[test]
fn a_faulted_rotary_axis_is_held_and_the_others_brake_within_their_distance() {
    let mut machine = MachineConfig::parse("mill5", BUILTIN_MILL5).expect("mill5");
    let at = 1.2;
    machine.faults = vec![FaultConfig {
        at,
        kind: FaultKind::Drive,
        axis: Some(AxisLetter::C),
        code: None,
        amplitude: None,
        duration: None,
        offset: None,
    }];
    let path = temp_program("qs_hold.h", TURNING);
    let (result, trace) = run(&path, &machine);
    let failure = result.expect_err("the drive fault stops the run");
    let stop = failure.report.stop.expect("a stop report");
    assert!(
        stop.t_rest - stop.t_fault < 1.0,
        "at rest after {} s",
        stop.t_rest - stop.t_fault
    );
    let cols = commanded(&trace, &["X", "A", "C"]);
    let k = trace
        .t
        .iter()
        .position(|&t| t >= stop.t_fault - 1e-9)
        .expect("rows after the fault");
    let n = cols[0].len() - 1;
    // C: held from the first stop cycle on, not ramped on from its commanded speed.
    let held = cols[2][k + 1];
    assert!(
        cols[2][k + 1..].iter().all(|&c| c == held),
        "C moved after the fault: {} .. {}",
        held,
        cols[2][n]
    );
    // X and A brake within v²/(2a) + v·a/j of where they were (a ramp of the deceleration
    // at the jerk limit costs at most the speed times the ramp time a/j more).
    for (col, axis) in [(0, 0usize), (1, 3)] {
        let limits = &machine.axes[axis];
        let dt = machine.servo_period;
        let v = ((cols[col][k] - cols[col][k - 1]) / dt).abs();
        let (a, j) = (limits.max_acceleration, limits.max_jerk);
        let bound = v * v / (2.0 * a) + v * a / j + 1e-9;
        let travelled = (cols[col][n] - cols[col][k]).abs();
        assert!(v > 1.0, "axis {} was moving ({v}/s)", limits.letter);
        assert!(
            travelled <= bound,
            "axis {} braked over {travelled}, bound {bound}",
            limits.letter
        );
    }
}
