//! Dense CAM code as CAM systems write it: chords with coordinates rounded to 1 µm, so the
//! directions (and the curvature the blends estimate from them) carry rounding noise.

mod common;

use common::*;
use klar_interp::{Feed, Pose};
use std::f64::consts::PI;

/// The `k`-th of `n` chord end points on a circle of radius `r` through the origin (centre
/// at X−r), rounded to 1 µm as a post-processor prints them; the last one is the origin.
fn rounded_point(r: f64, n: usize, k: usize) -> Pose {
    if k.is_multiple_of(n) {
        return Pose::xyz(0.0, 0.0, 0.0);
    }
    let phi = 2.0 * PI * k as f64 / n as f64;
    let round = |x: f64| (x * 1e6).round() / 1e6;
    Pose::xyz(round(-r + r * phi.cos()), round(r * phi.sin()), 0.0)
}

#[test]
fn rounded_r5_polyline_stops_exactly_within_every_limit() {
    // 2000 chords on R5 at F3000, jerk 1e5 and (nearly) unlimited. The braking curve to
    // the program end runs through chords shorter than one period's travel: the path must
    // reach the end at rest without a jump in speed (the finite differences of the trace
    // would show it as an acceleration far above the limit).
    let (r, n) = (5.0, 2000usize);
    for jerk in [1e5, 1e9] {
        let ops = (0..n)
            .map(|k| {
                line(
                    k as u32 + 1,
                    rounded_point(r, n, k),
                    rounded_point(r, n, k + 1),
                    Feed::Rate(50.0),
                )
            })
            .collect();
        let cfg = config(limits_xyz(100.0, 1000.0, jerk));
        let start = rounded_point(r, n, 0);
        let run = run(cfg.clone(), start, ops);
        assert_within_limits(&cfg, &start, &run.samples, 1.01);
        let last = run.samples.last().expect("samples");
        assert!(last.pose.0[0].abs() <= 1e-9 && last.pose.0[1].abs() <= 1e-9);
        for s in &run.samples {
            let d = (s.pose.0[0] + r).hypot(s.pose.0[1]) - r;
            // The chords themselves lie up to r·(1 − cos(π/n)) ≈ 0.012 µm inside the
            // circle; rounding adds up to 0.7 µm; the blends stay within 0.01 mm.
            assert!(d.abs() <= cfg.tolerance + 1e-5, "{d} mm off the circle");
        }
    }
}
