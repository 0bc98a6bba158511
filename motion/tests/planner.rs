//! The planner and sampler, judged from their sampled output: limits by finite differences,
//! exact end points, closed-form times, event order and errors.

mod common;

use common::*;
use klar_interp::op::SplineAxis;
use klar_interp::{AxisLetter, Feed, OpKind, Plane, Pose};
use klar_motion::{AxisLimits, MotionError, Planner, PlannerConfig, Step};

const PERIOD: f64 = 0.001;

/// Time of the first sample standing exactly on `end`.
fn arrival_time(r: &Run, end: &Pose) -> f64 {
    r.samples
        .iter()
        .find(|s| s.pose == *end)
        .map_or(f64::INFINITY, |s| s.t)
}

#[test]
fn long_line_takes_the_closed_form_time_and_ends_exactly() {
    // Direction (0.6, 0.8, 0): path limits are the axis limits over the largest component.
    let (vmax, amax, jmax) = (200.0, 1000.0, 20_000.0);
    let feed = 100.0;
    let d = 500.0123;
    let from = Pose::xyz(1.0, 2.0, 3.0);
    let to = Pose::xyz(1.0 + 0.6 * d, 2.0 + 0.8 * d, 3.0);
    let cfg = config(limits_xyz(vmax, amax, jmax));
    let r = run(cfg.clone(), from, vec![line(1, from, to, Feed::Rate(feed))]);

    let v = feed.min(vmax / 0.8);
    let a = (amax / 0.6).min(amax / 0.8);
    let j = (jmax / 0.6).min(jmax / 0.8);
    assert!(v * j >= a * a, "test case must reach full acceleration");
    let t = d / v + v / a + a / j;
    // The look-ahead rides the braking curve sample by sample: it arrives within one period
    // of the time-optimal closed form, and stops sampling there.
    let arrival = arrival_time(&r, &to);
    assert!((arrival - t).abs() <= PERIOD, "{arrival} vs {t}");
    assert_eq!(r.samples.last().unwrap().t, arrival);
    for (k, s) in r.samples.iter().enumerate() {
        assert_eq!(s.t, (k + 1) as f64 * PERIOD);
    }
    let last = r.samples.last().unwrap();
    for i in 0..9 {
        assert!((last.pose.0[i] - to.0[i]).abs() <= 1e-9);
    }
    let before = &r.samples[r.samples.len() - 2];
    assert!(linear_distance(&before.pose, &to) > 0.0);
    assert_within_limits(&cfg, &from, &r.samples, 1.01);
    // Cruise at the feed is reached, never exceeded.
    let peak = r
        .samples
        .iter()
        .map(|s| (s.velocity[0].powi(2) + s.velocity[1].powi(2)).sqrt())
        .fold(0.0, f64::max);
    assert!((peak - feed).abs() < 1e-9, "peak {peak}");
}

#[test]
fn rapid_moves_as_fast_as_the_slowest_axis_allows() {
    let mut limits = limits_xyz(500.0, 2000.0, 50_000.0);
    limits[1] = Some(AxisLimits {
        max_velocity: 100.0,
        max_acceleration: 2000.0,
        max_jerk: 50_000.0,
    });
    let cfg = config(limits);
    // Equal X and Y travel: Y (100 mm/s) limits the path to 100·√2.
    let from = Pose::ZERO;
    let to = Pose::xyz(200.0, 200.0, 0.0);
    let r = run(cfg.clone(), from, vec![line(1, from, to, Feed::Rapid)]);
    let peak_y = r.samples.iter().map(|s| s.velocity[1]).fold(0.0, f64::max);
    assert!((peak_y - 100.0).abs() < 1e-9, "peak Y {peak_y}");
    assert_within_limits(&cfg, &from, &r.samples, 1.01);
}

