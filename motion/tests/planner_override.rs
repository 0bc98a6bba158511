//! Feed override, feed hold and the tolerance op, judged from the commanded trace: limits
//! by finite differences, the path by its distance from the programmed contour.

mod common;

use common::*;
use klar_interp::{Feed, Op, OpKind, Pose};
use klar_motion::{Planner, Sample};
use std::f64::consts::PI;

/// Path speed of a sample over X Y Z.
fn speed(s: &Sample) -> f64 {
    (s.velocity[0].powi(2) + s.velocity[1].powi(2) + s.velocity[2].powi(2)).sqrt()
}

/// A square of four 60 mm lines at 80 mm/s, corners at the origin and (60, 60).
fn square() -> (Pose, Vec<Op>) {
    let c = [
        Pose::xyz(0.0, 0.0, 0.0),
        Pose::xyz(60.0, 0.0, 0.0),
        Pose::xyz(60.0, 60.0, 0.0),
        Pose::xyz(0.0, 60.0, 0.0),
    ];
    let ops = (0..4)
        .map(|k| line(k as u32 + 1, c[k], c[(k + 1) % 4], Feed::Rate(80.0)))
        .collect();
    (c[0], ops)
}

/// Distance from the square's edges.
fn off_square(p: &Pose) -> f64 {
    let (x, y) = (p.0[0].clamp(0.0, 60.0), p.0[1].clamp(0.0, 60.0));
    let inside = x.min(60.0 - x).min(y).min(60.0 - y);
    let outside = (p.0[0] - x).hypot(p.0[1] - y);
    inside.max(outside)
}

/// Runs `ops` on the test machine, calling `control` before every step with the samples so
/// far.
fn run_with(
    start: Pose,
    ops: Vec<Op>,
    control: impl FnMut(&mut Planner, &[Sample]),
) -> Vec<Sample> {
    let cfg = config(limits_xyz(100.0, 1000.0, 20_000.0));
    run_controlled(cfg, start, ops, control).samples
}

#[test]
fn feed_override_scales_the_speed_and_keeps_path_and_limits() {
    let (start, ops) = square();
    let cfg = config(limits_xyz(100.0, 1000.0, 20_000.0));
    // 50 % from 0.3 s, 150 % from 1.2 s: the programmed 80 mm/s becomes 40, then 120
    // (capped by the 100 mm/s axis limit along X or Y).
    let samples = run_with(start, ops.clone(), |p, s| {
        let t = s.last().map_or(0.0, |s| s.t);
        p.set_feed_override(if t < 0.3 {
            1.0
        } else if t < 1.2 {
            0.5
        } else {
            1.5
        });
    });
    assert_within_limits(&cfg, &start, &samples, 1.01);
    for s in &samples {
        assert!(off_square(&s.pose) <= cfg.tolerance, "{:?}", s.pose);
        let v = speed(s);
        // Slowing down from 80 to 40 takes v/A + A/J = 0.09 s; speeding up again too.
        if s.t > 0.45 && s.t < 1.2 {
            assert!(v <= 40.0 * (1.0 + 1e-6), "t {}: {v}", s.t);
        }
        assert!(v <= 100.0 * (1.0 + 1e-6));
    }
    let peak_late = samples
        .iter()
        .filter(|s| s.t > 1.4 && s.loc.line == 3)
        .map(speed)
        .fold(0.0, f64::max);
    assert!(
        peak_late > 95.0,
        "150 % should reach the axis limit: {peak_late}"
    );
    let plain = run_with(start, ops, |_, _| {});
    assert!(samples.len() != plain.len());
    assert_eq!(samples.last().unwrap().pose, start);
}

#[test]
fn override_limits_are_clamped() {
    let mut p = Planner::new(config(limits_xyz(100.0, 1000.0, 20_000.0)), Pose::ZERO).unwrap();
    assert_eq!(p.set_feed_override(2.0), 1.5);
    assert_eq!(p.set_feed_override(-1.0), 0.0);
    assert_eq!(p.set_feed_override(f64::NAN), 0.0);
    assert_eq!(p.set_feed_override(0.7), 0.7);
    assert_eq!(p.feed_override(), 0.7);
}

