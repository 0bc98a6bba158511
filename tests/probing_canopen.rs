//! `klar run` of a probing program on simulated CiA 402 drives (`machines/canopen-probing.toml`:
//! the part of `machines/probing-mill.toml`, a probe with a trigger delay of 2 ms and 1 mm
//! overtravel): the cycle measures what it measures on simulated axes, and the drives carry
//! the probe past the touch point by the stop distance worked out here from the axis limits.

mod common;

use klar::config::MachineConfig;
use std::path::Path;

fn load(name: &str) -> MachineConfig {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("machines")
        .join(name);
    MachineConfig::load(&p).expect("machine loads")
}

#[test]
fn cycle_412_on_canopen_drives_measures_as_on_simulated_axes_and_overruns_the_touch() {
    let can = load("canopen-probing.toml");
    let probe = can.probe.clone().expect("[probe]");
    let delay = probe.trigger_delay.expect("trigger_delay");
    let v = probe.feed / 60.0;
    // the same probe on the simulated axes of probing-mill.toml
    let mut sim = load("probing-mill.toml");
    sim.probe = Some(probe);
    let path = common::program("probing_412.h");
    let (result, trace) = common::run(&path, &can);
    let report = result.expect("runs on the CANopen drives");
    let (sim_result, _) = common::run(&path, &sim);
    let sim_report = sim_result.expect("runs on simulated axes");
    assert!(!report.probe_results.is_empty());
    assert_eq!(report.probe_results.len(), sim_report.probe_results.len());
    for (a, b) in report.probe_results.iter().zip(&sim_report.probe_results) {
        assert_eq!(a.params.len(), b.params.len());
        for (p, q) in a.params.iter().zip(&b.params) {
            assert_eq!(p.0, q.0);
            assert!(
                (p.1 - q.1).abs() < 1e-9,
                "Q{}: {} against {}",
                p.0,
                p.1,
                q.1
            );
        }
    }

    // The probe-axis touch: the top of the part lies 0.25 mm below preset 1's Z−60, so the
    // ball centre triggers at Z −60 − 0.25 + 2 (machine). At 5 mm/s the stop never reaches
    // Z's acceleration limit (a²/j = 56.25 mm/s): jerk phases of √(v/j) each, covering
    // v·√(v/j); the trigger delay adds delay·v.
    let trigger = -60.0 - 0.25 + 2.0;
    let overshoot = delay * v + v * (v / 40000.0f64).sqrt();
    let [x, y, z, z_act] = ["X", "Y", "Z", "Z_act"].map(|c| trace.column(c).expect("column"));
    // the probe-axis touch is at Q382/Q383 = X+30 Y+25 of preset 1 (machine X130 Y75)
    let over_it = |k: &usize| (x[*k] - 130.0).abs() < 1e-6 && (y[*k] - 75.0).abs() < 1e-6;
    let lowest = |col: &[f64]| {
        (0..col.len())
            .filter(over_it)
            .map(|k| col[k])
            .fold(f64::INFINITY, f64::min)
    };
    let stop = lowest(&z);
    eprintln!(
        "Z stopped {} past the touch point (closed form {overshoot})",
        trigger - stop
    );
    assert!(
        (trigger - stop - overshoot).abs() < 1e-6,
        "stopped {} past the touch, closed form {overshoot}",
        trigger - stop
    );
    // the drive reports having gone there too (to the count and its lag: its encoder has
    // 10 000 counts per mm and the run's largest following error of Z is its bound)
    let act = lowest(&z_act);
    let lag = report
        .max_following_error
        .iter()
        .find(|(a, _)| a.index() == 2)
        .map_or(0.0, |&(_, e)| e);
    assert!(
        (act - stop).abs() <= lag + 1e-4,
        "the drive stood at {act}, commanded {stop}, lag up to {lag}"
    );
}
