//! The fault-injection matrix: every injectable fault on real programs, checking that the run
//! ends in a stop that names the cause, the block and the axis, that every axis came to rest
//! within the braking distance its limits allow, and that after the fault reset the control's
//! position equals the plant's to the encoder count.
//!
//! The stop distance and the speed at the fault are measured on the simulated plants' true
//! state (not on what the control reports); the bound is worked out here from the machine
//! limits: `v²/(2a) + v·a/(2j)` from the speed the axis had, plus what an acceleration along
//! the motion adds before the braking can start, plus one servo cycle of detection latency and
//! the following error the axis carried and 10 µm for the servo settling onto its final
//! setpoint.

mod common;

use common::{program, temp_program};
use klar::config::MachineConfig;
use klar::faults::{FaultConfig, FaultKind};
use klar::monitor::{StopCause, StopKind};
use klar::runtime::{Run, RunError, RunOptions};
use klar_interp::AxisLetter;
use klar_motion::AxisFault;
use klar_sim::faults::FAULT_INJECTED;
use std::path::PathBuf;

/// A program with long rapids and a fast feed move in X and Y.
const FAST: &str = "0 BEGIN PGM FAST MM\n\
1 TOOL CALL 1 Z S3000\n\
2 L X-250 Y-250 Z+50 R0 FMAX\n\
3 L X+250 FMAX\n\
4 L Y+250 F6000\n\
5 L X-250 Y-250 FMAX\n\
6 END PGM FAST MM\n";

/// Allowance for the servo settling onto its final setpoint, mm.
const SETTLE: f64 = 0.01;

/// Machine with the control's following-error monitor set on every axis.
fn machine() -> MachineConfig {
    let mut m = MachineConfig::builtin_mill();
    for a in &mut m.axes {
        a.following_error_limit = Some(0.5);
    }
    m
}

/// Closed-form braking distance from speed u at zero acceleration (trapezoidal or
/// triangular deceleration), written independently of the runtime's helper.
fn braking(u: f64, a: f64, j: f64) -> f64 {
    if u >= a * a / j {
        u * u / (2.0 * a) + u * a / (2.0 * j)
    } else {
        2.0 * u * (u / j).sqrt() / 2.0
    }
}

/// Upper bound of the stop distance from speed `v` and acceleration `acc` (true plant state).
fn stop_bound(v: f64, acc: f64, a: f64, j: f64, dt: f64) -> f64 {
    let u = v.abs();
    let b = if v != 0.0 {
        acc * v.signum()
    } else {
        acc.abs()
    };
    let (extra, u1) = if b > 0.0 {
        let t = b / j;
        (u * t + 0.5 * b * t * t, u + b * b / (2.0 * j))
    } else {
        (0.0, u)
    };
    extra + braking(u1, a, j) + u1 * dt
}

struct Case {
    program: PathBuf,
    kind: FaultKind,
    axis: Option<AxisLetter>,
    at: f64,
}

/// Figures of one case for the summary.
struct Outcome {
    stops_within: usize,
    axes: usize,
    counts_lost: i64,
    worst_ratio: f64,
}

/// Per axis: true position and velocity of the plant.
fn plant_state(run: &Run<'_, '_>, letters: &[AxisLetter]) -> Vec<(f64, f64)> {
    let sim = run.sim_axes().expect("simulated axes");
    letters
        .iter()
        .map(|&l| {
            let p = sim.plant_of(l).expect("plant");
            (p.actual_position(), p.actual_velocity())
        })
        .collect()
}

