//! Corners next to moves that turn a rotary axis along their linear motion: every axis,
//! rotary ones included, within its speed, acceleration and jerk limits by finite
//! differences of the samples, before, inside and after the blend (or the exact stop that
//! replaces it).
//!
//! The limits are those of `machines/mill5.toml`. A move of X 0.25 mm with C 29° turns C by
//! 116° per millimetre of path, so C's limits put the path's far below the floors the
//! look-ahead distance is sized with.

mod common;

use common::*;
use klar_interp::op::SplineAxis;
use klar_interp::{AxisLetter, Feed, Op, OpKind, Pose};
use klar_motion::{AxisLimits, PlannerConfig};

const PERIOD: f64 = 0.001;

fn axis(v: f64, a: f64, j: f64) -> Option<AxisLimits> {
    Some(AxisLimits {
        max_velocity: v,
        max_acceleration: a,
        max_jerk: j,
    })
}

/// The limits of machines/mill5.toml: X Y Z, A and C (tolerance 0.01 mm, 1 ms).
fn mill5() -> PlannerConfig {
    let mut limits = [None; 9];
    limits[0] = axis(166.0, 2000.0, 50_000.0);
    limits[1] = axis(166.0, 2000.0, 50_000.0);
    limits[2] = axis(100.0, 1500.0, 40_000.0);
    limits[AxisLetter::A.index()] = axis(90.0, 720.0, 10_000.0);
    limits[AxisLetter::C.index()] = axis(180.0, 1440.0, 20_000.0);
    config(limits)
}

fn pose(x: f64, y: f64, z: f64, a: f64, c: f64) -> Pose {
    let mut p = Pose::xyz(x, y, z);
    p.set(AxisLetter::A, a);
    p.set(AxisLetter::C, c);
    p
}

/// Runs `ops` from `start` on mill5 and checks every axis by finite differences.
fn run_within_limits(start: Pose, ops: Vec<Op>) -> Run {
    let cfg = mill5();
    let r = run(cfg.clone(), start, ops);
    assert_within_limits(&cfg, &start, &r.samples, 1.01);
    r
}

/// Rest-to-rest time of a straight move of `d` with path limits v, a, j (closed form of the
/// jerk-limited S-curve: `d/v + v/a + a/j` when it reaches both v and a, else the peak
/// speed from `d = v_p·(v_p/a + a/j)`, or `d = 2·v_p·√(v_p/j)` when not even a is reached).
fn rest_to_rest(d: f64, v: f64, a: f64, j: f64) -> f64 {
    let full = if v * j >= a * a {
        v * (v / a + a / j)
    } else {
        2.0 * v * (v / j).sqrt()
    };
    if d >= full {
        return if v * j >= a * a {
            d / v + v / a + a / j
        } else {
            d / v + 2.0 * (v / j).sqrt()
        };
    }
    // Peak speed below v: reaches a when v_p ≥ a²/j.
    let r = a / j;
    let vp = 0.5 * a * (-r + (r * r + 4.0 * d / a).sqrt());
    if vp >= a * a / j {
        2.0 * (vp / a + r)
    } else {
        // d = 2·v_p·√(v_p/j): v_p = (d²·j/4)^(1/3), t = 4·√(v_p/j).
        let vp = (d * d * j / 4.0).cbrt();
        4.0 * (vp / j).sqrt()
    }
}

/// The program of the report: Z from 150 down to 100 at rapid, then X+0.25 with A and C
/// turning by `a` and `c` degrees, at `feed`.
fn z_then_x_turning(a: f64, c: f64, feed: Feed) -> (Pose, Vec<Op>, Pose) {
    let start = pose(0.0, 0.0, 150.0, 0.0, 0.0);
    let p1 = pose(0.0, 0.0, 100.0, 0.0, 0.0);
    let p2 = pose(0.25, 0.0, 100.0, a, c);
    let ops = vec![line(1, start, p1, Feed::Rapid), line(2, p1, p2, feed)];
    (start, ops, p2)
}

