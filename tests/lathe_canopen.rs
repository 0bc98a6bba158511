//! The built-in lathe with X, Z, C and the main spindle on simulated CiA 402 drives
//! (machines/lathe-canopen.toml): a G33 thread geared to the angle the spindle drive
//! reports as its actual position (0x6064), read back from the trace. The Python CANopen
//! peer has no velocity modes, so klar's own simulated drive is the peer here.

mod common;

use common::threads::{angle_apart, lead_error, passes, start_angle};
use common::{program, run};
use klar::config::MachineConfig;
use klar::testrun::test_run;

fn machine() -> MachineConfig {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/lathe-canopen.toml");
    MachineConfig::load(&file).expect("machine loads")
}

#[test]
fn check_accepts_threading_on_the_canopen_spindle() {
    let report = test_run(&program("lathe/thread_g33.nc"), &machine());
    assert!(report.errors.is_empty(), "{:?}", report.errors);
}

#[test]
fn g33_on_canopen_drives_follows_the_measured_spindle_angle() {
    let (result, trace) = run(&program("lathe/thread_g33.nc"), &machine());
    result.expect("the thread program runs");
    // Run-in B4 from Z6 and run-out P3 before Z-30: the thread proper is Z2 … Z-27.
    let found = passes(&trace, -27.0, 2.0, 10.5, 50);
    assert_eq!(found.len(), 4, "four passes");
    let pitch = 1.5;
    let t = &trace.t;
    let mut starts = Vec::new();
    let mut worst_cmd: f64 = 0.0;
    let mut worst_act: f64 = 0.0;
    for (k, p) in found.iter().enumerate() {
        let x0 = p.x[0];
        assert!(
            (x0 - (9.8 - 0.2 * k as f64)).abs() < 1e-9,
            "pass {k} at X {x0}"
        );
        worst_cmd = worst_cmd.max(lead_error(&p.z, &p.angle, pitch, 1.0));
        worst_act = worst_act.max(lead_error(&p.z_act, &p.angle, pitch, 1.0));
        starts.push(start_angle(p, 2.0, pitch, 1.0));
        // The angle is the drive's: it turns at the commanded 800 rpm (4800 °/s) over the
        // pass, within the CSV at-speed window of 2 %.
        let (first, last) = (p.rows[0], p.rows[p.rows.len() - 1]);
        let rate = (p.angle[p.angle.len() - 1] - p.angle[0]) / (t[last] - t[first]);
        assert!(
            (rate - 4800.0).abs() < 0.02 * 4800.0,
            "pass {k}: {rate} °/s"
        );
    }
    assert!(worst_cmd < 0.005, "commanded lead error {worst_cmd} mm");
    assert!(worst_act < 0.005, "measured lead error {worst_act} mm");
    for a in &starts {
        assert!(angle_apart(*a, 30.0) < 1.0, "start angle {a}");
    }
    let spread = starts
        .iter()
        .flat_map(|a| starts.iter().map(move |b| angle_apart(*a, *b)))
        .fold(0.0, f64::max);
    assert!(spread < 1.0, "phase spread {spread}°");
    println!(
        "G33 M20x1.5 on CiA 402 drives, 4 passes at 800 rpm: lead error commanded {:.3} µm, \
         measured {:.3} µm; phase spread {spread:.4}°",
        worst_cmd * 1e3,
        worst_act * 1e3
    );
}