#[test]
fn rotary_move_is_timed_in_degrees() {
    let mut limits = limits_xyz(100.0, 1000.0, 20_000.0);
    let (v, a, j) = (360.0, 3600.0, 360_000.0);
    limits[AxisLetter::C.index()] = Some(AxisLimits {
        max_velocity: v,
        max_acceleration: a,
        max_jerk: j,
    });
    let cfg = config(limits);
    let from = Pose::ZERO;
    let mut to = Pose::ZERO;
    to.set(AxisLetter::C, 720.0);
    let feed = 90.0; // °/s
    let r = run(cfg.clone(), from, vec![line(1, from, to, Feed::Rate(feed))]);
    assert!(feed * j >= a * a, "test case must reach full acceleration");
    let t = 720.0 / feed + feed / a + a / j;
    let arrival = arrival_time(&r, &to);
    assert!((arrival - t).abs() <= PERIOD, "{arrival} vs {t}");
    assert_eq!(r.samples.last().unwrap().pose.get(AxisLetter::C), 720.0);
    assert_within_limits(&cfg, &from, &r.samples, 1.01);
}

/// Programmed feed by source line (`None`: rapid).
type FeedTable = Vec<(u32, Option<f64>)>;

/// A program of lines, arcs in all planes, a helix and a spline, with its feeds by line.
fn mixed_program() -> (Pose, Vec<klar_interp::Op>, FeedTable) {
    let p0 = Pose::xyz(0.0, 0.0, 10.0);
    let p1 = Pose::xyz(20.0, 0.0, 0.0);
    let p2 = Pose::xyz(20.0, 30.0, 0.0);
    // Quarter circle CCW about (10, 30): from (20, 30) to (10, 40).
    let p3 = Pose::xyz(10.0, 40.0, 0.0);
    // Helix: 1.5 turns CW about (10, 35) radius 5, rising 6 mm, ending at (10, 30).
    let p4 = Pose::xyz(10.0, 30.0, 6.0);
    // ZX arc: about (Z 6, X 5), from (Z 6, X 10) a half turn to (Z 6, X 0).
    let p5 = Pose::xyz(0.0, 30.0, 6.0);
    // Spline ending at p6 from p5.
    let p6 = Pose::xyz(8.0, 34.0, 4.0);
    let k = |axis, k: [f64; 3]| SplineAxis { axis, k };
    let spline_axes = vec![
        k(AxisLetter::X, [1.0, -2.0, 0.0 - 8.0 - 1.0 + 2.0]),
        k(AxisLetter::Y, [-2.0, 1.0, 30.0 - 34.0 + 2.0 - 1.0]),
        k(AxisLetter::Z, [0.5, 0.5, 6.0 - 4.0 - 0.5 - 0.5]),
    ];
    let ops = vec![
        line(1, p0, p1, Feed::Rapid),
        line(2, p1, p2, Feed::Rate(40.0)),
        arc(3, p2, p3, [10.0, 30.0], Plane::XY, 90.0, Feed::Rate(30.0)),
        arc(4, p3, p4, [10.0, 35.0], Plane::XY, -540.0, Feed::Rate(50.0)),
        arc(5, p4, p5, [6.0, 5.0], Plane::ZX, 180.0, Feed::Rate(20.0)),
        op(
            6,
            OpKind::Spline {
                from: p5,
                to: p6,
                axes: spline_axes,
                feed: Feed::Rate(25.0),
            },
        ),
        line(7, p6, p0, Feed::Rapid),
    ];
    let feeds = vec![
        (1, None),
        (2, Some(40.0)),
        (3, Some(30.0)),
        (4, Some(50.0)),
        (5, Some(20.0)),
        (6, Some(25.0)),
        (7, None),
    ];
    (p0, ops, feeds)
}