/// The corner between the Z move and a move that turns C (or A) by over 50° per mm: with
/// C at 116°/mm, C's limits allow the second move 1.55 mm/s, 12.4 mm/s² and 172 mm/s³ of
/// path. Braking into a blend there with that jerk would take seconds; the corner stops
/// exactly instead, so the program takes the two rest-to-rest times.
#[test]
fn a_corner_into_a_move_turning_c_fast_stops_and_keeps_every_axis_within_its_limits() {
    // The report's program at rapid and at F3000, without A, and the case the five-axis
    // property test reduced it to (A alone, 58°/mm).
    for (a, c, feed) in [
        (0.5, 29.0, Feed::Rapid),
        (0.5, 29.0, Feed::Rate(50.0)),
        (0.0, 29.0, Feed::Rapid),
        (14.5, 0.0, Feed::Rapid),
    ] {
        let (start, ops, end) = z_then_x_turning(a, c, feed);
        let r = run_within_limits(start, ops);
        let last = r.samples.last().expect("samples");
        for i in 0..9 {
            assert!((last.pose.0[i] - end.0[i]).abs() < 1e-9, "axis {i}");
        }
        // Z: 50 mm with Z's limits. The second move: X's limits, and each rotary axis's
        // over its turn per mm of path (the 0.25 mm of X).
        let tz = rest_to_rest(50.0, 100.0, 1500.0, 40_000.0);
        let (mut v, mut acc, mut j) = (166.0f64, 2000.0f64, 50_000.0f64);
        for (turn, (vr, ar, jr)) in [(a, (90.0, 720.0, 10_000.0)), (c, (180.0, 1440.0, 20_000.0))] {
            let k = turn / 0.25;
            if k > 0.0 {
                (v, acc, j) = (v.min(vr / k), acc.min(ar / k), j.min(jr / k));
            }
        }
        let tx = rest_to_rest(0.25, v, acc, j);
        let t = last.t;
        assert!(
            t >= tz + tx - 2.0 * PERIOD && t <= tz + tx + 3.0 * PERIOD,
            "A {a} C {c} {feed:?}: {t} s against {tz} + {tx}"
        );
    }
}

/// Short lines as a five-axis CAM post writes them: chords of 0.2 mm on a circle of radius
/// 20 mm in XY, C turning by `step` degrees per chord; `jump` (index, C step) puts one
/// chord with a far larger turn in the middle.
fn cam_chords(n: usize, step: f64, jump: Option<(usize, f64)>, feed: f64) -> (Pose, Vec<Op>) {
    let r = 20.0;
    let dphi = 0.2 / r;
    let at = |k: usize, c: f64| {
        let phi = dphi * k as f64;
        pose(r * phi.sin(), r - r * phi.cos(), 0.0, 0.0, c)
    };
    let start = at(0, 0.0);
    let mut ops = Vec::new();
    let (mut from, mut c) = (start, 0.0);
    for k in 1..=n {
        c += match jump {
            Some((i, big)) if i == k => big,
            _ => step,
        };
        let to = at(k, c);
        ops.push(line(k as u32, from, to, Feed::Rate(feed)));
        from = to;
    }
    (start, ops)
}

/// Path speed over X Y Z of each sample.
fn path_speeds(r: &Run) -> Vec<f64> {
    r.samples
        .iter()
        .map(|s| (s.velocity[0].powi(2) + s.velocity[1].powi(2) + s.velocity[2].powi(2)).sqrt())
        .collect()
}

#[test]
fn dense_five_axis_code_with_small_c_steps_keeps_blending_at_the_feed() {
    // 300 chords of 0.2 mm with C 0.1° each (0.5°/mm) at F1200: C turns at 10°/s. Nothing
    // there needs to slow down: the path runs at the feed between its ramps, without stops.
    let feed = 20.0;
    let (start, ops) = cam_chords(300, 0.1, None, feed);
    let r = run_within_limits(start, ops);
    let v = path_speeds(&r);
    let n = v.len();
    let middle = &v[n / 5..4 * n / 5];
    let slowest = middle.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(slowest > 0.98 * feed, "slowest {slowest} mm/s at F{feed}");
    // 60 mm at the feed and one ramp up and down with the XY limits: a little more than
    // the feed time, far less than a stop at any of the 299 corners would add.
    let t = r.samples.last().expect("samples").t;
    assert!(t > 60.0 / feed && t < 60.0 / feed + 0.1, "{t} s");
}

