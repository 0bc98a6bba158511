//! Each block's programmed feed over its own stretch of the path: where the feed changes at a
//! joint the blend replaces, the speed changes at that joint, not over the blend's reach into
//! the neighbours. Judged from the commanded trace against closed-form jerk-limited ramps.

mod common;

use common::*;
use klar_interp::{Feed, Op, Pose};

/// Bench limits: 100 mm/s, 1000 mm/s², 1e5 mm/s³ per axis.
const V: f64 = 100.0;
const A: f64 = 1000.0;
const J: f64 = 1e5;

/// Duration and distance of the time-optimal jerk-limited change of speed from `v0` to `v1`
/// (at rest in acceleration at both ends; closed form: with or without a stretch at the
/// acceleration limit).
fn ramp(v0: f64, v1: f64) -> (f64, f64) {
    let dv = (v1 - v0).abs();
    let t = if dv >= A * A / J {
        dv / A + A / J
    } else {
        2.0 * (dv / J).sqrt()
    };
    // The profile is symmetric in time about its middle: the mean speed is the average.
    (t, 0.5 * (v0 + v1) * t)
}

/// The time-optimal jerk-limited time of a straight path of stretches `(length, speed)`
/// from rest to rest, each at its speed, with every change of speed done where the slower
/// stretch begins or ends (the programmed feed holds over each block's stretch). Valid when
/// each ramp fits within the faster stretch next to it.
fn straight_bound(stretches: &[(f64, f64)]) -> f64 {
    let mut time: f64 = stretches.iter().map(|(l, v)| l / v).sum();
    let mut lost = |v0: f64, v1: f64| {
        let fast = v0.max(v1);
        let (t, d) = ramp(v0, v1);
        time += t - d / fast;
    };
    let speeds: Vec<f64> = stretches.iter().map(|s| s.1).collect();
    lost(0.0, speeds[0]);
    for w in speeds.windows(2) {
        lost(w[0], w[1]);
    }
    lost(speeds[speeds.len() - 1], 0.0);
    time
}

/// Path speed over each period (difference over X Y Z) with the X it starts and ends at.
fn speeds(start: &Pose, r: &Run) -> Vec<(f64, f64, f64)> {
    let mut prev = *start;
    r.samples
        .iter()
        .map(|s| {
            let v = linear_distance(&prev, &s.pose) / 0.001;
            let x0 = prev.0[0];
            prev = s.pose;
            (x0, s.pose.0[0], v)
        })
        .collect()
}

/// Three lines: to X50 at `f_fast`, to X53 with a kink of `dy` at `f_slow`, to X100 (still
/// at Y `dy`) at `f_fast` (feeds in mm/s, as the planner takes them).
fn three_lines(dy: f64, f_fast: f64, f_slow: f64) -> (Pose, Vec<Op>) {
    let p0 = Pose::xyz(0.0, 0.0, 0.0);
    let p1 = Pose::xyz(50.0, 0.0, 0.0);
    let p2 = Pose::xyz(53.0, dy, 0.0);
    let p3 = Pose::xyz(100.0, dy, 0.0);
    let ops = vec![
        line(1, p0, p1, Feed::Rate(f_fast)),
        line(2, p1, p2, Feed::Rate(f_slow)),
        line(3, p2, p3, Feed::Rate(f_fast)),
    ];
    (p0, ops)
}

fn check_three_lines(dy: f64) {
    let (fast, slow) = (1206.0 / 60.0, 302.0 / 60.0);
    let (start, ops) = three_lines(dy, fast, slow);
    let cfg = config(limits_xyz(V, A, J));
    let r = run(cfg.clone(), start, ops);
    assert_within_limits(&cfg, &start, &r.samples, 1.01);
    let end = r.samples.last().expect("samples").pose;
    assert!(linear_distance(&end, &Pose::xyz(100.0, dy, 0.0)) < 1e-9);

    let (_, from_rest) = ramp(0.0, fast);
    let (_, change) = ramp(fast, slow);
    // A little more than a period's travel at the fast feed, for the sampling.
    let margin = 0.05;
    for (x0, x, v) in speeds(&start, &r) {
        // The slow block's stretch never sees more than its feed; the fast ones run at
        // theirs wherever the ramps from rest, into and out of the slow stretch allow.
        if x0 >= 50.0 && x <= 53.0 {
            assert!(v <= slow * (1.0 + 1e-6), "dy {dy}: {v} mm/s at X{x} (F302)");
        }
        if (50.0 + margin..=53.0 - margin).contains(&x) {
            assert!(v >= slow * 0.999, "dy {dy}: {v} mm/s at X{x} (F302)");
        }
        let fast_left = from_rest + margin..=50.0 - change - margin;
        let fast_right = 53.0 + change + margin..=100.0 - from_rest - margin;
        if fast_left.contains(&x) || fast_right.contains(&x) {
            assert!(v >= fast * 0.999, "dy {dy}: {v} mm/s at X{x} (F1206)");
        }
        assert!(v <= fast * (1.0 + 1e-6), "dy {dy}: {v} mm/s at X{x}");
    }
    // Against the closed form: at most one period over it (the end rounds up to the next
    // period; the braking into the slow block starts on a period boundary, a fraction of a
    // period early, while the ramp out of it starts at the joint itself).
    let bound = straight_bound(&[(50.0, fast), (3.0, slow), (47.0, fast)]);
    let t = r.samples.last().map_or(0.0, |s| s.t);
    assert!(
        t <= bound + 0.001,
        "dy {dy}: {t} s against the jerk-limited optimum {bound} s"
    );
}