#[test]
fn feed_hold_stops_on_the_path_and_resume_finishes_it() {
    let (start, ops) = square();
    let cfg = config(limits_xyz(100.0, 1000.0, 20_000.0));
    let mut held_at = None;
    let samples = run_with(start, ops, |p, s| {
        let t = s.last().map_or(0.0, |s| s.t);
        if (0.5..1.5).contains(&t) {
            p.hold();
        } else {
            p.resume();
        }
        if t >= 1.4 && held_at.is_none() {
            held_at = s.last().map(|s| s.pose);
        }
    });
    assert_within_limits(&cfg, &start, &samples, 1.01);
    for s in &samples {
        assert!(off_square(&s.pose) <= cfg.tolerance);
    }
    // Braking from 80 mm/s takes v/A + A/J = 0.13 s: standing still well before 1.4 s,
    // on the first edge (80 mm/s · 0.5 s plus the braking distance is below 60 mm).
    let still: Vec<_> = samples.iter().filter(|s| s.t > 0.8 && s.t < 1.5).collect();
    assert!(still.iter().all(|s| speed(s) == 0.0));
    let p = held_at.unwrap();
    assert!(p.0[0] > 30.0 && p.0[0] < 60.0 && p.0[1] == 0.0, "{p:?}");
    assert!(still.iter().all(|s| s.pose == p));
    // The whole square is still driven after the resume.
    assert_eq!(samples.last().unwrap().pose, start);
    assert!(samples.iter().any(|s| s.loc.line == 4 && s.t > 1.5));
}

/// Distance over X and Y from `q` to the polyline through `pts`.
fn distance_to_polyline(q: &Pose, pts: &[Pose]) -> f64 {
    pts.windows(2)
        .map(|w| {
            let (ax, ay, bx, by) = (w[0].0[0], w[0].0[1], w[1].0[0], w[1].0[1]);
            let (dx, dy) = (bx - ax, by - ay);
            let t =
                (((q.0[0] - ax) * dx + (q.0[1] - ay) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
            (q.0[0] - ax - t * dx).hypot(q.0[1] - ay - t * dy)
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn a_tolerance_op_tightens_the_corners_after_it() {
    // Two 15° corners, the second after a tolerance op of 0.001 mm: the path stays within
    // 0.01 mm of the contour around the first and within 0.001 mm around the second, and
    // cuts the first corner deeper than the second.
    let turn = |p: Pose, deg: f64| {
        let r = deg.to_radians();
        Pose::xyz(p.0[0] + 30.0 * r.cos(), p.0[1] + 30.0 * r.sin(), 0.0)
    };
    let p0 = Pose::ZERO;
    let p1 = turn(p0, 0.0);
    let p2 = turn(p1, 15.0);
    let p3 = turn(p2, 30.0);
    let pts = [p0, p1, p2, p3];
    let ops = vec![
        line(1, p0, p1, Feed::Rate(50.0)),
        line(2, p1, p2, Feed::Rate(50.0)),
        op(3, OpKind::Tolerance { mm: Some(0.001) }),
        line(4, p2, p3, Feed::Rate(50.0)),
    ];
    let cfg = config(limits_xyz(100.0, 1000.0, 1e6));
    let r = run(cfg.clone(), p0, ops);
    assert_within_limits(&cfg, &p0, &r.samples, 1.01);
    let mut worst = [0.0f64; 2];
    for s in &r.samples {
        let d = distance_to_polyline(&s.pose, &pts);
        // Samples nearer the second corner belong to its band.
        let second = linear_distance(&s.pose, &p2) < linear_distance(&s.pose, &p1);
        let (band, k) = if second { (0.001, 1) } else { (0.01, 0) };
        assert!(d <= band, "{:?}: {d} above {band}", s.pose);
        worst[k] = worst[k].max(d);
    }
    assert!(worst[0] > worst[1], "{worst:?}");
    assert!(worst[0] > 0.001, "{worst:?}");
}

#[test]
fn dense_r5_polyline_runs_near_its_feed() {
    // 2000 chords of 0.0157 mm on R5 at 50 mm/s: centripetal 500 mm/s² is within the axes,
    // so the time stays near length / feed (no minimum time per segment: 2000 segments at
    // one per 1 ms period would take 2 s).
    let (r, n, feed) = (5.0, 2000usize, 50.0);
    let p = |k: usize| {
        let phi = 2.0 * PI * k as f64 / n as f64;
        Pose::xyz(r * phi.cos(), r * phi.sin(), 0.0)
    };
    let ops = (0..n)
        .map(|k| line(k as u32 + 1, p(k), p(k + 1), Feed::Rate(feed)))
        .collect();
    let cfg = config(limits_xyz(100.0, 1000.0, 1e5));
    let run = run(cfg.clone(), p(0), ops);
    assert_within_limits(&cfg, &p(0), &run.samples, 1.01);
    let length = n as f64 * 2.0 * r * (PI / n as f64).sin();
    let t = run.samples.last().unwrap().t;
    // Start and end (curvature from and back to zero) are slower than the feed.
    assert!(t < 2.0 && t < 1.5 * length / feed, "{t} s for {length} mm");
    for s in &run.samples {
        let d = (s.pose.0[0].hypot(s.pose.0[1]) - r).abs();
        assert!(d <= cfg.tolerance, "{d}");
    }
}
