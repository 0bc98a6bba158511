//! End-to-end: the rectangle on CiA 402 drives in the velocity modes over the in-memory
//! bus (machines/canopen-csv-sim.toml): X in cyclic synchronous velocity with klar closing
//! the position loop, the spindle in profile velocity ramping on its own.

mod common;

use common::{distance_to_rectangle, program, run};
use klar::config::MachineConfig;
use klar_sim::plant::SimAxisParams;
use std::path::Path;

fn machine() -> MachineConfig {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/canopen-csv-sim.toml");
    MachineConfig::load(&p).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_rectangle_runs_with_a_csv_axis_and_a_pv_spindle() {
    let m = machine();
    let (result, trace) = run(&program("rectangle.h"), &m);
    let report = result.unwrap_or_else(|f| panic!("{}", f.error));
    assert_eq!(report.blocks, 19);
    // The bound for the CSV axis, from its gain and its plant (velocity loop only): the
    // error left after the feed-forward shrinks by (1 − K_p·T) per cycle while the drive's
    // velocity falls short by at most δv = a/ω + F/K_v (lag behind the acceleration a with
    // the loop's ω = K_v/m, and the friction F it must overcome at top speed), so
    // |e| ≤ δv / K_p.
    let plant = SimAxisParams::default();
    let (gain, a, v) = (50.0, 2000.0, 166.0);
    let si = plant.si_per_unit();
    let omega = plant.velocity_gain / plant.mass;
    let friction = plant.coulomb_friction + plant.viscous_friction * v * si;
    let bound = (a / omega + friction / plant.velocity_gain / si) / gain + 2e-4;
    let (x, y, z) = (
        trace.column("X").unwrap(),
        trace.column("Y").unwrap(),
        trace.column("Z").unwrap(),
    );
    let (xa, ya) = (
        trace.column("X_act").unwrap(),
        trace.column("Y_act").unwrap(),
    );
    let mut on_contour = 0;
    for i in 0..x.len() {
        if z[i] == -5.0 {
            on_contour += 1;
            assert!(distance_to_rectangle([x[i], y[i]]) <= m.tolerance + 1e-9);
            assert!(
                distance_to_rectangle([xa[i], ya[i]]) < bound,
                "row {i}: the drives left the contour"
            );
        }
    }
    assert!(on_contour > 100, "{on_contour} rows on the contour");
    let n = x.len() - 1;
    assert_eq!((x[n], y[n], z[n]), (-10.0, 10.0, 50.0));
    assert!((xa[n] + 10.0).abs() < 1e-3 && (ya[n] - 10.0).abs() < 1e-3);
    eprintln!(
        "CSV machine: max following error {:?}, bound {bound:.4} mm, spindle wait {:.3} s",
        report.max_following_error, report.spindle_wait
    );
    for (l, fe) in &report.max_following_error {
        assert!(
            *fe < bound,
            "axis {l}: following error {fe} (bound {bound})"
        );
    }
    // S3000 from standstill at the drive's 4000 rpm/s takes 0.75 s, after the three
    // cycles that switch the drive on; "target reached" counts from the cycle after the
    // drive has seen the target. The program waits for all of it before feeding.
    let period = m.servo_period;
    assert!(
        (0.75..=0.75 + 5.0 * period).contains(&report.spindle_wait),
        "spindle wait {} s",
        report.spindle_wait
    );
}

#[test]
fn profile_velocity_on_an_axis_is_refused_when_the_machine_opens() {
    let mut m = machine();
    if let klar::config::BackendConfig::Canopen(c) = &mut m.axes[0].backend {
        c.drive.mode = klar_drivers::cia402::AxisMode::Pv;
    } else {
        panic!("X is a CANopen axis");
    }
    let (result, _trace) = run(&program("rectangle.h"), &m);
    let failure = result.expect_err("refused");
    let text = failure.error.to_string();
    assert!(text.contains("node 1") && text.contains("pv"), "{text}");
}
