//! Sharp corners: an exact stop where the blend inside the band would crawl (overlapped
//! where the axes that brake are not those that start), a blend where it pays. A 90° stepover (a pass along X at F2400, then up in Z at F400), as parallel
//! finishing turns from each pass into the stepover, judged from the commanded trace against
//! the closed-form time of stopping at the corner.

mod common;

use common::*;
use klar_interp::{Feed, Pose};
use klar_motion::blend::corner::TOLERANCE_SHARE;

/// Bench limits: 100 mm/s, 1000 mm/s², 1e5 mm/s³ per axis.
const V: f64 = 100.0;
const A: f64 = 1000.0;
const J: f64 = 1e5;

/// Duration of the time-optimal jerk-limited change of speed between rest and `v` (at rest
/// in acceleration at both ends; with or without a stretch at the acceleration limit) with
/// path acceleration `a` and jerk `j`.
fn ramp_with(v: f64, a: f64, j: f64) -> f64 {
    if v >= a * a / j {
        v / a + a / j
    } else {
        2.0 * (v / j).sqrt()
    }
}

/// [`ramp_with`] at the axes' own limits.
fn ramp_time(v: f64) -> f64 {
    ramp_with(v, A, J)
}

/// Time-optimal jerk-limited time of a straight stretch of `length` at feed `v`, from rest
/// to rest, when it is long enough to reach `v`: the ramps are symmetric in time, so each
/// covers `v · t / 2` and loses half its duration against running at `v`.
fn stretch_time(length: f64, v: f64) -> f64 {
    length / v + ramp_time(v)
}

/// Two lines from the origin: `first` at `f1`, then on to `second` at `f2` (mm/s), on a
/// machine with path tolerance `tol`. Returns the run after checking every axis's limits
/// and the distance from the programmed contour, with the closest approach to the corner.
fn corner(first: Pose, f1: f64, second: Pose, f2: f64, tol: f64) -> (Run, f64) {
    let p0 = Pose::xyz(0.0, 0.0, 0.0);
    let ops = vec![
        line(1, p0, first, Feed::Rate(f1)),
        line(2, first, second, Feed::Rate(f2)),
    ];
    let mut cfg = config(limits_xyz(V, A, J));
    cfg.tolerance = tol;
    let r = run(cfg.clone(), p0, ops);
    assert_within_limits(&cfg, &p0, &r.samples, 1.01);
    let mut closest = f64::INFINITY;
    for s in &r.samples {
        let off =
            segment_distance(&s.pose, &p0, &first).min(segment_distance(&s.pose, &first, &second));
        assert!(
            off <= tol + 1e-9,
            "tolerance {tol}: {off} mm off the contour"
        );
        closest = closest.min(linear_distance(&s.pose, &first));
    }
    let end = r.samples.last().expect("samples").pose;
    assert!(linear_distance(&end, &second) < 1e-9);
    (r, closest)
}

/// The stepover: 10 mm along X at F2400, then 1 mm up in Z at F400.
fn stepover(tol: f64) -> (Run, f64) {
    let (corner_at, top) = (Pose::xyz(10.0, 0.0, 0.0), Pose::xyz(10.0, 0.0, 1.0));
    corner(corner_at, 40.0, top, 400.0 / 60.0, tol)
}

/// Time the jerk-limited departure from rest towards `v` with path acceleration `a` and
/// jerk `j` (time-optimal, as in [`ramp_with`]) takes to cover `d` mm, when `v` is reached
/// over more than `d`: the first half of the S-curve covers j·t³/6, the second half is
/// found by bisection.
fn departure_time(d: f64, v: f64, a: f64, j: f64) -> f64 {
    assert!(
        v < a * a / j,
        "only the ramp without a stretch at the acceleration limit"
    );
    let half = (v / j).sqrt();
    let distance = |t: f64| {
        if t <= half {
            j * t.powi(3) / 6.0
        } else {
            let u = t - half;
            let peak = j * half;
            j * half.powi(3) / 6.0 + v / 2.0 * u + peak * u * u / 2.0 - j * u.powi(3) / 6.0
        }
    };
    let (mut lo, mut hi) = (0.0, 2.0 * half);
    assert!(distance(hi) > d);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if distance(mid) < d {
            lo = mid
        } else {
            hi = mid
        }
    }
    hi
}

