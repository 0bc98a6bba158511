//! The simulated spindle's ramp against its closed form.

use klar_motion::{AxisFault, SpindleBackend};
use klar_sim::modbus::{PositioningLimits, SimSpindle, SpindleModel, SpindleParams, profile_step};

#[test]
fn ramp_reaches_speed_at_the_closed_form_time() {
    let params = SpindleParams {
        max_rpm: 12_000.0,
        acceleration: 8_000.0,
        at_speed_fraction: 0.02,
        at_speed_min_rpm: 10.0,
        ..SpindleParams::default()
    };
    let mut s = SimSpindle::new(params);
    s.command(6_000.0).unwrap();
    let dt = 0.001;
    let mut first_at_speed = None;
    for k in 0..=1_000 {
        let t = k as f64 * dt;
        let fb = s.cycle(t).unwrap();
        // rpm(t) = min(a t, target)
        let expected = (8_000.0 * t).min(6_000.0);
        assert!((fb.rpm - expected).abs() < 1e-6, "t={t} rpm={}", fb.rpm);
        if fb.at_speed && first_at_speed.is_none() {
            first_at_speed = Some(t);
        }
    }
    // The window is 2 % of 6000 = 120 rpm: at speed from (6000 - 120) / 8000 = 0.735 s.
    let t = first_at_speed.expect("reached speed");
    assert!((t - 0.735).abs() <= dt + 1e-9, "{t}");

    // Reversal passes through zero at the same rate: 6000 → -6000 takes 1.5 s.
    s.command(-6_000.0).unwrap();
    let fb = s.cycle(1.0 + 0.75).unwrap();
    assert!(fb.rpm.abs() < 1e-6);
    let fb = s.cycle(1.0 + 1.5).unwrap();
    assert!((fb.rpm + 6_000.0).abs() < 1e-6 && fb.at_speed);
}

#[test]
fn bad_commands_are_refused_and_faults_stop_the_spindle() {
    let mut s = SimSpindle::new(SpindleParams::default());
    assert!(s.command(f64::NAN).is_err());
    assert!(s.command(1e9).is_err());
    s.command(1_000.0).unwrap();
    s.cycle(0.0).unwrap();
    s.cycle(1.0).unwrap();
    s.model_mut().inject_fault(4);
    let fb = s.cycle(2.0).unwrap();
    assert!(matches!(fb.fault, Some(AxisFault::Drive { code: 4, .. })));
    assert_eq!(fb.rpm, 0.0);
    assert!(!fb.at_speed);
    let mut m = SpindleModel::new(SpindleParams::default());
    m.set_command(500.0);
    m.inject_fault(1);
    m.reset_fault();
    assert_eq!(
        m.command(),
        0.0,
        "a reset fault does not restart the spindle"
    );
}

#[test]
fn positioning_profile_matches_the_trapezoid() {
    // 100 units at v = 50, a = 100: accelerate 0.5 s (12.5 units), cruise 1.5 s
    // (75 units), brake 0.5 s: 2.5 s in total.
    let limits = PositioningLimits {
        velocity: 50.0,
        acceleration: 100.0,
    };
    let dt = 0.0005;
    let (mut p, mut v) = (0.0, 0.0);
    let mut t = 0.0;
    let mut peak: f64 = 0.0;
    while p != 100.0 {
        let (np, nv, _) = profile_step(p, v, 100.0, limits, dt);
        assert!(
            nv <= 50.0 + 1e-9 && (nv - v).abs() <= 100.0 * dt + 1e-9,
            "t={t} p={p} v={v} -> {np} {nv}"
        );
        p = np;
        v = nv;
        peak = peak.max(v);
        t += dt;
        assert!(t < 5.0, "did not arrive");
    }
    assert!((peak - 50.0).abs() < 1e-9);
    assert!((t - 2.5).abs() < 0.02, "{t}");
}

#[test]
fn encoder_counts_the_integral_of_the_speed_and_the_cut_slows_it() {
    let params = SpindleParams {
        max_rpm: 6_000.0,
        acceleration: 6_000.0,
        encoder_counts: 4096,
        load_droop: 0.1,
        load_time_constant: 0.05,
        ..SpindleParams::default()
    };
    let mut s = SimSpindle::new(params);
    s.command(600.0).unwrap();
    let dt = 0.001;
    // Ramp 0 → 600 rpm at 6000 rpm/s takes 0.1 s: the angle is ½·a·t² (a in °/s²) then
    // grows at 3600 °/s.
    let count = 360.0 / 4096.0;
    for k in 0..=500 {
        let t = k as f64 * dt;
        let fb = s.cycle(t).unwrap();
        let angle = if t <= 0.1 {
            0.5 * 36_000.0 * t * t
        } else {
            180.0 + 3_600.0 * (t - 0.1)
        };
        let measured = fb.position.expect("the simulated spindle has an encoder");
        // Whole counts toward −∞: at most one count below the true angle, never above.
        assert!(
            measured <= angle + 1e-6 && measured > angle - count - 1e-6,
            "t={t}: {measured} for {angle}"
        );
        assert!((measured / count - (measured / count).round()).abs() < 1e-9);
    }
    // Under a 2 mm² chip the speed sinks toward 600·(1 − 0.2) = 480 rpm with τ = 50 ms.
    s.set_load(2.0);
    let t0 = 0.5;
    for k in 1..=300 {
        let t = t0 + k as f64 * dt;
        let fb = s.cycle(t).unwrap();
        // The discrete first-order step is exact at the sample times.
        let dip = 0.2 * (1.0 - (-(t - t0) / 0.05).exp());
        assert!(
            (fb.rpm - 600.0 * (1.0 - dip)).abs() < 1e-6,
            "t={t}: {} rpm",
            fb.rpm
        );
    }
    s.set_load(0.0);
    let fb = s.cycle(1.3).unwrap();
    assert!((fb.rpm - 600.0).abs() < 1.0, "recovers: {}", fb.rpm);
}
