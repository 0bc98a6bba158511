//! The geometry of the recess turning example programs (`recess_turn_g869.nc` and its
//! offset variant share the FINISHED PART), worked out by hand for the G869 tests.

use klar_interp::Feed;

/// The rapid feed, short for the want lists.
pub const RAPID: Feed = Feed::Rapid;

/// The FINISHED PART contour of the program as (z, x radius) corners.
pub const CONTOUR: [[f64; 2]; 14] = [
    [0.0, 0.0],
    [0.0, 25.0],
    [-20.0, 25.0],
    [-20.0, 15.0],
    [-40.0, 15.0],
    [-40.0, 25.0],
    [-60.0, 25.0],
    [-60.0, 30.0],
    [-70.0, 30.0],
    [-74.0, 22.0],
    [-84.0, 22.0],
    [-88.0, 30.0],
    [-100.0, 30.0],
    [-100.0, 0.0],
];

/// How far the tool (`w` wide, +Z corner at `p`) reaches below the contour: the largest
/// contour height inside its width minus the tool's height (≤ 0 when clear).
pub fn overlap(p: [f64; 2], w: f64) -> f64 {
    let (lo, hi) = (p[0] - w + 1e-9, p[0] - 1e-9);
    let mut worst = f64::NEG_INFINITY;
    for s in CONTOUR.windows(2) {
        let (a, b) = (s[0], s[1]);
        for t in 0..=200 {
            let t = f64::from(t) / 200.0;
            let q = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            if q[0] > lo && q[0] < hi {
                worst = worst.max(q[1] - p[1]);
            }
        }
    }
    worst
}

/// The sloped recess of the program (N7…N9): r30 at Z-70 down to r22 at Z-74, flat to
/// Z-84, up to r30 at Z-88. The highest point between `lo` and `hi`.
pub fn sloped(lo: f64, hi: f64) -> f64 {
    let x = |z: f64| {
        if z >= -74.0 {
            30.0 + 2.0 * (z + 70.0)
        } else if z >= -84.0 {
            22.0
        } else {
            22.0 + 2.0 * (-84.0 - z)
        }
    };
    // piecewise linear: the highest point is at an end or a corner
    [lo, hi, -74.0, -84.0]
        .into_iter()
        .filter(|z| *z >= lo && *z <= hi)
        .map(x)
        .fold(f64::NEG_INFINITY, f64::max)
}
