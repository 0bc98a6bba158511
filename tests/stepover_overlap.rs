//! A stepover as parallel finishing writes it, run through `klar run` on the bench machine
//! (X Y Z 100 mm/s, 1000 mm/s², 1e5 mm/s³, tolerance 0.01 mm): its four sharp corners are
//! crossed with the next move starting while the last one brakes. Judged from the trace
//! against the programmed polyline, the axis limits and the closed-form time of stopping
//! at every corner.

mod common;

use common::*;
use klar::config::MachineConfig;

const PROGRAM: &str = "BEGIN PGM STEP MM
L X+10 F2400
L Z+1 F400
L Y+1
L Z+0
L X+0 F2400
END PGM STEP MM
";

/// The corners of the path, from the start at the origin.
const POLYLINE: [[f64; 3]; 6] = [
    [0.0, 0.0, 0.0],
    [10.0, 0.0, 0.0],
    [10.0, 0.0, 1.0],
    [10.0, 1.0, 1.0],
    [10.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
];

const A: f64 = 1000.0;
const J: f64 = 1e5;

/// Distance from `p` to the segment from `a` to `b`.
fn to_segment(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let ab: Vec<f64> = (0..3).map(|i| b[i] - a[i]).collect();
    let ap: Vec<f64> = (0..3).map(|i| p[i] - a[i]).collect();
    let ab2: f64 = ab.iter().map(|x| x * x).sum();
    let t = (ap.iter().zip(&ab).map(|(x, y)| x * y).sum::<f64>() / ab2).clamp(0.0, 1.0);
    (0..3)
        .map(|i| (ap[i] - t * ab[i]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Distance between two points.
fn dist(p: [f64; 3], q: [f64; 3]) -> f64 {
    (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f64>().sqrt()
}

/// Time of a straight stretch of `length` at feed `v` from rest to rest, long enough to
/// reach `v` (the jerk-limited ramps are symmetric in time and each loses half of its
/// duration against running at `v`).
fn stretch(length: f64, v: f64) -> f64 {
    let ramp = if v >= A * A / J {
        v / A + A / J
    } else {
        2.0 * (v / J).sqrt()
    };
    length / v + ramp
}

#[test]
fn a_stepover_crosses_its_corners_within_the_band_and_the_limits() {
    let machine = MachineConfig::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("bench/machine-jerk-1e5.toml"),
    )
    .expect("the bench machine");
    let path = temp_program("stepover.h", PROGRAM);
    let (result, trace) = run(&path, &machine);
    result.unwrap_or_else(|f| panic!("{}", f.error));
    assert_within_limits(&trace, &machine);
    let cols = commanded(&trace, &["X", "Y", "Z"]);
    let n = cols[0].len();
    let mut worst = 0.0f64;
    let mut closest = [f64::INFINITY; 4];
    for ((x, y), z) in cols[0].iter().zip(&cols[1]).zip(&cols[2]) {
        let p = [*x, *y, *z];
        let off = POLYLINE
            .windows(2)
            .map(|w| to_segment(p, w[0], w[1]))
            .fold(f64::INFINITY, f64::min);
        worst = worst.max(off);
        for (c, corner) in closest.iter_mut().zip(&POLYLINE[1..5]) {
            *c = c.min(dist(p, *corner));
        }
    }
    assert!(worst <= 0.01, "{worst} mm off the programmed path");
    // No corner is stood on: each is cut within the band.
    for (k, c) in closest.iter().enumerate() {
        assert!(*c > 1e-3, "corner {}: passed {c} mm from it", k + 1);
    }
    let end = [cols[0][n - 1], cols[1][n - 1], cols[2][n - 1]];
    assert!(dist(end, POLYLINE[5]) < 1e-9, "{end:?}");
    // Stopping at every corner takes each stretch from rest to rest: 10 mm at 40 mm/s
    // twice, 1 mm at 6.667 mm/s three times. Each corner saves the time the braking takes
    // over its last 0.009 mm (the share of the band a blend may use too) plus the time the
    // next move takes over its first: 8.14 ms each, the last part of a braking and the
    // first of a start both in a jerk phase (J·t³/6) at these speeds.
    let f400 = 400.0 / 60.0;
    let stop = 2.0 * stretch(10.0, 40.0) + 3.0 * stretch(1.0, f400);
    let phase = (6.0 * 0.009 / J).cbrt();
    assert!(J * (f400 / J).sqrt().powi(3) / 6.0 > 0.009);
    let saved = 4.0 * 2.0 * phase;
    let t = trace.t[n - 1];
    assert!(
        t <= stop - saved + 0.004 && t >= stop - saved - 0.008,
        "{t} s against {stop} s standing at each corner less {saved} s"
    );
}
