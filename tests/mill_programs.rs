//! End-to-end: the example programs on the built-in simulated mill, checked against geometry
//! computed here by hand from the program text (not from the interpreter or planner).

mod common;

use common::{assert_within_limits, distance_to_rectangle, program, run};
use klar::config::MachineConfig;

#[test]
fn rectangle_follows_the_programmed_contour() {
    let machine = MachineConfig::builtin_mill();
    let (result, trace) = run(&program("rectangle.h"), &machine);
    let report = result.expect("rectangle runs");
    let x = trace.column("X").unwrap();
    let y = trace.column("Y").unwrap();
    let z = trace.column("Z").unwrap();
    let dt = machine.servo_period;

    // Every commanded sample at cutting depth lies on the contour, or within the machine's
    // path tolerance of it where the planner blends a corner.
    let mut on_depth = 0;
    for i in 0..x.len() {
        if (z[i] + 5.0).abs() < 1e-12 {
            on_depth += 1;
            let d = distance_to_rectangle([x[i], y[i]]);
            assert!(
                d <= machine.tolerance + 1e-9,
                "sample {i} ({}, {}) is {d} mm off the contour",
                x[i],
                y[i]
            );
        }
    }
    assert!(on_depth > 1000, "only {on_depth} samples at depth");

    // Every programmed end point is passed: at tangent joins the path runs through it, at
    // a blended corner within the tolerance. Samples are spaced by at most F·T (F600 = 10 mm/s),
    // so the nearest one lies within F·T/2 of the path's closest point.
    let corners = [
        [0.0, 10.0],
        [0.0, 50.0],
        [10.0, 60.0],
        [80.0, 60.0],
        [100.0, 40.0],
        [100.0, 10.0],
        [90.0, 0.0],
        [10.0, 0.0],
    ];
    let reach = machine.tolerance + 10.0 * dt / 2.0 + 1e-9;
    for c in corners {
        let nearest = (0..x.len())
            .filter(|&i| z[i] == -5.0)
            .map(|i| (x[i] - c[0]).hypot(y[i] - c[1]))
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest <= reach,
            "end point {c:?}: nearest sample {nearest} mm away"
        );
    }
    // Program end: the last block's end point.
    let n = x.len() - 1;
    assert_eq!((x[n], y[n], z[n]), (-10.0, 10.0, 50.0));

    // Path speed at depth never above the programmed F600 (10 mm/s) beyond rounding.
    for i in 1..x.len() {
        if z[i] == -5.0 && z[i - 1] == -5.0 {
            let v = (x[i] - x[i - 1]).hypot(y[i] - y[i - 1]) / dt;
            assert!(v <= 10.0 * (1.0 + 1e-9), "path speed {v} mm/s above F600");
        }
    }
    assert_within_limits(&trace, &machine);
    assert!(report.blocks >= 19, "blocks executed: {}", report.blocks);
    for (l, fe) in &report.max_following_error {
        assert!(*fe < 0.05, "axis {l}: following error {fe} mm");
    }
}

#[test]
fn helix_samples_lie_on_the_cylinder_and_rise_linearly() {
    check_helix("helix_thread.h");
}

/// The same thread programmed on the contour (radius 20) with RL and a R5 tool: the trace
/// follows the compensated helix at radius 20 - 5 = 15 (internal thread, seed 000's table).
#[test]
fn the_compensated_thread_follows_the_tool_centre_helix() {
    check_helix("helix_thread_rl.h");
}