#[test]
fn mixed_program_keeps_every_axis_within_its_limits() {
    let (start, ops, feeds) = mixed_program();
    let mut limits = limits_xyz(150.0, 800.0, 10_000.0);
    limits[2] = Some(AxisLimits {
        max_velocity: 60.0,
        max_acceleration: 400.0,
        max_jerk: 5_000.0,
    });
    let cfg = config(limits);
    let r = run(cfg.clone(), start, ops);
    assert_within_limits(&cfg, &start, &r.samples, 1.01);

    // Path speed never above the programmed feed, from the commanded velocity and from
    // finite differences (a chord is never longer than its arc).
    let mut prev = start;
    for s in &r.samples {
        let feed = feeds.iter().find(|f| f.0 == s.loc.line).unwrap().1;
        if let Some(f) = feed {
            let v = (s.velocity[0].powi(2) + s.velocity[1].powi(2) + s.velocity[2].powi(2)).sqrt();
            assert!(
                v <= f * (1.0 + 1e-9),
                "line {}: speed {v} above {f}",
                s.loc.line
            );
            // A period that crosses into a slower piece may average a hair above its
            // feed (the speed meets the limit at the crossing, not at the samples).
            let fd = linear_distance(&prev, &s.pose) / PERIOD;
            assert!(
                fd <= f * (1.0 + 1e-4),
                "line {}: chord speed {fd}",
                s.loc.line
            );
        }
        prev = s.pose;
    }
    let last = r.samples.last().unwrap();
    for i in 0..9 {
        assert!((last.pose.0[i] - start.0[i]).abs() <= 1e-9);
    }
    // Every block was executed, in order.
    let mut lines: Vec<u32> = r.samples.iter().map(|s| s.loc.line).collect();
    lines.dedup();
    assert_eq!(lines, vec![1, 2, 3, 4, 5, 6, 7]);
}

#[test]
fn samples_stay_on_the_programmed_circle() {
    let (cx, cy, rad) = (5.0, 5.0, 12.0);
    let from = Pose::xyz(cx + rad, cy, 0.0);
    let cfg = config(limits_xyz(100.0, 1000.0, 20_000.0));
    let r = run(
        cfg,
        from,
        vec![arc(
            1,
            from,
            from,
            [cx, cy],
            Plane::XY,
            360.0,
            Feed::Rate(50.0),
        )],
    );
    for s in &r.samples {
        let d = (s.pose.0[0] - cx).hypot(s.pose.0[1] - cy);
        assert!((d - rad).abs() < 1e-9);
    }
    assert_eq!(r.samples.last().unwrap().pose, from);
}

#[test]
fn dwell_holds_the_corner_exactly_for_its_time() {
    let cfg = config(limits_xyz(100.0, 1000.0, 20_000.0));
    let a = Pose::ZERO;
    let b = Pose::xyz(10.0, 0.0, 0.0);
    let c = Pose::xyz(10.0, 10.0, 0.0);
    let r = run(
        cfg,
        a,
        vec![
            line(1, a, b, Feed::Rate(50.0)),
            op(2, OpKind::Dwell { seconds: 0.25 }),
            line(3, b, c, Feed::Rate(50.0)),
        ],
    );
    let held: Vec<_> = r.samples.iter().filter(|s| s.loc.line == 2).collect();
    // 0.25 s of hold: 250 or 251 samples depending on where the move ended in its cycle.
    assert!((250..=251).contains(&held.len()), "{}", held.len());
    for s in &held {
        assert_eq!(s.pose, b);
        assert_eq!(s.velocity, [0.0; 9]);
    }
    let (at, ev) = &r.events[0];
    assert!(matches!(ev.kind, OpKind::Dwell { .. }));
    assert_eq!(r.samples[*at].loc.line, 2);
}

