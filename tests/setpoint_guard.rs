//! The setpoint guard, the run's last line of defence: a commanded setpoint whose step breaks
//! an axis's velocity or acceleration limit never reaches a backend; the run stops with a
//! quick stop from the last good setpoint and names the axis, the step, the limit, the block
//! and the line. Two ways to make the planner's output jump: the `jump` fault of a simulated
//! axis, and the known TCPM switch bug on mill5 (with the test run switched off, which would
//! refuse that program before motion).

mod common;

use common::{max_derivative, program, run, temp_program};
use klar::config::MachineConfig;
use klar::monitor::{StopCause, StopKind};
use klar::runtime::RunError;
use klar::runtime::guard::{VELOCITY_MARGIN, Violation};
use std::path::Path;
use std::process::Command;

const TCPM_JUMP: &str = "BEGIN PGM TCPMJUMP MM\n\
L A+76.323 C+0 FMAX\n\
L M128\n\
L Z-18.674 F3000\n\
END PGM TCPMJUMP MM\n";

fn mill5() -> MachineConfig {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/mill5.toml");
    MachineConfig::load(&p).unwrap_or_else(|e| panic!("{e}"))
}

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
fn the_tcpm_switch_jump_never_reaches_the_backends() {
    let path = temp_program("guard_tcpm_jump.h", TCPM_JUMP);
    let mut machine = mill5();
    machine.check_before_run = false;
    let (result, trace) = run(&path, &machine);
    let failure = result.expect_err("the run must stop");
    let RunError::Setpoint {
        diagnostic,
        violation,
    } = &failure.error
    else {
        panic!("{}", failure.error);
    };
    // Y and Z both jump by hundreds of mm at the switch; the guard names the worst of them
    // against its limit.
    let Violation::Velocity {
        axis, step, limit, ..
    } = *violation
    else {
        panic!("{violation:?}");
    };
    assert!(
        matches!(axis.to_string().as_str(), "Y" | "Z"),
        "{violation}"
    );
    assert!(step > 50.0 && limit < 0.2, "{violation}");
    assert_eq!((diagnostic.line, diagnostic.col), (4, 1));
    let text = failure.error.to_string();
    assert!(
        text.contains("guard_tcpm_jump.h:4:1: setpoint guard: axis")
            && text.contains("in one servo cycle, above the limit of"),
        "{text}"
    );
    let stop = failure.report.stop.expect("stop report");
    assert_eq!(stop.kind, StopKind::Quick);
    assert_eq!((stop.line, stop.axis), (4, Some(axis)));
    assert!(matches!(stop.cause, StopCause::Setpoint(_)), "{stop}");
    assert_no_step_beyond_the_guard(&trace, &machine);
    // The axes rest where the last good setpoint left them: at the start of block 4.
    let last = trace.rows.last().expect("rows");
    for (k, want) in [(1, 0.0), (2, 150.0)] {
        assert!((last[k] - want).abs() < 1e-9, "axis {k} at {}", last[k]);
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