fn check_helix(name: &str) {
    let machine = MachineConfig::builtin_mill();
    let (result, trace) = run(&program(name), &machine);
    result.unwrap_or_else(|f| panic!("{name}: {}", f.error));
    let x = trace.column("X").unwrap();
    let y = trace.column("Y").unwrap();
    let z = trace.column("Z").unwrap();
    // From the program: pole X0 Y0, radius 15, start angle 0 at Z-8.25, IPA+2160, IZ+9.
    let (z0, h, ipa, r) = (-8.25, 9.0, 2160.0f64, 15.0);
    let mut unwrapped = 0.0f64;
    let mut last_angle: Option<f64> = None;
    let mut count = 0;
    for i in 0..x.len() {
        // Helix samples: strictly between start and end height, off the bore axis (the
        // rapid plunge runs down the axis at X0 Y0).
        if z[i] > z0 + 1e-9 && z[i] < z0 + h - 1e-9 && x[i].hypot(y[i]) > 1.0 {
            count += 1;
            let radius = x[i].hypot(y[i]);
            // The helix starts at the end of the radial move out to it and ends where the
            // move back in starts: corners the path may cross within its tolerance
            // (0.01 mm) while both moves overlap.
            let from_start = (x[i] - r).hypot(y[i]).hypot(z[i] - z0);
            let from_end = (x[i] - r).hypot(y[i]).hypot(z[i] - z0 - h);
            let band = if from_start.min(from_end) < 0.05 {
                0.01 + 1e-9
            } else {
                1e-9
            };
            assert!((radius - r).abs() < band, "sample {i}: radius {radius}");
            let a = y[i].atan2(x[i]).to_degrees();
            if let Some(prev) = last_angle {
                let mut d = a - prev;
                if d < -180.0 {
                    d += 360.0;
                }
                assert!(d > 0.0, "DR+ must turn counter-clockwise (sample {i})");
                unwrapped += d;
            } else {
                unwrapped = a.rem_euclid(360.0);
            }
            last_angle = Some(a);
            let expected_z = z0 + h * unwrapped / ipa;
            assert!(
                (z[i] - expected_z).abs() < band,
                "sample {i}: z {} but {} from the angle",
                z[i],
                expected_z
            );
        }
    }
    assert!(count > 10_000, "only {count} helix samples");
    assert!((unwrapped - ipa).abs() < 1.0, "turned {unwrapped} degrees");
    assert_within_limits(&trace, &machine);
}

#[test]
fn the_same_program_gives_the_same_trace_bit_for_bit() {
    let machine = MachineConfig::builtin_mill();
    let (_, a) = run(&program("rectangle.h"), &machine);
    let (_, b) = run(&program("rectangle.h"), &machine);
    assert_eq!(a, b);
}

/// The tool radius comes from the machine's tool table: programs/rectangle_rl.h with `DR+5`
/// replaced by a table entry R5 runs the same tool-centre path, 5 mm outside the contour.
#[test]
fn the_tool_table_gives_the_radius_for_compensation() {
    let text = std::fs::read_to_string(program("rectangle_rl.h"))
        .unwrap()
        .replace("TOOL CALL 1 Z S3000 DR+5", "TOOL CALL 1 Z S3000");
    let path = common::temp_program("rectangle_table.h", &text);
    let toml = format!(
        "{}\n[[tool]]\nnumber = 1\nname = \"end mill 10\"\nlength = 60.0\nradius = 5.0\n",
        klar::config::BUILTIN_MILL
    );
    let machine = MachineConfig::parse("table.toml", &toml).unwrap();
    let (result, trace) = run(&path, &machine);
    result.unwrap_or_else(|f| panic!("{}", f.error));
    let (x, y, z) = (
        trace.column("X").unwrap(),
        trace.column("Y").unwrap(),
        trace.column("Z").unwrap(),
    );
    let mut n = 0;
    for i in 0..x.len() {
        // On the contour pass: at depth, and past the approach/leave moves at X < -5.
        if z[i] == -5.0 && x[i] > -4.0 {
            n += 1;
            let d = distance_to_rectangle([x[i], y[i]]);
            assert!(
                (d - 5.0).abs() <= machine.tolerance + 1e-6,
                "row {i}: {d} mm"
            );
        }
    }
    assert!(n > 1000, "{n} samples on the contour pass");
}