#[test]
fn dense_five_axis_code_turning_c_fast_blends_without_stopping() {
    // Chords of 0.2 mm with C 1° each (5°/mm) at F3000: C allows the path 36 mm/s, and its
    // limits put the blends through the split points well below the lines'. The path slows
    // down for them but stops nowhere between its ends.
    let (start, ops) = cam_chords(200, 1.0, None, 50.0);
    let r = run_within_limits(start, ops);
    let v = path_speeds(&r);
    let n = v.len();
    let slowest = v[n / 10..9 * n / 10]
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    assert!(slowest > 1.0, "slowest {slowest} mm/s");
}

#[test]
fn a_sudden_large_c_step_in_dense_code_is_met_within_the_limits() {
    // The same chords with one in the middle that turns C by 20° over 0.2 mm (100°/mm).
    for feed in [20.0, 50.0] {
        let (start, ops) = cam_chords(200, 0.1, Some((100, 20.0)), feed);
        run_within_limits(start, ops);
    }
}

#[test]
fn a_blend_between_two_moves_turning_c_alike_is_kept_within_every_limit() {
    // Two 2 mm moves 5° apart in XY that both turn C by 5°/mm (and A by 2°/mm, or not),
    // at F1000 and at rapid: the blend's limits are close to its neighbours', so the path
    // goes round the corner without stopping.
    for feed in [Feed::Rate(1000.0 / 60.0), Feed::Rapid] {
        for a in [0.0, 2.0] {
            let th = 5f64.to_radians();
            let p0 = pose(0.0, 0.0, 0.0, 0.0, 0.0);
            let p1 = pose(2.0, 0.0, 0.0, 2.0 * a, 10.0);
            let p2 = pose(2.0 + 2.0 * th.cos(), 2.0 * th.sin(), 0.0, 4.0 * a, 20.0);
            let r = run_within_limits(p0, vec![line(1, p0, p1, feed), line(2, p1, p2, feed)]);
            assert_eq!(r.samples.last().expect("samples").pose, p2);
            let v = path_speeds(&r);
            let n = v.len();
            let slowest = v[n / 4..3 * n / 4]
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min);
            assert!(slowest > 1.0, "{feed:?} A {a}: {slowest} mm/s");
        }
    }
}

#[test]
fn a_corner_between_moves_turning_c_at_different_rates_stops_within_every_limit() {
    // 10 mm moves 8° apart turning C by 1 and then 2 °/mm at F3000: braking into the blend
    // with the jerk C leaves it takes longer than stopping (0.79 s against 0.64 s). The
    // path stands at the corner: the rest-to-rest time of each move with its own limits.
    let th = 8f64.to_radians();
    let p0 = pose(0.0, 0.0, 0.0, 0.0, 0.0);
    let p1 = pose(10.0, 0.0, 0.0, 0.0, 10.0);
    let p2 = pose(10.0 + 10.0 * th.cos(), 10.0 * th.sin(), 0.0, 0.0, 30.0);
    let feed = Feed::Rate(50.0);
    let r = run_within_limits(p0, vec![line(1, p0, p1, feed), line(2, p1, p2, feed)]);
    // Path limits: the first move X alone with C at 1 °/mm; the second with C at 2 °/mm
    // and X, Y at cos 8°, sin 8°.
    let t1 = rest_to_rest(10.0, 50.0, 1440.0, 20_000.0);
    let c = th.cos();
    let t2 = rest_to_rest(
        10.0,
        50.0,
        (2000.0 / c).min(720.0),
        (50_000.0 / c).min(10_000.0),
    );
    let t = r.samples.last().expect("samples").t;
    assert!(
        t >= t1 + t2 - 2.0 * PERIOD && t <= t1 + t2 + 3.0 * PERIOD,
        "{t} s against {t1} + {t2}"
    );
}

