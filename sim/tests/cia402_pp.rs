//! A slow auxiliary axis in profile position mode: the drive runs its own trapezoidal
//! profile to each new set-point handed over with the CiA 402 handshake.

use klar_drivers::cia402::CanOpenConfig;
use klar_motion::{AxisBackend, AxisFeedback, AxisState, Setpoint};
use klar_sim::cia402::simulated_backend;

const PERIOD: f64 = 0.001;

fn config() -> CanOpenConfig {
    toml::from_str(
        r#"
        bus = { adapter = "sim" }
        [[drives]]
        node = 3
        counts_per_unit = 1000.0
        mode = "pp"
        profile_velocity = 20.0
        profile_acceleration = 100.0
        "#,
    )
    .expect("config parses")
}

/// Position along a rest-to-rest trapezoid of `distance` with speed `v` and acceleration
/// `a`, `t` seconds after the start.
fn trapezoid(distance: f64, v: f64, a: f64, t: f64) -> f64 {
    let ramp = v / a;
    let total = distance / v + ramp;
    if t <= 0.0 {
        0.0
    } else if t < ramp {
        0.5 * a * t * t
    } else if t < total - ramp {
        0.5 * a * ramp * ramp + v * (t - ramp)
    } else if t < total {
        distance - 0.5 * a * (total - t) * (total - t)
    } else {
        distance
    }
}

#[test]
fn profile_position_follows_the_drives_trapezoid() {
    let (mut backend, _bus, drives) = simulated_backend(&config(), PERIOD, &[]).expect("starts");
    backend.enable().expect("enables");
    let mut fb = vec![AxisFeedback::default(); 1];
    let target = [Setpoint {
        position: 10.0,
        ..Default::default()
    }];
    let mut t = 0.0;
    // 10 mm at 20 mm/s and 100 mm/s²: 0.2 s ramps, 0.7 s in all.
    for k in 1..=900 {
        t += PERIOD;
        backend.cycle(t, &target, &mut fb).expect("cycle");
        assert_eq!(
            fb[0].state,
            AxisState::Enabled,
            "{:?}",
            backend.stop_report()
        );
        let expected = trapezoid(10.0, 20.0, 100.0, f64::from(k - 1) * PERIOD);
        assert!(
            (fb[0].position - expected).abs() < 0.05,
            "at {} ms: {} instead of {expected}",
            k,
            fb[0].position
        );
    }
    assert!((fb[0].position - 10.0).abs() < 1e-3);
    assert!((drives[0].position() - 10.0).abs() < 1e-3);
}

#[test]
fn a_new_set_point_changes_the_move_at_once() {
    let (mut backend, _bus, _drives) = simulated_backend(&config(), PERIOD, &[]).expect("starts");
    backend.enable().expect("enables");
    let mut fb = vec![AxisFeedback::default(); 1];
    let mut t = 0.0;
    let mut run = |backend: &mut klar_drivers::cia402::Cia402Backend, p: f64, n: usize| {
        for _ in 0..n {
            t += PERIOD;
            let sp = [Setpoint {
                position: p,
                ..Default::default()
            }];
            backend.cycle(t, &sp, &mut fb).expect("cycle");
        }
        fb[0].position
    };
    let mid = run(&mut backend, 10.0, 300);
    assert!(mid > 3.0 && mid < 5.0, "{mid}");
    // Back to 2 mm while moving out at full speed: the drive brakes and returns.
    let peak = run(&mut backend, 2.0, 250);
    assert!(peak < mid + 2.5, "braked within 0.2 s: {peak}");
    let end = run(&mut backend, 2.0, 800);
    assert!((end - 2.0).abs() < 1e-3, "{end}");
}