#[test]
fn dwells_at_the_same_point_add_up() {
    let cfg = config(limits_xyz(100.0, 1000.0, 20_000.0));
    let a = Pose::ZERO;
    let b = Pose::xyz(10.0, 0.0, 0.0);
    let c = Pose::xyz(10.0, 10.0, 0.0);
    let r = run(
        cfg,
        a,
        vec![
            line(1, a, b, Feed::Rate(50.0)),
            op(2, OpKind::Dwell { seconds: 0.25 }),
            op(3, OpKind::Dwell { seconds: 0.3 }),
            line(4, b, c, Feed::Rate(50.0)),
        ],
    );
    let held: Vec<_> = r
        .samples
        .iter()
        .filter(|s| s.loc.line == 2 || s.loc.line == 3)
        .collect();
    // 0.25 s + 0.3 s, give or take the cycle in which the move ended.
    assert!((550..=551).contains(&held.len()), "{}", held.len());
    for s in &held {
        assert_eq!(s.pose, b);
        assert_eq!(s.velocity, [0.0; 9]);
    }
}

#[test]
fn events_arrive_in_order_when_they_take_effect() {
    let (vmax, amax, jmax) = (100.0, 1000.0, 20_000.0);
    let cfg = config(limits_xyz(vmax, amax, jmax));
    let a = Pose::ZERO;
    let b = Pose::xyz(100.37, 0.0, 0.0);
    let c = Pose::xyz(100.37, 0.0, -5.3);
    let feed = 50.0;
    let r = run(
        cfg,
        a,
        vec![
            op(1, OpKind::Coolant { on: true }),
            line(2, a, b, Feed::Rate(feed)),
            op(3, OpKind::Coolant { on: false }),
            op(4, OpKind::Stop { optional: false }),
            line(5, b, c, Feed::Rate(feed)),
            op(6, OpKind::End),
        ],
    );
    let lines: Vec<u32> = r.events.iter().map(|e| e.1.loc.line).collect();
    assert_eq!(lines, vec![1, 3, 4, 6]);
    assert_eq!(r.events[0].0, 0, "coolant on before any motion");
    // Line 2 ends in a standstill at b (the program stop needs it) near its closed-form
    // time t1. Coolant off comes on the way there, the stop once the machine stands on b.
    let t1 = 100.37 / feed + feed / amax + amax / jmax;
    let arrival = arrival_time(&r, &b);
    assert!((arrival - t1).abs() <= PERIOD, "{arrival} vs {t1}");
    let off = r.events[1].0;
    assert!(r.samples[off].t <= arrival + 1e-12);
    let stop = r.events[2].0;
    assert_eq!(r.samples[stop - 1].pose, b);
    assert!(r.samples[stop - 1].t - arrival <= PERIOD + 1e-12);
    assert_eq!(r.samples[stop - 1].velocity, [0.0; 9]);
    assert!(off <= stop);
    assert_eq!(r.samples[stop].loc.line, 5);
    // End comes after the last sample, which is on the end point.
    assert_eq!(r.events[3].0, r.samples.len());
    assert_eq!(r.samples.last().unwrap().pose, c);
    // Samples stay on the k · period grid throughout.
    for (k, s) in r.samples.iter().enumerate() {
        assert_eq!(s.t, (k + 1) as f64 * PERIOD);
    }
}

#[test]
fn zero_length_moves_take_no_time() {
    let cfg = config(limits_xyz(100.0, 1000.0, 20_000.0));
    let a = Pose::ZERO;
    let b = Pose::xyz(10.0, 0.0, 0.0);
    let plain = run(cfg.clone(), a, vec![line(1, a, b, Feed::Rate(20.0))]);
    let with_zero = run(
        cfg,
        a,
        vec![
            line(1, a, b, Feed::Rate(20.0)),
            line(2, b, b, Feed::Rate(20.0)),
        ],
    );
    assert_eq!(plain.samples.len(), with_zero.samples.len());
    assert!(with_zero.samples.iter().all(|s| s.loc.line == 1));
}

#[test]
fn short_segments_still_end_exactly() {
    let cfg = config(limits_xyz(100.0, 1000.0, 20_000.0));
    let mut ops = Vec::new();
    let mut p = Pose::ZERO;
    for k in 0..200u32 {
        let q = Pose::xyz(
            p.0[0] + 0.013,
            p.0[1] + if k % 2 == 0 { 0.007 } else { -0.007 },
            0.0,
        );
        ops.push(line(k + 1, p, q, Feed::Rate(80.0)));
        p = q;
    }
    let r = run(cfg.clone(), Pose::ZERO, ops);
    assert_within_limits(&cfg, &Pose::ZERO, &r.samples, 1.01);
    let last = r.samples.last().unwrap().pose;
    for i in 0..3 {
        assert!((last.0[i] - p.0[i]).abs() <= 1e-9);
    }
}

