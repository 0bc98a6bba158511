//! On a curve the acceleration left for changing speed depends on the speed: all of the
//! limit at rest, √(a² − (v²/r)²) on an arc at speed v. These tests drive circles and
//! small corner arcs fast enough for the curvature term to take most of the limit and judge
//! the samples by finite differences and against that closed form.

mod common;

use common::*;
use klar_interp::{Feed, Plane, Pose};

const A: f64 = 1000.0;

/// A full circle of radius `r` from (0, 0) round the centre (r, 0), at `feed` mm/s.
fn circle(r: f64, feed: f64, jerk: f64) -> (klar_motion::PlannerConfig, Pose, Run) {
    let cfg = config(limits_xyz(200.0, A, jerk));
    let from = Pose::xyz(0.0, 0.0, 0.0);
    let ops = vec![arc(
        1,
        from,
        from,
        [r, 0.0],
        Plane::XY,
        360.0,
        Feed::Rate(feed),
    )];
    let out = run(cfg.clone(), from, ops);
    (cfg, from, out)
}

/// Path speeds between consecutive samples.
fn speeds(start: &Pose, r: &Run) -> Vec<f64> {
    let mut prev = *start;
    r.samples
        .iter()
        .map(|s| {
            let v = linear_distance(&prev, &s.pose) / 0.001;
            prev = s.pose;
            v
        })
        .collect()
}

#[test]
fn a_fast_circle_keeps_every_axis_within_its_limits_and_on_the_circle() {
    for jerk in [1e5, 1e9] {
        let (cfg, from, out) = circle(10.0, 150.0, jerk);
        assert_within_limits(&cfg, &from, &out.samples, 1.01);
        for s in &out.samples {
            let d = (s.pose.0[0] - 10.0).hypot(s.pose.0[1]);
            assert!((d - 10.0).abs() < 1e-9, "off the circle by {}", d - 10.0);
        }
        assert_eq!(out.samples.last().map(|s| s.pose), Some(from));
    }
}

#[test]
fn the_circle_runs_close_to_the_speed_where_the_curvature_takes_all_of_the_limit() {
    // v²/r = a at v = √(a·r) = 100 mm/s: no admissible speed is higher; a split of the
    // limit fixed at the top speed (0.8 for the curvature) would stop at √(0.8·a·r).
    for jerk in [1e5, 1e9] {
        let (_, from, out) = circle(10.0, 150.0, jerk);
        let top = speeds(&from, &out).into_iter().fold(0.0, f64::max);
        let bound = (A * 10.0f64).sqrt();
        assert!(top <= bound * 1.001, "j {jerk}: {top} above {bound}");
        assert!(top >= 0.97 * bound, "j {jerk}: only {top} of {bound}");
    }
}

#[test]
fn starting_on_a_circle_uses_the_acceleration_left_at_low_speed() {
    // With the jerk effectively unlimited, the speed after 20 ms from rest is the
    // integral of √(a² − (v²/r)²) ≥ a·√(1 − (v²/(a·r))²): at v ≤ 20 mm/s on r = 10 that
    // is at least 0.999·a, so v(20 ms) ≥ 19.9 mm/s less a period of start-up. A split
    // fixed at the top speed would give 0.6·a, 12 mm/s.
    let (_, from, out) = circle(10.0, 150.0, 1e9);
    let v = speeds(&from, &out);
    assert!(v[19] >= 18.0, "speed after 20 ms: {}", v[19]);
    assert!(v[19] <= 20.0 * 1.01, "speed after 20 ms: {}", v[19]);
}

#[test]
fn small_corner_arcs_keep_every_axis_within_its_limits() {
    // A 20 × 20 square with 1 mm corner arcs at 100 mm/s: v²/r reaches the limit at
    // 31.6 mm/s in each corner.
    for jerk in [1e5, 1e9] {
        let cfg = config(limits_xyz(100.0, A, jerk));
        let p = |x: f64, y: f64| Pose::xyz(x, y, 0.0);
        let f = Feed::Rate(100.0);
        let ops = vec![
            line(1, p(0.0, 0.0), p(9.0, 0.0), f),
            arc(2, p(9.0, 0.0), p(10.0, 1.0), [9.0, 1.0], Plane::XY, 90.0, f),
            line(3, p(10.0, 1.0), p(10.0, 19.0), f),
            arc(
                4,
                p(10.0, 19.0),
                p(9.0, 20.0),
                [9.0, 19.0],
                Plane::XY,
                90.0,
                f,
            ),
            line(5, p(9.0, 20.0), p(-9.0, 20.0), f),
        ];
        let from = p(0.0, 0.0);
        let out = run(cfg.clone(), from, ops);
        assert_within_limits(&cfg, &from, &out.samples, 1.01);
        assert_eq!(out.samples.last().map(|s| s.pose), Some(p(-9.0, 20.0)));
    }
}