/// Time at which the commanded path first reaches `x` (linear between samples).
fn time_at_x(start: &Pose, r: &Run, x: f64) -> f64 {
    let (mut t0, mut x0) = (0.0, start.0[0]);
    for s in &r.samples {
        let x1 = s.pose.0[0];
        if x1 >= x {
            return t0 + (s.t - t0) * (x - x0) / (x1 - x0).max(f64::MIN_POSITIVE);
        }
        (t0, x0) = (s.t, x1);
    }
    f64::INFINITY
}

#[test]
fn ramp_out_of_a_slow_block_starts_at_its_end() {
    // From the end of the slow block (X53) to X60 the fastest motion ramps from 5.0333 to
    // 20.1 mm/s over 0.31501 mm in 25.067 ms and covers the remaining 6.68499 mm at 20.1
    // mm/s (0.332587 s): 0.357654 s. Starting the ramp at the next period boundary after
    // the joint instead would take up to a period longer.
    let (fast, slow) = (1206.0 / 60.0, 302.0 / 60.0);
    let (start, ops) = three_lines(0.0, fast, slow);
    let r = run(config(limits_xyz(V, A, J)), start, ops);
    let (t_ramp, d_ramp) = ramp(slow, fast);
    let closed = t_ramp + (7.0 - d_ramp) / fast;
    assert!((closed - 0.357654).abs() < 1e-6, "{closed}");
    let took = time_at_x(&start, &r, 60.0) - time_at_x(&start, &r, 53.0);
    assert!(
        (took - closed).abs() < 2e-5,
        "{took} s from X53 to X60 against {closed} s"
    );
}

#[test]
fn slow_block_between_fast_ones_keeps_each_feed_on_its_own_stretch() {
    // Exactly straight, and kinks of 0.1 µrad to 10 mrad, as 3-decimal CAM output has them.
    for dy in [0.0, 3e-7, 3e-6, 0.0003, 0.003, 0.03] {
        check_three_lines(dy);
    }
}

#[test]
fn three_line_bound_is_the_closed_form() {
    // The bound itself, by hand: 97 mm at 20.1 mm/s, 3 mm at 5.0333 mm/s, a ramp from and
    // to rest (0.0301 s, 0.30251 mm each) and two changes between the feeds (0.025067 s,
    // 0.31501 mm each).
    let (fast, slow) = (20.1, 302.0 / 60.0);
    let by_hand = 97.0 / fast
        + 3.0 / slow
        + 2.0 * (0.0301 - 0.30251 / fast)
        + 2.0 * (0.0250667 - 0.315007 / fast);
    let bound = straight_bound(&[(50.0, fast), (3.0, slow), (47.0, fast)]);
    assert!((bound - by_hand).abs() < 1e-5, "{bound} against {by_hand}");
    assert!((bound - 5.4708).abs() < 1e-3, "{bound}");
}

/// A reduced-feed line before a corner, as CAM post-processors print it: the long line's
/// feed holds up to the ramp into the slow stretch, which ends where the slow block begins.
#[test]
fn reduced_feed_before_a_corner_holds_the_long_line_feed() {
    let (fast, slow) = (2000.0 / 60.0, 500.0 / 60.0);
    let p0 = Pose::xyz(0.0, 0.0, 0.0);
    // The split before the corner is nearly straight (1 µm off in Y over 2 mm).
    let p1 = Pose::xyz(40.0, 0.0, 0.0);
    let p2 = Pose::xyz(42.0, 0.001, 0.0);
    let p3 = Pose::xyz(42.0, 30.0, 0.0);
    let ops = vec![
        line(1, p0, p1, Feed::Rate(fast)),
        line(2, p1, p2, Feed::Rate(slow)),
        line(3, p2, p3, Feed::Rate(fast)),
    ];
    let cfg = config(limits_xyz(V, A, J));
    let r = run(cfg.clone(), p0, ops);
    assert_within_limits(&cfg, &p0, &r.samples, 1.01);
    let (_, from_rest) = ramp(0.0, fast);
    let (_, change) = ramp(fast, slow);
    let mut seen_fast = 0;
    for (x0, x, v) in speeds(&p0, &r) {
        if x > 1.0 {
            // Past the start (the third line runs along Y at X42).
            if (from_rest + 0.05..=40.0 - change - 0.05).contains(&x) {
                assert!(v >= fast * 0.999, "{v} mm/s at X{x}");
                seen_fast += 1;
            }
            if x0 >= 40.0 && x < 41.99 {
                assert!(v <= slow * (1.0 + 1e-6), "{v} mm/s at X{x} (F500)");
            }
        }
    }
    assert!(seen_fast > 1000, "{seen_fast} samples at the fast feed");
}