#[test]
fn a_program_ending_on_a_short_move_ends_exactly_on_its_end_point() {
    // A 2 ms period, a long line, then a short move at an odd angle whose end the path
    // distance reaches only through sums that round.
    let cfg = PlannerConfig {
        period: 0.002,
        ..config(limits_xyz(100.0, 1000.0, 20_000.0))
    };
    let a = Pose::xyz(0.1, 0.2, 0.3);
    let b = Pose::xyz(37.123456789, -11.987654321, 5.5);
    let c = Pose::xyz(37.123456789 + 0.0137, -11.987654321 + 0.0071, 5.5 - 0.0029);
    let r = run(
        cfg.clone(),
        a,
        vec![
            line(1, a, b, Feed::Rate(80.0)),
            line(2, b, c, Feed::Rate(80.0)),
        ],
    );
    assert_within_limits(&cfg, &a, &r.samples, 1.01);
    let last = r.samples.last().unwrap();
    assert_eq!(last.pose, c);
    assert_eq!(last.velocity, [0.0; 9]);
    assert_eq!(last.acceleration, [0.0; 9]);
    // Sample times are whole periods.
    for (k, s) in r.samples.iter().enumerate() {
        assert_eq!(s.t, (k + 1) as f64 * 0.002);
    }
}

#[test]
fn stops_before_events_land_exactly_on_the_point() {
    let cfg = PlannerConfig {
        period: 0.002,
        ..config(limits_xyz(100.0, 1000.0, 20_000.0))
    };
    let a = Pose::xyz(0.3, 0.0, 0.0);
    let b = Pose::xyz(13.777, 2.313, -0.41);
    let c = Pose::xyz(13.7801, 2.3177, -0.4105);
    let d = Pose::xyz(1.0, 1.0, 1.0);
    let r = run(
        cfg.clone(),
        a,
        vec![
            line(1, a, b, Feed::Rate(60.0)),
            op(2, OpKind::ExactStop),
            line(3, b, c, Feed::Rate(60.0)),
            op(4, OpKind::Dwell { seconds: 0.01 }),
            line(5, c, d, Feed::Rapid),
            op(6, OpKind::End),
        ],
    );
    assert_within_limits(&cfg, &a, &r.samples, 1.01);
    let points = [b, c, d];
    assert_eq!(r.events.len(), 3);
    for ((at, _), point) in r.events.iter().zip(points) {
        // The last sample before each event stands exactly on its point, at rest.
        let before = &r.samples[at - 1];
        assert_eq!(before.pose, point);
        assert_eq!(before.velocity, [0.0; 9]);
    }
    assert_eq!(r.samples.last().unwrap().pose, d);
}

fn planner() -> Planner {
    Planner::new(config(limits_xyz(100.0, 1000.0, 20_000.0)), Pose::ZERO).unwrap()
}

#[test]
fn moving_an_absent_axis_names_the_block_and_axis() {
    let mut p = planner();
    let mut to = Pose::ZERO;
    to.set(AxisLetter::B, 30.0);
    let e = p
        .push(line(7, Pose::ZERO, to, Feed::Rate(10.0)))
        .unwrap_err();
    assert!(matches!(
        e,
        MotionError::AbsentAxis {
            axis: AxisLetter::B,
            ..
        }
    ));
    let msg = e.to_string();
    assert!(
        msg.contains("axis B") && msg.contains("line 7") && msg.contains("block 7"),
        "{msg}"
    );
}