/// Block 2: a spline from `p1` to `p2` with X linear in the spline parameter (`K1X = k1x`)
/// and C = 30·u³ of the way (K3/K2/K1 of C: −30, 90, −90).
fn x_c_spline(p1: Pose, p2: Pose, k1x: f64, feed: Feed) -> Op {
    let k = |axis, k: [f64; 3]| SplineAxis { axis, k };
    op(
        2,
        OpKind::Spline {
            from: p1,
            to: p2,
            axes: vec![
                k(AxisLetter::X, [0.0, 0.0, k1x]),
                k(AxisLetter::C, [-30.0, 90.0, -90.0]),
            ],
            feed,
        },
    )
}

#[test]
fn a_spline_turning_c_after_a_fast_line_is_seen_in_time() {
    // A line along X at F3000, then a spline that continues it without a corner (same
    // tangent, no curvature at the joint: nothing to blend) while C follows 30·u³ over its
    // 1 mm, up to 90°/mm at its end: its path jerk limit is a few hundred mm/s³. The path
    // must come down from 50 mm/s for it well before the joint.
    let p0 = pose(-100.0, 0.0, 0.0, 0.0, 0.0);
    let p1 = pose(0.0, 0.0, 0.0, 0.0, 0.0);
    let p2 = pose(1.0, 0.0, 0.0, 0.0, 30.0);
    // Coordinates as K3·t³ + K2·t² + K1·t + end with t = 1 − u: X = 1 − t, and
    // C = 30·(1 − t)³ = 30 − 90t + 90t² − 30t³.
    let spline = x_c_spline(p1, p2, -1.0, Feed::Rate(50.0));
    let r = run_within_limits(p0, vec![line(1, p0, p1, Feed::Rate(50.0)), spline]);
    assert_eq!(r.samples.last().expect("samples").pose, p2);
}

#[test]
fn a_spline_turning_c_too_sharply_to_brake_for_from_the_look_ahead_gets_a_stop() {
    // X at rapid over 2000 mm, then a spline of 0.05 mm continuing it while C turns by 30°
    // (up to 1800°/mm), then more moves: the spline is committed only when the path is a
    // look-ahead distance before it, far less than braking from 166 mm/s with its jerk of a
    // few mm/s³ would need. The path stops in front of it instead, within every limit.
    let p0 = pose(-2000.0, 0.0, 0.0, 0.0, 0.0);
    let p1 = pose(0.0, 0.0, 0.0, 0.0, 0.0);
    let p2 = pose(0.05, 0.0, 0.0, 0.0, 30.0);
    let spline = x_c_spline(p1, p2, -0.05, Feed::Rapid);
    // Moves after it, so that the spline waits for its corner after the line is committed.
    let p3 = pose(10.0, 0.0, 0.0, 0.0, 30.0);
    let p4 = pose(10.0, 10.0, 0.0, 0.0, 30.0);
    let ops = vec![
        line(1, p0, p1, Feed::Rapid),
        spline,
        line(3, p2, p3, Feed::Rapid),
        line(4, p3, p4, Feed::Rapid),
        line(5, p4, p0, Feed::Rapid),
    ];
    let r = run_within_limits(p0, ops);
    assert_eq!(r.samples.last().expect("samples").pose, p0);
    // The path stands on the joint: X's rest-to-rest time over the line.
    let tx = rest_to_rest(2000.0, 166.0, 2000.0, 50_000.0);
    let stood = r
        .samples
        .iter()
        .find(|s| s.pose == p1)
        .map_or(f64::INFINITY, |s| s.t);
    assert!((stood - tx).abs() <= 2.0 * PERIOD, "{stood} against {tx}");
}
