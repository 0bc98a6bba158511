//! Dense CAM code as CAM systems write it: chords with rounded coordinates, so the
//! directions (and the curvature the blends estimate from them) carry rounding noise.

mod common;

use common::*;
use klar_interp::{Feed, Pose};
use std::f64::consts::PI;

/// The `k`-th of `n` chord end points on a circle of radius `r` through the origin (centre
/// at X−r), rounded to `step` mm as a post-processor prints them; the last one is the
/// origin.
fn rounded_point(r: f64, n: usize, k: usize, step: f64) -> Pose {
    if k.is_multiple_of(n) {
        return Pose::xyz(0.0, 0.0, 0.0);
    }
    let phi = 2.0 * PI * k as f64 / n as f64;
    let round = |x: f64| (x / step).round() * step;
    Pose::xyz(round(-r + r * phi.cos()), round(r * phi.sin()), 0.0)
}

/// The ops of `chords` chords of the circle of `rounded_point(r, n, ·, step)` at `feed`.
fn circle_ops(r: f64, n: usize, chords: usize, step: f64, feed: f64) -> Vec<klar_interp::Op> {
    (0..chords)
        .map(|k| {
            line(
                k as u32 + 1,
                rounded_point(r, n, k, step),
                rounded_point(r, n, k + 1, step),
                Feed::Rate(feed),
            )
        })
        .collect()
}