#[test]
fn bad_ops_are_refused_with_their_location() {
    let to = Pose::xyz(5.0, 0.0, 0.0);
    let cases = vec![
        line(2, Pose::ZERO, to, Feed::PerRevolution(0.1)),
        line(3, Pose::ZERO, to, Feed::Rate(0.0)),
        line(4, Pose::ZERO, to, Feed::Rate(f64::NAN)),
        line(5, Pose::xyz(1.0, 0.0, 0.0), to, Feed::Rate(10.0)),
        line(
            6,
            Pose::ZERO,
            Pose::xyz(f64::INFINITY, 0.0, 0.0),
            Feed::Rate(10.0),
        ),
        arc(
            8,
            Pose::xyz(10.0, 0.0, 0.0),
            Pose::xyz(0.0, 12.0, 0.0),
            [0.0, 0.0],
            Plane::XY,
            90.0,
            Feed::Rate(10.0),
        ),
        op(9, OpKind::Dwell { seconds: -1.0 }),
        op(10, OpKind::Tolerance { mm: Some(-0.1) }),
    ];
    for o in cases {
        let line_no = o.loc.line;
        let mut p = planner();
        if line_no == 8 {
            p = Planner::new(
                config(limits_xyz(100.0, 1000.0, 20_000.0)),
                Pose::xyz(10.0, 0.0, 0.0),
            )
            .unwrap();
        }
        let e = p.push(o).unwrap_err();
        assert!(e.to_string().contains(&format!("line {line_no}")), "{e}");
        match line_no {
            2 => assert!(matches!(e, MotionError::NeedsSpindle { .. })),
            3 | 4 => assert!(matches!(e, MotionError::BadFeed { .. })),
            5 => assert!(matches!(
                e,
                MotionError::Discontinuity {
                    axis: AxisLetter::X,
                    ..
                }
            )),
            6 | 8 => assert!(matches!(e, MotionError::Geometry { .. })),
            9 => assert!(matches!(e, MotionError::BadDwell { .. })),
            _ => assert!(matches!(e, MotionError::BadTolerance { .. })),
        }
    }
}

#[test]
fn tight_corners_ahead_do_not_pull_the_program_into_the_look_ahead() {
    // Laps of a 50 × 50 mm square with 1 mm corner arcs at F6000: at the full speed of its
    // edges the blends of its corners allow no acceleration at all (the curvature would take
    // it all), which once made the look-ahead reach infinite: the planner asked for the
    // whole program (2500 moves, 20 000 pieces) and each servo cycle scanned all of it.
    let mut p = Planner::new(
        config(limits_xyz(100.0, 1000.0, 1e5)),
        Pose::xyz(-24.0, 0.0, 0.0),
    )
    .expect("valid config");
    let xy = |x: f64, y: f64| Pose::xyz(x, y, 0.0);
    let feed = Feed::Rate(100.0);
    let lap = [
        (xy(-24.0, 0.0), xy(24.0, 0.0), None),
        (xy(24.0, 0.0), xy(25.0, 1.0), Some([24.0, 1.0])),
        (xy(25.0, 1.0), xy(25.0, 49.0), None),
        (xy(25.0, 49.0), xy(24.0, 50.0), Some([24.0, 49.0])),
        (xy(24.0, 50.0), xy(-24.0, 50.0), None),
        (xy(-24.0, 50.0), xy(-25.0, 49.0), Some([-24.0, 49.0])),
        (xy(-25.0, 49.0), xy(-25.0, 1.0), None),
        (xy(-25.0, 1.0), xy(-24.0, 0.0), Some([-24.0, 1.0])),
    ];
    let mut pushed = 0usize;
    let mut most_ahead = 0usize;
    for cycle in 0..6000 {
        while p.needs_input() && pushed < 10_000 {
            let (from, to, center) = lap[pushed % lap.len()];
            let n = u32::try_from(pushed + 1).expect("few moves");
            let op = match center {
                Some(c) => arc(n, from, to, c, Plane::XY, 90.0, feed),
                None => line(n, from, to, feed),
            };
            p.push(op).expect("valid move");
            pushed += 1;
        }
        // Moves pushed beyond those the path has got through: about 2.4 s a lap.
        let done = (cycle as f64 / 2400.0 * lap.len() as f64) as usize;
        most_ahead = most_ahead.max(pushed.saturating_sub(done));
        assert!(p.next_step().is_some());
    }
    assert!(most_ahead <= 2 * lap.len(), "{most_ahead} moves ahead");
}

