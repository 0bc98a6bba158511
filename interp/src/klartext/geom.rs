//! Plane geometry of the Klartext arc blocks: centres, sweeps and tangents.
//!
//! All functions work on 2-D points in the plane of the arc (first, second axis of
//! [`crate::op::Plane::axes`]); angles are in degrees, positive counter-clockwise.

/// A 2-D point or vector.
pub(crate) type P2 = [f64; 2];

/// Difference `a - b`.
pub(crate) fn sub(a: P2, b: P2) -> P2 {
    [a[0] - b[0], a[1] - b[1]]
}

/// Length of a vector.
pub(crate) fn norm(v: P2) -> f64 {
    // plain √(x² + y²): machine coordinates are far from overflow, and it is much faster
    // than `hypot`
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

/// Polar angle of a vector, degrees in (-180, 180].
pub(crate) fn angle(v: P2) -> f64 {
    v[1].atan2(v[0]).to_degrees()
}

/// The point at `radius` and `deg` about `centre`.
pub(crate) fn polar(centre: P2, radius: f64, deg: f64) -> P2 {
    let (s, c) = deg.to_radians().sin_cos();
    [centre[0] + radius * c, centre[1] + radius * s]
}

/// Signed sweep from angle `from` to angle `to` turning counter-clockwise (`ccw`) or clockwise:
/// in (0, 360] or [-360, 0). Equal angles give a full turn.
pub(crate) fn directed_sweep(from: f64, to: f64, ccw: bool) -> f64 {
    let d = (to - from).rem_euclid(360.0);
    if ccw {
        if d == 0.0 { 360.0 } else { d }
    } else if d == 0.0 {
        -360.0
    } else {
        d - 360.0
    }
}

/// Unit tangent at the end of an arc about `centre` ending at `end`, travelling with the sign
/// of `sweep`.
pub(crate) fn arc_end_tangent(centre: P2, end: P2, sweep: f64) -> P2 {
    let r = sub(end, centre);
    let n = norm(r);
    if n == 0.0 {
        return [0.0, 0.0];
    }
    if sweep >= 0.0 {
        [-r[1] / n, r[0] / n]
    } else {
        [r[1] / n, -r[0] / n]
    }
}

/// Centre and signed sweep of a CR arc from `s` to `e` with signed radius `r` (R>0 the arc of
/// at most 180°, R<0 the larger one) and direction `ccw`.
///
/// Returns `Err(chord)` when the chord is longer than 2|R| (beyond a 1e-9 mm rounding slack).
/// The caller rejects `s == e` before.
pub(crate) fn cr_arc(s: P2, e: P2, r: f64, ccw: bool) -> Result<(P2, f64), f64> {
    let c = sub(e, s);
    let chord = norm(c);
    let ra = r.abs();
    if chord > 2.0 * ra + 1e-9 {
        return Err(chord);
    }
    let half = (chord / 2.0).min(ra);
    let h = (ra * ra - half * half).max(0.0).sqrt();
    let left = [-c[1] / chord, c[0] / chord];
    let small = r > 0.0;
    let side = if ccw == small { 1.0 } else { -1.0 };
    let m = [(s[0] + e[0]) / 2.0, (s[1] + e[1]) / 2.0];
    let centre = [m[0] + side * h * left[0], m[1] + side * h * left[1]];
    let alpha = 2.0 * (half / ra).asin().to_degrees();
    let mag = if small { alpha } else { 360.0 - alpha };
    Ok((centre, if ccw { mag } else { -mag }))
}

/// Centre and signed sweep of a CT arc from `s`, tangent to unit direction `t`, ending at `e`.
///
/// Returns `None` when `e` lies on the tangent line (the "arc" would be a straight line).
pub(crate) fn ct_arc(s: P2, t: P2, e: P2) -> Option<(P2, f64)> {
    let c = sub(e, s);
    let len2 = c[0] * c[0] + c[1] * c[1];
    let left = [-t[1], t[0]];
    let lc = left[0] * c[0] + left[1] * c[1];
    if lc.abs() <= 1e-12 * len2.sqrt().max(1.0) {
        return None;
    }
    let k = len2 / (2.0 * lc);
    let centre = [s[0] + k * left[0], s[1] + k * left[1]];
    let r = k.abs();
    let half = (len2.sqrt() / 2.0).min(r);
    let alpha = 2.0 * (half / r).asin().to_degrees();
    let ahead = t[0] * c[0] + t[1] * c[1] >= 0.0;
    let mag = if ahead { alpha } else { 360.0 - alpha };
    Some((centre, if k > 0.0 { mag } else { -mag }))
}