#[test]
fn a_stepover_in_a_tight_band_overlaps_the_stop_at_the_corner() {
    // In a 0.01 mm band a curvature-continuous blend of the 90° corner allows about 1.3 mm/s
    // (the jerk its curvature causes, v³·dκ/ds); stopping and speeding up again loses less.
    // X brakes and Z starts, so Z may start before X stands still, as long as one of the two
    // is within the band of the corner (the contour check in `corner` holds every sample to
    // it).
    let tol = 0.01;
    let (r, closest) = stepover(tol);
    assert!(
        closest > 1e-3,
        "the path passes {closest} mm from the corner"
    );
    // Stopped at the corner, the fastest motion is the two stretches, each from rest to
    // rest: 10/40 + 0.05 s and 1/6.667 + 0.01633 s.
    let bound = stretch_time(10.0, 40.0) + stretch_time(1.0, 400.0 / 60.0);
    assert!((bound - 0.466330).abs() < 1e-5, "{bound}");
    // The overlap: X's braking covers the last 0.009 mm (the share of the band a blend may
    // use too) in the final jerk phase of its stop (J·t³/6 = 0.009: 8.14 ms), Z's start its
    // first 0.009 mm in 8.15 ms; Z may start that much before X stands still, rounded to
    // whole periods.
    let band = TOLERANCE_SHARE * tol;
    let brake_tail = (6.0 * band / J).cbrt();
    let overlap = brake_tail + departure_time(band, 400.0 / 60.0, A, J);
    assert!((overlap - 0.01629).abs() < 1e-4, "{overlap}");
    assert_saved(&r, bound, overlap);
}

/// Asserts that the run took the time `stop` of stopping at the corner less `overlap`,
/// rounded to whole periods (up to two periods less, one more).
fn assert_saved(r: &Run, stop: f64, overlap: f64) {
    let t = r.samples.last().map_or(0.0, |s| s.t);
    let saved = stop - t;
    assert!(
        saved >= overlap - 0.002 - 1e-9 && saved <= overlap + 0.001,
        "{t} s: {saved} s saved against the exact stop's {stop} s, the overlap allows {overlap} s"
    );
}

#[test]
fn a_lift_after_a_sloped_pass_overlaps_the_stop_sharing_z() {
    // A finishing pass that falls 0.12 mm over 10 mm at F2400, then 1 mm up in Z at F400: Z
    // moves on both sides of the corner. The lift plans with Z's limits lowered by 1.5 times
    // the pass's share of them, so the pass's braking and the lift's start add up within
    // Z's limits (checked by `corner` on the trace) and overlap as at a level pass.
    let tol = 0.01;
    let (corner_at, top) = (Pose::xyz(10.0, 0.0, -0.12), Pose::xyz(10.0, 0.0, 0.88));
    let (r, closest) = corner(corner_at, 40.0, top, 400.0 / 60.0, tol);
    assert!(
        closest > 1e-3,
        "the path passes {closest} mm from the corner"
    );
    // X binds the pass: its path limits are X's over |u_x|; the lift keeps Z's, lowered.
    let length = (100.0f64 + 0.0144).sqrt();
    let (ux, uz) = (10.0 / length, 0.12 / length);
    let (pass_a, pass_j) = (A / ux, J / ux);
    let lowered = 1.0 - 1.5 * uz / ux;
    let (lift_a, lift_j) = (A * lowered, J * lowered);
    let v2 = 400.0 / 60.0;
    let stop =
        length / 40.0 + ramp_with(40.0, pass_a, pass_j) + 1.0 / v2 + ramp_with(v2, lift_a, lift_j);
    // The overlap: the pass's last 0.009 mm in the final jerk phase of its stop, the lift's
    // first 0.009 mm of its S-curve with the lowered limits.
    let band = TOLERANCE_SHARE * tol;
    let brake_tail = (6.0 * band / pass_j).cbrt();
    let overlap = brake_tail + departure_time(band, v2, lift_a, lift_j);
    assert_saved(&r, stop, overlap);
}

#[test]
fn a_line_travelled_back_reaches_its_end_standing_still() {
    // Along X at F2400, then 1 mm back at F400: the path turns back on itself, so the stop
    // is not overlapped and the path reaches the end of the first line standing still.
    let (corner_at, end) = (Pose::xyz(10.0, 0.0, 0.0), Pose::xyz(9.0, 0.0, 0.0));
    let (r, closest) = corner(corner_at, 40.0, end, 400.0 / 60.0, 0.01);
    assert!(
        closest < 1e-6,
        "the path passes {closest} mm from the corner"
    );
    let bound = stretch_time(10.0, 40.0) + stretch_time(1.0, 400.0 / 60.0);
    let t = r.samples.last().map_or(0.0, |s| s.t);
    assert!(
        t >= bound - 1e-9 && t <= bound + 0.002,
        "{t} s against the exact stop's {bound} s"
    );
}

#[test]
fn a_right_angle_in_a_wide_band_keeps_its_blend() {
    // In a 0.5 mm band the blend of a 90° corner between two lines at F600 reaches 2.8 mm
    // into each, and its curvature (about 0.5/mm at most) lets the path cross it at the
    // feed: no time lost, where a stop loses a ramp down and up (10 ms each way).
    let (corner_at, end) = (Pose::xyz(10.0, 0.0, 0.0), Pose::xyz(10.0, 10.0, 0.0));
    let (r, closest) = corner(corner_at, 10.0, end, 10.0, 0.5);
    assert!(
        closest > 0.05,
        "the path passes {closest} mm from the corner"
    );
    let stop = 2.0 * stretch_time(10.0, 10.0);
    let t = r.samples.last().map_or(0.0, |s| s.t);
    assert!(t < stop - 0.01, "{t} s against the exact stop's {stop} s");
}