#[test]
fn the_look_ahead_is_sized_by_braking_distance_and_bounded_in_memory() {
    // 1 mm segments: the planner asks for input until the committed path reaches past its
    // look-ahead distance (three elements wait for their corners).
    let mut p = planner();
    let mut n = 0u32;
    let mut from = Pose::ZERO;
    while p.needs_input() {
        n += 1;
        let to = Pose::xyz(f64::from(n), 0.0, 0.0);
        p.push(line(n, from, to, Feed::Rate(10.0))).unwrap();
        from = to;
    }
    let horizon = p.horizon();
    // The horizon is twice the braking distance from the top speed (√3 · 100 · 1.5 mm/s
    // over three axes) with half the axis acceleration and jerk, so far beyond 10 mm.
    let top = 3f64.sqrt() * 100.0 * 1.5;
    assert!(horizon >= top * top / 1000.0, "{horizon}");
    assert!(
        f64::from(n) >= horizon && f64::from(n) <= horizon + 4.0,
        "{n} vs {horizon}"
    );

    // Tiny segments that turn sharply (a zigzag of 0.1 µm steps: no run of dense code
    // can merge them) fill the reserved piece queue long before the look-ahead distance:
    // the planner stops asking with a margin left in its reserve. Besides the pieces, at
    // most a few hundred elements wait for their corners.
    let mut p = planner();
    let mut n = 0u32;
    let mut from = Pose::ZERO;
    while p.needs_input() {
        n += 1;
        let y = if n.is_multiple_of(2) { 0.0 } else { 1e-4 };
        let to = Pose::xyz(f64::from(n) * 1e-4, y, 0.0);
        p.push(line(n, from, to, Feed::Rate(10.0))).unwrap();
        from = to;
    }
    assert!(f64::from(n) * 2e-4 < horizon);
    let reserve = klar_motion::planner::RESERVED_PIECES - klar_motion::planner::PIECE_MARGIN;
    assert!(n as usize <= reserve + 300, "{n}");
    // A caller that pushes on regardless meets the hard memory bound: pushes are refused
    // once the planner holds its capacity, never later.
    let mut extra = 0usize;
    let e = loop {
        n += 1;
        extra += 1;
        let y = if n.is_multiple_of(2) { 0.0 } else { 1e-4 };
        let to = Pose::xyz(f64::from(n) * 1e-4, y, 0.0);
        match p.push(line(n, from, to, Feed::Rate(10.0))) {
            Ok(()) => from = to,
            Err(e) => break e,
        }
        assert!(
            extra <= klar_motion::planner::BUFFER_CAPACITY,
            "never refused"
        );
    };
    assert!(matches!(e, MotionError::BufferFull { .. }));
    // Draining lets it ask again (a stop passed frees a place too: `next_step` then asks
    // for input at once).
    let mut steps = 0u32;
    while !p.needs_input() && p.next_step().is_some() {
        steps += 1;
    }
    assert!(p.needs_input(), "still full after {steps} steps");
    p.finish();
    assert!(matches!(
        p.push(line(99, from, from, Feed::Rate(1.0))),
        Err(MotionError::AfterFinish { .. })
    ));
}