#[test]
fn rounded_r5_polyline_stops_exactly_within_every_limit() {
    // 2000 chords on R5 at F3000, jerk 1e5 and (nearly) unlimited. The braking curve to
    // the program end runs through chords shorter than one period's travel: the path must
    // reach the end at rest without a jump in speed (the finite differences of the trace
    // would show it as an acceleration far above the limit).
    let (r, n) = (5.0, 2000usize);
    for jerk in [1e5, 1e9] {
        let ops = circle_ops(r, n, n, 1e-3, 50.0);
        let cfg = config(limits_xyz(100.0, 1000.0, jerk));
        let start = rounded_point(r, n, 0, 1e-3);
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

#[test]
fn rounded_chords_of_a_hundredth_run_at_the_programmed_feed() {
    // Half of an R25 circle in 0.01 mm chords (7854 of them), rounded to 1 µm and to
    // 0.1 µm, at F3000 with jerk 1e5. Each chord's direction is off by up to a tenth of a
    // radian, yet the path must run at the feed: the time is the closed form of a straight
    // move of the same length (cruise at the feed, one jerk-limited ramp up and one down,
    // each costing half of its duration v/a + a/j) within 3 %, where the curvature costs
    // nothing at this speed (v²/r = 100 mm/s², v³/r² = 200 mm/s³).
    let (r, n) = (25.0, 15_708usize);
    let (v, a, j) = (50.0, 1000.0, 1e5);
    let chords = n / 2;
    let length = chords as f64 * 2.0 * PI * r / n as f64;
    let closed = length / v + v / a + a / j;
    for step in [1e-3, 1e-4] {
        let cfg = config(limits_xyz(100.0, a, j));
        let start = rounded_point(r, n, 0, step);
        let run = run(cfg.clone(), start, circle_ops(r, n, chords, step, v));
        let time = run.samples.len() as f64 * cfg.period;
        assert!(
            time <= 1.03 * closed && time >= 0.99 * closed,
            "rounded to {step} mm: {time} s against {closed} s"
        );
        assert_within_limits(&cfg, &start, &run.samples, 1.01);
        for s in &run.samples {
            let d = (s.pose.0[0] + r).hypot(s.pose.0[1]) - r;
            assert!(d.abs() <= cfg.tolerance, "{d} mm off the circle");
        }
        let end = rounded_point(r, n, chords, step);
        let last = run.samples.last().expect("samples");
        assert!(
            linear_distance(&last.pose, &end) <= 1e-9,
            "ends at {:?}",
            last.pose
        );
    }
}

/// The servo period of [`config`] (s).
const PERIOD: f64 = 0.001;

/// Distance in XY from `p` to the nearest of the chords through `points`.
fn chords_distance(points: &[Pose], p: &Pose) -> f64 {
    points
        .windows(2)
        .map(|w| segment_distance(p, &w[0], &w[1]))
        .fold(f64::INFINITY, f64::min)
}

/// The chord end points of `turns` turns of the circle of `rounded_point(r, n, ·, 1 µm)`,
/// and the run of the planner along them at `v` with acceleration `a` and jerk `j` (1 ms
/// period), which it checks to keep every axis within its limits and every sample within
/// the band round the chords.
fn chord_turns(r: f64, n: usize, turns: usize, (v, a, j): (f64, f64, f64)) -> (Vec<Pose>, Run) {
    let chords = turns * n;
    let points: Vec<Pose> = (0..=chords).map(|k| rounded_point(r, n, k, 1e-3)).collect();
    let cfg = config(limits_xyz(100.0, a, j));
    assert_eq!(cfg.period, PERIOD);
    let run = run(cfg.clone(), points[0], circle_ops(r, n, chords, 1e-3, v));
    assert_within_limits(&cfg, &points[0], &run.samples, 1.01);
    for s in &run.samples {
        let d = chords_distance(&points, &s.pose);
        assert!(d <= cfg.tolerance, "{d} mm off the chords at {:?}", s.pose);
    }
    let last = run.samples.last().expect("samples");
    assert!(linear_distance(&last.pose, &points[chords]) <= 1e-9);
    (points, run)
}

#[test]
fn rounded_chords_of_three_tenths_round_a_small_circle_run_at_the_programmed_feed() {
    // Two turns of an R4 circle in chords of about 0.3 mm (84 a turn), rounded to 1 µm,
    // at F3000 with jerk 1e5: adaptive clearing as CAM systems print it. Each chord turns
    // by 0.075 rad, so the polyline lies up to L²/8r = 2.8 µm inside the circle, well
    // within the 0.01 mm band, and the circle itself allows the feed (v²/r = 625 mm/s²,
    // v³/r² = 7.8e3 mm/s³ per axis at most). Taken corner by corner, each 0.3 mm chord
    // would be a blend from zero curvature to twice the circle's and back, whose rate of
    // change held the path to about half the feed. The path must follow the circle at the
    // feed instead: the time is the closed form of a straight move of the same length
    // within 3 %, every sample within the band round the programmed chords.
    let (r, n) = (4.0, 84usize);
    let (v, a, j) = (50.0, 1000.0, 1e5);
    let (points, run) = chord_turns(r, n, 2, (v, a, j));
    let length: f64 = points
        .windows(2)
        .map(|w| linear_distance(&w[0], &w[1]))
        .sum();
    let closed = length / v + v / a + a / j;
    let time = run.samples.len() as f64 * PERIOD;
    assert!(
        time <= 1.03 * closed && time >= 0.99 * closed,
        "{time} s against {closed} s"
    );
}

#[test]
fn chords_turning_a_third_of_a_radian_round_a_tiny_circle_run_at_the_feed() {
    // Three turns of an R0.3 circle in chords of 0.1 mm (19 a turn, each turning by
    // 0.33 rad), rounded to 1 µm, at F900: the tight arcs of 2D pocket finishing as CAM
    // systems print them. The circle allows the feed (v²/r = 750 mm/s², v³/r² = 3.75e4
    // mm/s³), and the polyline lies within L²/8r = 4.2 µm of it. Taken corner by corner
    // the path would crawl at about half the feed; on a curve fitted to the chords it
    // keeps to the feed less the headroom the limits of a curve keep (the fitted curve's
    // curvature bound carries the rounding): every sample of the middle turn moves at
    // 90–100 % of the feed, and every sample lies within the band round the chords.
    let (r, n) = (0.3, 19usize);
    let v = 15.0;
    let (points, run) = chord_turns(r, n, 3, (v, 1000.0, 1e5));
    let turn: f64 = points[..=n]
        .windows(2)
        .map(|w| linear_distance(&w[0], &w[1]))
        .sum();
    let mut travelled = 0.0;
    let mut previous = points[0];
    let mut middle = 0;
    for s in &run.samples {
        let step = linear_distance(&previous, &s.pose);
        travelled += step;
        previous = s.pose;
        if travelled > turn && travelled < 2.0 * turn {
            let speed = step / PERIOD;
            assert!(
                speed >= 0.9 * v && speed <= v * (1.0 + 1e-9),
                "{speed} mm/s at {travelled} mm"
            );
            middle += 1;
        }
    }
    // A turn of 1.9 mm at 15 mm/s: about 125 periods.
    assert!(middle > 100, "{middle} samples in the middle turn");
}
