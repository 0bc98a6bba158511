//! The setpoint guard, the run's last line of defence: a commanded setpoint whose step breaks
//! an axis's velocity or acceleration limit never reaches a backend; the run stops with a
//! quick stop from the last good setpoint and names the axis, the step, the limit, the block
//! and the line. The planner's output is made to jump on purpose by the `jump` fault of a
//! simulated axis.

mod common;

use common::{max_derivative, program, run};
use klar::config::MachineConfig;
use klar::monitor::StopKind;
use klar::runtime::guard::VELOCITY_MARGIN;
use std::path::Path;
use std::process::Command;

/// Every axis's commanded trace (what the backends received, cycle by cycle) steps at most
/// the guard's bound, and its measured position never jumps either.
fn assert_no_step_beyond_the_guard(trace: &common::Trace, machine: &MachineConfig) {
    let dt = machine.servo_period;
    for a in &machine.axes {
        let l = a.letter.to_string();
        let bound = VELOCITY_MARGIN * a.max_velocity;
        let mut x = vec![a.start];
        x.extend(trace.column(&l).expect("column"));
        let v = max_derivative(&x, dt, 1);
        assert!(v <= bound, "axis {l}: commanded {v} units/s");
        let act = trace.column(&format!("{l}_act")).expect("column");
        let v = max_derivative(&act, dt, 1);
        assert!(v <= bound * 1.5, "axis {l}: measured {v} units/s");
    }
}

#[test]
fn a_jump_fault_stops_the_run_from_the_last_good_setpoint() {
    let mut machine = MachineConfig::builtin_mill();
    machine.faults.push("jump:X@1.1".parse().expect("fault"));
    let (result, trace) = run(&program("rectangle.h"), &machine);
    let failure = result.expect_err("the run must stop");
    let text = failure.error.to_string();
    // rectangle.h line 6 is block 5, `L X-10 Y+10 FMAX`, under way at 1.1 s: X moves
    // toward −10 at some 80 mm/s, so the jump of +1 mm is a step of 1 − 0.08 mm.
    assert!(
        text.contains("rectangle.h:6:1: block 5: setpoint guard: axis X: a step of 0.9")
            && text.contains("above the limit of 0.1743 mm (1.05 × 166 mm/s × 1 ms)"),
        "{text}"
    );
    let stop = failure.report.stop.expect("stop report");
    assert_eq!(stop.kind, StopKind::Quick);
    assert_no_step_beyond_the_guard(&trace, &machine);
    // Controlled: the stop ends at rest within the braking distance from the speed it had.
    let x = trace.column("X").expect("X");
    let n = x.len();
    assert!((x[n - 1] - x[n - 2]).abs() < 1e-12, "X still moving");
    let fault = stop.axes.first().expect("figures of X");
    let braking = klar::monitor::braking_distance(fault.velocity, 2000.0, 50_000.0);
    assert!(
        fault.stop_distance() <= braking + fault.velocity.abs() * 0.002 + 0.01,
        "stopped in {} mm, braking distance {braking} mm",
        fault.stop_distance()
    );
}

#[test]
fn klar_run_names_the_refused_step_and_a_real_drive_gets_no_jump() {
    let out = Command::new(env!("CARGO_BIN_EXE_klar"))
        .arg("run")
        .arg(program("rectangle.h"))
        .args(["--fault", "jump:Y@1.1", "--quiet"])
        .output()
        .expect("klar runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("rectangle.h:6:1: block 5: setpoint guard: axis Y: a step of")
            && stderr.contains("quick stop"),
        "{stderr}"
    );
    // Jumps are for simulated axes only: a machine on (simulated) CANopen drives refuses one.
    let canopen = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/canopen-sim.toml");
    let mut machine = MachineConfig::load(&canopen).expect("canopen-sim");
    machine.faults.push("jump:X@0.1".parse().expect("fault"));
    let (result, trace) = run(&program("rectangle.h"), &machine);
    let failure = result.expect_err("refused");
    assert!(
        failure
            .error
            .to_string()
            .contains("axis X is not a simulated axis"),
        "{}",
        failure.error
    );
    assert!(trace.t.is_empty());
}