fn run_case(case: &Case) -> Outcome {
    let mut config = machine();
    config.faults = vec![FaultConfig {
        at: case.at,
        kind: case.kind,
        axis: case.axis,
        code: None,
        amplitude: (case.kind == FaultKind::Noise).then_some(20_000),
        duration: None,
        offset: None,
    }];
    let letters = config.letters();
    let dt = config.servo_period;
    let mut run = Run::start(
        &case.program,
        &config,
        RunOptions {
            realtime: false,
            trace: None,
        },
    )
    .unwrap_or_else(|f| panic!("{}: start refused: {}", case.program.display(), f.error));
    let mut prev = plant_state(&run, &letters);
    let mut before = prev.clone();
    let error = loop {
        prev.clone_from(&before);
        before = plant_state(&run, &letters);
        match run.step() {
            Ok(true) => {}
            Ok(false) => panic!("{:?} at {} s never stopped the run", case.kind, case.at),
            Err(e) => break e,
        }
    };
    let label = format!(
        "{} {:?}:{:?}@{}",
        case.program.file_name().unwrap().to_string_lossy(),
        case.kind,
        case.axis,
        case.at
    );

    // The error and the report name the cause, the axis and the block.
    let (axis, fault, line) = match &error {
        RunError::Fault {
            axis, fault, line, ..
        } => (*axis, fault.clone(), *line),
        other => panic!("{label}: expected an axis fault, got {other}"),
    };
    assert!(line > 0, "{label}: no program line in {error}");
    let report = run.stop_report().expect("a stop report").clone();
    assert_eq!(report.kind, StopKind::Quick, "{label}");
    assert_eq!(report.line, line, "{label}");
    assert_eq!(report.axis, Some(axis), "{label}");
    let text = report.to_string();
    assert!(
        text.contains(&format!("axis {axis}")) && text.contains(&format!("line {line}")),
        "{label}: {text}"
    );
    match case.kind {
        FaultKind::Drive => {
            assert_eq!(Some(axis), case.axis, "{label}");
            assert!(
                matches!(fault, AxisFault::Drive { code, .. } if code == FAULT_INJECTED),
                "{label}: {fault}"
            );
        }
        FaultKind::Comm => {
            assert_eq!(Some(axis), case.axis, "{label}");
            assert_eq!(fault, AxisFault::CommunicationLost, "{label}");
        }
        FaultKind::Limit => {
            assert_eq!(Some(axis), case.axis, "{label}");
            assert!(
                matches!(fault, AxisFault::LimitSwitch { .. }),
                "{label}: {fault}"
            );
        }
        FaultKind::Estop => assert_eq!(fault, AxisFault::EStop, "{label}"),
        // Stops on the path, not quick stops: tests/faults_path.rs; the setpoint guard's
        // jumps: tests/setpoint_guard.rs.
        FaultKind::Stall | FaultKind::Spindle | FaultKind::Jump => {
            unreachable!("{label}: not in this matrix")
        }
        FaultKind::Stuck | FaultKind::Noise => {
            assert_eq!(Some(axis), case.axis, "{label}");
            assert!(
                matches!(fault, AxisFault::FollowingError(_)),
                "{label}: {fault}"
            );
            assert!(
                matches!(
                    report.cause,
                    StopCause::FollowingError { .. } | StopCause::AxisFault(_)
                ),
                "{label}: {:?}",
                report.cause
            );
        }
    }

    // Stop distances on the plants' true positions against the braking distance.
    let rest = plant_state(&run, &letters);
    let mut within = 0;
    let mut worst_ratio = 0.0f64;
    for (i, a) in config.axes.iter().enumerate() {
        let (x0, v0) = before[i];
        let acc = (v0 - prev[i].1) / dt;
        let distance = (rest[i].0 - x0).abs();
        let fe = report.axes[i].following_error;
        // 10 µm for the servo settling onto the final setpoint.
        let bound = stop_bound(v0, acc, a.max_acceleration, a.max_jerk, dt) + fe + SETTLE;
        eprintln!(
            "{label} axis {}: v {:.2} mm/s, stop {:.4} mm, bound {:.4} mm",
            a.letter, v0, distance, bound
        );
        assert!(
            distance <= bound,
            "{label} axis {}: stopped in {distance} mm, braking distance {bound} mm",
            a.letter
        );
        within += 1;
        if bound > 2.0 * SETTLE {
            worst_ratio = worst_ratio.max(distance / bound);
        }
    }

    // Fault reset: the control's position is the plant's again, count for count.
    let sim = run.sim_axes().expect("simulated axes").clone();
    sim.repair_all().expect("repair");
    run.reset_faults()
        .unwrap_or_else(|e| panic!("{label}: reset refused: {e}"));
    let status = run.status();
    let mut counts_lost = 0;
    for (i, &l) in letters.iter().enumerate() {
        let plant = sim.plant_of(l).expect("plant");
        let cpu = plant.params().counts_per_unit;
        let truth = (plant.actual_position() * cpu).round() as i64;
        let encoder = (plant.measured_position() * cpu).round() as i64;
        let control = (status.actual[i] * cpu).round() as i64;
        let command = (status.commanded[i] * cpu).round() as i64;
        assert_eq!(
            encoder, truth,
            "{label} axis {l}: encoder off the true position"
        );
        counts_lost += (control - truth).abs();
        // The command was set to the measured position before the axes were enabled again:
        // what is left is the settling of one cycle, no jump.
        assert!(
            (command - truth).abs() <= 20,
            "{label} axis {l}: command {command} counts, plant {truth} counts"
        );
    }
    assert_eq!(counts_lost, 0, "{label}: counts lost");
    let failure = run.finish(Some(error)).expect_err("a faulted run fails");
    assert_eq!(
        failure.report.stop.as_ref(),
        Some(&report),
        "{label}: the run's report carries the stop"
    );
    Outcome {
        stops_within: within,
        axes: letters.len(),
        counts_lost,
        worst_ratio,
    }
}

