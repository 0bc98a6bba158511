//! The S-curve against closed-form durations and peak values, and its own limits checked by
//! finite differences.

use klar_motion::{PathLimits, SCurve};

fn limits(v: f64, a: f64, j: f64) -> PathLimits {
    PathLimits {
        velocity: v,
        acceleration: a,
        jerk: j,
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn long_move_cruises_and_takes_the_closed_form_time() {
    // V·J ≥ A² and the distance is long: T = D/V + V/A + A/J.
    let (d, v, a, j) = (500.0, 100.0, 1000.0, 20_000.0);
    let p = SCurve::new(d, limits(v, a, j));
    assert!(close(p.duration(), d / v + v / a + a / j, 1e-12));
    assert!(close(p.peak_velocity(), v, 1e-12));
    assert!(close(p.peak_acceleration(), a, 1e-12));
}

#[test]
fn move_without_cruise_reaching_full_acceleration() {
    // Pick a peak speed w with w·J ≥ A², distance D = w²/A + w·A/J: the profile must reach
    // exactly w and last 2·(w/A + A/J).
    let (a, j) = (1000.0, 20_000.0);
    let w = 80.0;
    let d = w * w / a + w * a / j;
    let p = SCurve::new(d, limits(200.0, a, j));
    assert!(close(p.peak_velocity(), w, 1e-9));
    assert!(close(p.duration(), 2.0 * (w / a + a / j), 1e-12));
}

#[test]
fn very_short_move_has_triangular_acceleration() {
    // Below 2·A³/J² the acceleration never saturates: four jerk phases of τ = (D/(2J))^(1/3).
    let (a, j) = (1000.0, 20_000.0);
    let d = 0.01;
    assert!(d < 2.0 * a * a * a / (j * j));
    let p = SCurve::new(d, limits(200.0, a, j));
    let tau = (d / (2.0 * j)).cbrt();
    assert!(close(p.duration(), 4.0 * tau, 1e-12));
    assert!(close(p.peak_acceleration(), j * tau, 1e-9));
    assert!(close(p.peak_velocity(), j * tau * tau, 1e-9));
}

#[test]
fn low_jerk_long_move_never_reaches_full_acceleration() {
    // V·J < A²: ramps are pure jerk, each 2·√(V/J) long; T = D/V + 2·√(V/J).
    let (d, v, a, j) = (100.0, 50.0, 1000.0, 1000.0);
    let p = SCurve::new(d, limits(v, a, j));
    assert!(close(p.duration(), d / v + 2.0 * (v / j).sqrt(), 1e-12));
    assert!(close(p.peak_acceleration(), (v * j).sqrt(), 1e-9));
}

#[test]
fn profile_ends_exactly_and_stays_within_its_limits() {
    for d in [0.001, 0.3, 7.0, 250.0] {
        let (v, a, j) = (60.0, 800.0, 15_000.0);
        let p = SCurve::new(d, limits(v, a, j));
        let end = p.state(p.duration());
        assert_eq!(end.s, d);
        assert_eq!((end.v, end.a), (0.0, 0.0));
        let start = p.state(0.0);
        assert_eq!((start.s, start.v, start.a), (0.0, 0.0, 0.0));
        // Fine finite differences of s(t) against the limits; v, a from the state too.
        let dt = p.duration() / 2_000.0;
        let s: Vec<f64> = (0..=2_000).map(|k| p.state(k as f64 * dt).s).collect();
        let mut prev_s = 0.0;
        for (k, w) in s.windows(4).enumerate() {
            assert!(w[0] >= prev_s - 1e-12, "s decreases at {k}");
            prev_s = w[0];
            let vel = (w[1] - w[0]) / dt;
            let acc = (w[2] - 2.0 * w[1] + w[0]) / (dt * dt);
            let jerk = (w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0]) / dt.powi(3);
            assert!(vel <= v * 1.01, "d {d}: velocity {vel}");
            assert!(acc.abs() <= a * 1.01, "d {d}: acceleration {acc}");
            assert!(jerk.abs() <= j * 1.01, "d {d}: jerk {jerk}");
            let st = p.state(k as f64 * dt);
            assert!(st.v <= v * (1.0 + 1e-12) && st.a.abs() <= a * (1.0 + 1e-12));
        }
    }
}