#[test]
fn bad_configurations_are_refused() {
    let good = config(limits_xyz(100.0, 1000.0, 20_000.0));
    let mut c = good.clone();
    c.period = 0.0;
    assert!(matches!(
        Planner::new(c, Pose::ZERO),
        Err(MotionError::Config(_))
    ));
    let mut c = good.clone();
    c.tolerance = -1.0;
    assert!(Planner::new(c, Pose::ZERO).is_err());
    let mut c = good.clone();
    c.limits[1] = Some(AxisLimits {
        max_velocity: 10.0,
        max_acceleration: f64::NAN,
        max_jerk: 1.0,
    });
    let e = Planner::new(c, Pose::ZERO).unwrap_err();
    assert!(e.to_string().contains("axis Y"), "{e}");
    let c = PlannerConfig {
        limits: [None; 9],
        ..good.clone()
    };
    assert!(Planner::new(c, Pose::ZERO).is_err());
    assert!(Planner::new(good, Pose::xyz(f64::NAN, 0.0, 0.0)).is_err());
}

#[test]
fn an_empty_program_gives_no_samples() {
    let mut p = planner();
    p.push(op(1, OpKind::End)).unwrap();
    p.finish();
    assert!(matches!(p.next_step(), Some(Step::Event(_))));
    assert!(p.next_step().is_none());
}

#[test]
fn a_move_too_long_to_measure_is_refused() {
    let start = Pose::xyz(-1e308, 0.0, 0.0);
    let mut p = Planner::new(config(limits_xyz(100.0, 1000.0, 20_000.0)), start).unwrap();
    let e = p
        .push(line(3, start, Pose::xyz(1e308, 0.0, 0.0), Feed::Rate(10.0)))
        .unwrap_err();
    assert!(matches!(e, MotionError::Geometry { .. }), "{e}");
}

#[test]
fn an_exact_stop_op_stops_at_the_corner_and_its_absence_blends_it() {
    let cfg = config(limits_xyz(100.0, 1000.0, 20_000.0));
    let a = Pose::ZERO;
    // A 10° turn in the XZ plane.
    let b = Pose::xyz(40.0, 0.0, 0.0);
    let c = Pose::xyz(
        40.0 + 20.0 * 10f64.to_radians().cos(),
        0.0,
        -20.0 * 10f64.to_radians().sin(),
    );
    let ops = |stop: bool| {
        let mut v = vec![line(1, a, b, Feed::Rate(50.0))];
        if stop {
            v.push(op(2, OpKind::ExactStop));
        }
        v.push(line(3, b, c, Feed::Rate(50.0)));
        v
    };
    let stopped = run(cfg.clone(), a, ops(true));
    // With the exact stop some sample stands exactly on the corner with zero speed.
    assert!(
        stopped
            .samples
            .iter()
            .any(|s| s.pose == b && s.velocity == [0.0; 9])
    );
    assert!(matches!(stopped.events[0].1.kind, OpKind::ExactStop));
    assert_eq!(stopped.samples[stopped.events[0].0 - 1].pose, b);
    assert_within_limits(&cfg, &a, &stopped.samples, 1.01);

    let blended = run(cfg.clone(), a, ops(false));
    // Without it the corner is rounded inside the tolerance and never reached; the path
    // keeps moving (no sample at rest until the end).
    let moving = &blended.samples[..blended.samples.len() - 1];
    assert!(moving.iter().all(|s| s.pose != b));
    assert!(moving.iter().all(|s| s.velocity.iter().any(|v| *v != 0.0)));
    let (ux, uz) = (10f64.to_radians().cos(), -10f64.to_radians().sin());
    for s in &blended.samples {
        // Distance from the two programmed lines (in the XZ plane).
        let (x, z) = (s.pose.0[0], s.pose.0[2]);
        let d1 = if x <= 40.0 {
            z.abs()
        } else {
            (x - 40.0).hypot(z)
        };
        let along = ((x - 40.0) * ux + z * uz).clamp(0.0, 20.0);
        let d2 = (x - 40.0 - along * ux).hypot(z - along * uz);
        assert!(d1.min(d2) <= cfg.tolerance, "{x} {z}");
    }
    assert_within_limits(&cfg, &a, &blended.samples, 1.01);
}