#[test]
fn every_fault_on_real_programs_stops_within_braking_distance_without_losing_counts() {
    let fast = temp_program("fast.h", FAST);
    let rect = program("rectangle.h");
    let helix = program("helix_thread.h");
    use AxisLetter::{X, Y, Z};
    use FaultKind::*;
    let cases = [
        // Diagonal rapid of block 2, X rapid of block 3, fast feed of block 4.
        (fast.clone(), Drive, Some(X), 0.8),
        (fast.clone(), Drive, Some(Y), 2.9),
        (fast.clone(), Comm, Some(Y), 0.8),
        (fast.clone(), Comm, Some(X), 2.9),
        (fast.clone(), Noise, Some(X), 2.9),
        (fast.clone(), Stuck, Some(X), 2.9),
        (fast.clone(), Stuck, Some(Y), 0.8),
        (fast.clone(), Limit, Some(X), 2.9),
        (fast.clone(), Estop, None, 0.8),
        (fast.clone(), Estop, None, 2.9),
        (fast.clone(), Drive, Some(Y), 6.0),
        // The contour and the helix.
        (rect.clone(), Drive, Some(X), 4.0),
        (rect.clone(), Stuck, Some(Y), 5.0),
        (rect.clone(), Estop, None, 1.2),
        (helix.clone(), Comm, Some(Z), 0.8),
        (helix.clone(), Drive, Some(Y), 6.0),
        (helix.clone(), Limit, Some(Z), 1.0),
    ];
    let (mut faults, mut stops, mut axes, mut lost, mut worst) = (0, 0, 0, 0, 0.0f64);
    for (program, kind, axis, at) in cases {
        let o = run_case(&Case {
            program,
            kind,
            axis,
            at,
        });
        faults += 1;
        stops += o.stops_within;
        axes += o.axes;
        lost += o.counts_lost;
        worst = worst.max(o.worst_ratio);
    }
    eprintln!(
        "fault matrix: {faults} faults injected, {stops}/{axes} axis stops within braking \
         distance (worst {:.1} % of the bound), counts lost = {lost}",
        worst * 100.0
    );
}