/// A line along X (y = 0, x ≤ 9) running into a quarter arc round (9, 1) of radius 1 and on
/// up the line x = 10, at 100 mm/s from the origin; the samples are checked against every
/// limit.
fn line_into_arc(jerk: f64) -> (Pose, Run) {
    let cfg = config(limits_xyz(100.0, A, jerk));
    let p = |x: f64, y: f64| Pose::xyz(x, y, 0.0);
    let f = Feed::Rate(100.0);
    let ops = vec![
        line(1, p(0.0, 0.0), p(9.0, 0.0), f),
        arc(2, p(9.0, 0.0), p(10.0, 1.0), [9.0, 1.0], Plane::XY, 90.0, f),
        line(3, p(10.0, 1.0), p(10.0, 10.0), f),
    ];
    let from = p(0.0, 0.0);
    let out = run(cfg.clone(), from, ops);
    assert_within_limits(&cfg, &from, &out.samples, 1.01);
    (from, out)
}

/// Largest distance of the samples of [`line_into_arc`] from its contour.
fn largest_deviation(jerk: f64) -> f64 {
    let (_, out) = line_into_arc(jerk);
    out.samples
        .iter()
        .map(|s| {
            let (x, y) = (s.pose.0[0], s.pose.0[1]);
            if x <= 9.0 {
                y.abs()
            } else if y <= 1.0 {
                ((x - 9.0).hypot(y - 1.0) - 1.0).abs()
            } else {
                (x - 10.0).abs()
            }
        })
        .fold(0.0, f64::max)
}

#[test]
fn a_line_running_into_an_arc_is_blended_only_where_the_jerk_needs_it() {
    // At 31.6 mm/s the curvature jump 1/mm steps the acceleration by 1000 mm/s²: within a
    // period that is 1e6 mm/s³, far below a jerk limit of 1e9 but ten times one of 1e5.
    let exact = largest_deviation(1e9);
    assert!(exact < 1e-9, "unblended joint left the contour by {exact}");
    let blended = largest_deviation(1e5);
    assert!(
        blended > 1e-6 && blended <= 0.01,
        "blend deviation {blended}"
    );
}

#[test]
fn a_blend_is_planned_in_parts_so_the_path_slows_down_inside_it() {
    // The blend from the line into the arc has zero curvature where it starts and the
    // arc's where it ends. Planned in parts with limits of their own, the path enters it
    // faster than it runs at its tightest part; with one limit for the whole blend it
    // would have to be at that speed before the blend begins.
    let (from, out) = line_into_arc(1e5);
    let v = speeds(&from, &out);
    // The first sample off the line y = 0 is just inside the blend.
    let Some(k) = out.samples.iter().position(|s| s.pose.0[1].abs() > 1e-7) else {
        panic!("the path never leaves the line")
    };
    let slowest = v
        .iter()
        .skip(k)
        .take(200)
        .fold(f64::INFINITY, |m, x| m.min(*x));
    assert!(
        v[k] > 1.05 * slowest,
        "entering the blend at {} mm/s, slowest {slowest} mm/s",
        v[k]
    );
}

#[test]
fn a_long_line_after_a_blend_keeps_its_own_jerk_limit() {
    // The blend out of the arc allows less jerk than the line x = 10 after it. The two
    // share the lower limit only near their joint: speeding up along the line, the Y axis
    // reaches its own jerk limit once the path is clear of the blend (y ≥ 1.78).
    let jerk = 1e5;
    let (_, out) = line_into_arc(jerk);
    let ys: Vec<f64> = out
        .samples
        .iter()
        .filter(|s| s.pose.0[1] > 2.0 && (s.pose.0[0] - 10.0).abs() < 1e-12)
        .map(|s| s.pose.0[1])
        .collect();
    let highest = ys
        .windows(4)
        .map(|w| (w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0]).abs() / 1e-9)
        .fold(0.0, f64::max);
    assert!(
        highest > 0.95 * jerk && highest <= 1.01 * jerk,
        "largest Y jerk on the line after the blend: {highest} mm/s³"
    );
}
