//! Faults the axes can ride through end in a stop on the path: a setpoint underrun (the servo
//! loop stalls beyond the machine's lateness limit) and a spindle drive fault. The stop keeps
//! the programmed path, keeps the axis limits, comes to rest within the braking distance and
//! names the cause and the block; a short stall is only counted.

mod common;

use common::{assert_within_limits, distance_to_rectangle, program, run, temp_program};
use klar::config::MachineConfig;
use klar::faults::{FaultConfig, FaultKind};
use klar::monitor::{StopCause, StopKind};
use klar::runtime::RunError;

/// A long feed move along X = 250 (block 4, line 5) after two rapids.
const FAST: &str = "0 BEGIN PGM FAST MM\n\
1 TOOL CALL 1 Z S3000\n\
2 L X-250 Y-250 Z+50 R0 FMAX\n\
3 L X+250 FMAX\n\
4 L Y+250 F6000\n\
5 L X-250 Y-250 FMAX\n\
6 END PGM FAST MM\n";

/// Machine time of the first trace row of a fault-free run of `path` that satisfies `pred`
/// (row values in the order X, Y, Z).
fn first_time(path: &std::path::Path, pred: impl Fn(f64, f64, f64) -> bool) -> f64 {
    let (result, trace) = run(path, &MachineConfig::builtin_mill());
    result.unwrap_or_else(|f| panic!("{}", f.error));
    let x = trace.column("X").unwrap();
    let y = trace.column("Y").unwrap();
    let z = trace.column("Z").unwrap();
    (0..x.len())
        .find(|&i| pred(x[i], y[i], z[i]))
        .map(|i| trace.t[i])
        .expect("the probe run reaches the point")
}

fn fault(kind: FaultKind, at: f64, duration: Option<f64>) -> FaultConfig {
    FaultConfig {
        at,
        kind,
        axis: None,
        code: None,
        amplitude: None,
        duration,
        offset: None,
    }
}

#[test]
fn a_stall_beyond_the_lateness_limit_stops_on_the_path_within_braking_distance() {
    let path = temp_program("stall.h", FAST);
    // Half-way along the feed move of block 4 (at full feed by then).
    let at = first_time(&path, |x, y, _| x == 250.0 && y >= 0.0);
    let mut machine = MachineConfig::builtin_mill();
    machine.faults = vec![fault(FaultKind::Stall, at, Some(0.05))];
    let (result, trace) = run(&path, &machine);
    let failure = result.expect_err("the stall must stop the run");
    let limit = machine.setpoint_lateness_limit();
    assert!(
        (limit - 10.0 * machine.servo_period).abs() < 1e-12,
        "default limit {limit}"
    );
    match &failure.error {
        RunError::Underrun {
            late, line, block, ..
        } => {
            assert!((late - 0.05).abs() < 1e-9, "late {late}");
            assert_eq!((*line, *block), (5, Some(4)));
        }
        other => panic!("expected a setpoint underrun, got {other}"),
    }
    let stop = failure.report.stop.as_ref().expect("stop report");
    assert_eq!(stop.kind, StopKind::OnPath);
    assert!(
        matches!(stop.cause, StopCause::Underrun { .. }),
        "{:?}",
        stop.cause
    );
    assert!(stop.to_string().contains("setpoint underrun"), "{stop}");
    assert_eq!(failure.report.underruns, 1);

    // On the path: from the fault on, X stays at 250 and Z at 50 while Y brakes.
    let x = trace.column("X").unwrap();
    let y = trace.column("Y").unwrap();
    let z = trace.column("Z").unwrap();
    let from = trace
        .t
        .iter()
        .position(|&t| t >= at)
        .expect("rows after the fault");
    for i in from..x.len() {
        assert!(
            (x[i] - 250.0).abs() < 1e-9 && (z[i] - 50.0).abs() < 1e-9,
            "row {i} left the path: X {} Z {}",
            x[i],
            z[i]
        );
    }
    assert_within_limits(&trace, &machine);
    // Braking distance from the speed at the fault (closed form, v ≥ a²/j here).
    let dt = machine.servo_period;
    let v = (y[from] - y[from - 1]) / dt;
    let ax = &machine.axes[1];
    let (a, j) = (ax.max_acceleration, ax.max_jerk);
    assert!(v >= a * a / j, "speed at the fault {v}");
    let bound = v * v / (2.0 * a) + v * a / (2.0 * j) + v * dt + 1e-6;
    let distance = y[y.len() - 1] - y[from];
    assert!(
        distance > 0.0 && distance <= bound,
        "stopped in {distance} mm from {v} mm/s, bound {bound} mm"
    );
    assert!(
        y[y.len() - 1] < 250.0,
        "the move must not have been finished"
    );
}

