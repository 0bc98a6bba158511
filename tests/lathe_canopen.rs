//! The built-in lathe with X, Z, C and the main spindle on simulated CiA 402 drives
//! (machines/lathe-canopen.toml): a G33 thread geared to the angle the spindle drive
//! reports as its actual position (0x6064), read back from the trace, also while the
//! simulated drive slows under the cut. The Python CANopen peer has no velocity modes, so
//! klar's own simulated drive is the peer here.

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
    let mut slowest = f64::INFINITY;
    for (k, p) in found.iter().enumerate() {
        let x0 = p.x[0];
        assert!(
            (x0 - (9.8 - 0.2 * k as f64)).abs() < 1e-9,
            "pass {k} at X {x0}"
        );
        worst_cmd = worst_cmd.max(lead_error(&p.z, &p.angle, pitch, 1.0));
        worst_act = worst_act.max(lead_error(&p.z_act, &p.angle, pitch, 1.0));
        starts.push(start_angle(p, 2.0, pitch, 1.0));
        // The angle is the drive's, and the drive slows under the cut: from the second pass
        // on the chip is pitch × infeed = 1.5 × 0.2 = 0.3 mm², so the speed settles (the
        // pass lasts some 30 time constants of 50 ms) at (1 − 0.1 × 0.3) of 800 rpm =
        // 4656 °/s; the first pass counts as no load and turns at 4800 °/s. Measured over the
        // last 100 ms of the pass.
        let expected = if k == 0 {
            4800.0
        } else {
            4800.0 * (1.0 - 0.1 * 0.3)
        };
        let n = p.rows.len() - 1;
        let (a, b) = (p.rows[n - 50], p.rows[n]);
        let rate = (p.angle[n] - p.angle[n - 50]) / (t[b] - t[a]);
        assert!(
            (rate - expected).abs() < 0.002 * 4800.0,
            "pass {k}: {rate} °/s, expected {expected}"
        );
        slowest = slowest.min(rate);
    }
    // Geared to the commanded speed instead, the slide would run ahead of the groove by
    // pitch × the revolutions lost: 3 % of some 19 turns, close to a millimetre.
    assert!(
        slowest < 0.975 * 4800.0,
        "the drive slowed to {slowest} °/s"
    );
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
        "G33 M20x1.5 on CiA 402 drives, 4 passes at 800 rpm slowing to {:.1} rpm under cut: \
         lead error commanded {:.3} µm, measured {:.3} µm; phase spread {spread:.4}°",
        slowest / 6.0,
        worst_cmd * 1e3,
        worst_act * 1e3
    );
}
