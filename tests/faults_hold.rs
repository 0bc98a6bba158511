//! Stops that keep the path: a feed hold in the middle of the rectangle contour rests on the
//! contour and the resumed run continues on it; a requested stop on a rapid comes to rest
//! within the braking distance of the axis limits, and the control's position equals the
//! plant's to the count afterwards.

mod common;

use common::hold::run_with_hold;
use common::{distance_to_rectangle, program, temp_program};
use klar::config::MachineConfig;
use klar::monitor::{StopCause, StopKind};
use klar::runtime::{Run, RunError, RunOptions};
use klar_interp::AxisLetter;

#[test]
fn a_feed_hold_on_the_contour_rests_on_it_and_resumes_along_it() {
    let machine = MachineConfig::builtin_mill();
    let path = program("rectangle.h");
    // Hold on the long top edge (block 10, L X+80 at Y 60) while cutting at Z-5; resume
    // after 300 cycles at rest.
    let held = run_with_hold(&path, &machine, 300, |s| {
        s.line == 11 && s.path_speed > 0.0 && s.commanded[0] > 40.0
    });
    assert!(held.resumed > held.asked);
    let trace = held.trace;
    let x = trace.column("X").unwrap();
    let y = trace.column("Y").unwrap();
    let z = trace.column("Z").unwrap();
    // Every commanded point at cutting depth lies on the contour (within the blending
    // tolerance), before, during and after the hold; the hold kept one point for a while.
    let mut still = 0;
    for i in 0..x.len() {
        if (z[i] + 5.0).abs() < 1e-9 {
            let d = distance_to_rectangle([x[i], y[i]]);
            assert!(
                d <= machine.tolerance + 1e-6,
                "row {i}: {d} mm off the contour"
            );
            if i > 0 && x[i] == x[i - 1] && y[i] == y[i - 1] && y[i] == 60.0 {
                still += 1;
            }
        }
    }
    assert!(still >= 250, "rested only {still} cycles on the top edge");
    // The run completed the contour after the resume: it ends at X-10 Y+10 Z+50.
    let n = x.len() - 1;
    assert!((x[n] + 10.0).abs() < 1e-6 && (y[n] - 10.0).abs() < 1e-6 && (z[n] - 50.0).abs() < 1e-6);
}

#[test]
fn a_requested_stop_on_a_rapid_rests_within_braking_distance_without_losing_counts() {
    let text = "0 BEGIN PGM FAST MM\n1 TOOL CALL 1 Z S3000\n2 L X-250 Y+0 Z+50 R0 FMAX\n\
                3 L X+250 FMAX\n4 END PGM FAST MM\n";
    let path = temp_program("stop_rapid.h", text);
    let machine = MachineConfig::builtin_mill();
    let x_axis = &machine.axes[0];
    let mut run = Run::start(
        &path,
        &machine,
        RunOptions {
            realtime: false,
            trace: None,
        },
    )
    .unwrap_or_else(|f| panic!("{}", f.error));
    let sim = run.sim_axes().expect("sim axes").clone();
    let mut requested: Option<(f64, f64)> = None;
    let error = loop {
        let status = run.status();
        if requested.is_none() && status.line == 4 && status.commanded[0] > 0.0 {
            let plant = sim.plant_of(AxisLetter::X).unwrap();
            requested = Some((plant.actual_position(), plant.actual_velocity()));
            run.request_stop();
        }
        match run.step() {
            Ok(true) => {}
            Ok(false) => panic!("the program ended before the stop"),
            Err(e) => break e,
        }
    };
    assert!(matches!(error, RunError::Stopped { line: 4 }), "{error}");
    let report = run.stop_report().expect("stop report").clone();
    assert_eq!(
        (report.kind, &report.cause),
        (StopKind::OnPath, &StopCause::Requested)
    );
    let (x0, v0) = requested.unwrap();
    let plant = sim.plant_of(AxisLetter::X).unwrap();
    let distance = plant.actual_position() - x0;
    let (a, j) = (x_axis.max_acceleration, x_axis.max_jerk);
    // v ≥ a²/j here: the trapezoidal closed form, plus one cycle and 10 µm of settling.
    assert!(v0 >= a * a / j, "v {v0}");
    let bound = v0 * v0 / (2.0 * a) + v0 * a / (2.0 * j) + v0 * machine.servo_period + 0.01;
    assert!(
        distance > 0.0 && distance <= bound,
        "stopped in {distance} mm from {v0} mm/s, bound {bound}"
    );
    eprintln!("requested stop from {v0:.2} mm/s: {distance:.4} mm, bound {bound:.4} mm");
    // Position integrity at rest: the control reads the plant's encoder count.
    let status = run.status();
    for (i, &l) in run.letters().to_vec().iter().enumerate() {
        let p = sim.plant_of(l).unwrap();
        let cpu = p.params().counts_per_unit;
        assert_eq!(
            (status.actual[i] * cpu).round() as i64,
            (p.actual_position() * cpu).round() as i64,
            "axis {l}"
        );
    }
    run.finish(Some(error))
        .expect_err("a stopped run reports the stop");
}

#[test]
fn a_program_error_reached_while_running_stops_at_the_end_of_the_previous_block() {
    // FN 14 raises a program error when block 4 is reached; with the test run switched off the
    // run gets there: the move of block 3 completes, then the run reports block 4.
    let text = "0 BEGIN PGM E MM\n1 TOOL CALL 1 Z S1000\n2 L X+0 Y+0 Z+10 R0 FMAX\n\
                3 L X+40 F3000\n4 FN 14: ERROR = 1001\n5 L X+0\n6 END PGM E MM\n";
    let path = temp_program("fn14_run.h", text);
    let mut machine = MachineConfig::builtin_mill();
    machine.check_before_run = false;
    let (result, trace) = common::run(&path, &machine);
    match result.expect_err("FN 14 stops the run").error {
        RunError::Program(d) => assert_eq!((d.line, d.block), (5, Some(4)), "{d}"),
        other => panic!("expected the program error, got {other}"),
    }
    let x = trace.column("X").unwrap();
    let last = *x.last().unwrap();
    assert!((last - 40.0).abs() < 1e-6, "stopped at X {last}");
    assert!(x.iter().all(|&v| v <= 40.0 + 1e-9));
}