#[test]
fn a_short_stall_is_counted_and_the_program_completes() {
    let path = temp_program("short_stall.h", FAST);
    let at = first_time(&path, |x, y, _| x == 250.0 && y >= 0.0);
    let mut machine = MachineConfig::builtin_mill();
    machine.faults = vec![fault(FaultKind::Stall, at, Some(0.005))];
    let (result, trace) = run(&path, &machine);
    let report = result.unwrap_or_else(|f| panic!("{}", f.error));
    assert_eq!(report.underruns, 1);
    assert!(report.stop.is_none());
    let y = trace.column("Y").unwrap();
    assert!((y[y.len() - 1] + 250.0).abs() < 1e-9);
}

/// The text of a machine file of the repository.
fn machine_text(name: &str) -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("machines")
        .join(name);
    std::fs::read_to_string(p).expect("machine file")
}

#[test]
fn a_limit_below_one_servo_period_is_refused() {
    // The mill's servo period is 1 ms.
    let text = format!(
        "max_setpoint_lateness = 0.0005\n{}",
        machine_text("mill.toml")
    );
    let e = MachineConfig::parse("test", &text).expect_err("refused");
    assert!(e.to_string().contains("max_setpoint_lateness"), "{e}");
    let text = format!(
        "max_setpoint_lateness = 0.002\n{}",
        machine_text("mill.toml")
    );
    let m = MachineConfig::parse("test", &text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.setpoint_lateness_limit(), 0.002);
}

#[test]
fn a_spindle_fault_while_cutting_stops_on_the_contour() {
    let path = program("rectangle.h");
    // On the left edge (block 8, L Y+50 at X 0, cutting depth Z-5).
    let at = first_time(&path, |x, y, z| x == 0.0 && y >= 30.0 && z == -5.0);
    let mut machine = MachineConfig::builtin_mill();
    machine.faults = vec![fault(FaultKind::Spindle, at, None)];
    let (result, trace) = run(&path, &machine);
    let failure = result.expect_err("the spindle fault must stop the run");
    let line = match &failure.error {
        RunError::Spindle { message, line } => {
            assert!(message.contains("fault"), "{message}");
            *line
        }
        other => panic!("expected a spindle error, got {other}"),
    };
    let stop = failure.report.stop.as_ref().expect("stop report");
    assert_eq!(stop.kind, StopKind::OnPath);
    assert!(
        matches!(stop.cause, StopCause::Spindle(_)),
        "{:?}",
        stop.cause
    );
    assert_eq!(stop.line, line);
    // The fault came while cutting (lines 7–17 are at Z-5) and every point at cutting
    // depth stays on the contour, through the stop.
    assert!((7..=17).contains(&line), "line {line}");
    let x = trace.column("X").unwrap();
    let y = trace.column("Y").unwrap();
    let z = trace.column("Z").unwrap();
    let mut at_depth = 0;
    for i in 0..x.len() {
        if (z[i] + 5.0).abs() < 1e-9 {
            at_depth += 1;
            let d = distance_to_rectangle([x[i], y[i]]);
            assert!(
                d <= machine.tolerance + 1e-6,
                "row {i}: {d} mm off the contour"
            );
        }
    }
    assert!(at_depth > 100);
    // It stopped at depth: the last point is still at Z-5, the contour unfinished.
    assert!((z[z.len() - 1] + 5.0).abs() < 1e-9);
    assert_within_limits(&trace, &machine);
}

#[test]
fn a_spindle_fault_needs_a_simulated_spindle() {
    let fault = "\n[[fault]]\nat = 1.0\nkind = \"spindle\"\n";
    let text = format!("{}{fault}", machine_text("canopen-sim.toml"));
    let e = MachineConfig::parse("test", &text).expect_err("refused");
    assert!(e.to_string().contains("simulated spindle"), "{e}");
    let text = format!("{}{fault}", machine_text("mill.toml"));
    MachineConfig::parse("test", &text).unwrap_or_else(|e| panic!("{e}"));
}
