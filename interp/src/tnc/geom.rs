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

/// A contour element in the plane, as far as a corner rounding needs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Elem {
    /// A straight line.
    Line {
        /// Start point.
        from: P2,
        /// End point.
        to: P2,
    },
    /// An arc about `centre` with signed sweep (degrees, positive counter-clockwise).
    Arc {
        /// Start point.
        from: P2,
        /// End point.
        to: P2,
        /// Centre.
        centre: P2,
        /// Signed sweep in degrees.
        sweep: f64,
    },
}

/// A rounding arc between two elements: where it touches them and how much of them is kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Fillet {
    /// Centre of the rounding arc.
    pub centre: P2,
    /// Tangent point on the first element (its new end).
    pub t1: P2,
    /// Tangent point on the second element (its new start).
    pub t2: P2,
    /// Signed sweep of the rounding arc, degrees.
    pub sweep: f64,
    /// Part of the first element kept, 0..1 (of its length or sweep).
    pub keep1: f64,
    /// Part of the second element cut off at its start, 0..1.
    pub cut2: f64,
}

/// Why no rounding arc fits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum FilletError {
    /// The elements meet tangentially (or reverse): there is no corner to round.
    NoCorner,
    /// The radius is too large for the neighbouring elements.
    TooLarge,
}

fn dot(a: P2, b: P2) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

fn cross(a: P2, b: P2) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Tolerance (mm, and as a fraction) for points that lie on an element's end.
const ON_ELEMENT: f64 = 1e-9;

impl Elem {
    /// Unit direction of travel at the start (`end` false) or the end (`end` true).
    pub fn tangent(&self, end: bool) -> P2 {
        match *self {
            Elem::Line { from, to } => {
                let d = sub(to, from);
                let n = norm(d);
                if n == 0.0 {
                    [0.0, 0.0]
                } else {
                    [d[0] / n, d[1] / n]
                }
            }
            Elem::Arc {
                from,
                to,
                centre,
                sweep,
            } => arc_end_tangent(centre, if end { to } else { from }, sweep),
        }
    }

    /// The element moved `d` to the left of its direction of travel (an arc becomes a
    /// concentric circle): line (point, direction) or circle (centre, radius).
    fn offset(&self, d: f64) -> Result<Curve, FilletError> {
        match *self {
            Elem::Line { from, .. } => {
                let t = self.tangent(false);
                Ok(Curve::Line([from[0] - t[1] * d, from[1] + t[0] * d], t))
            }
            Elem::Arc {
                from,
                centre,
                sweep,
                ..
            } => {
                let r = norm(sub(from, centre));
                // left of counter-clockwise travel is towards the centre
                let rho = if sweep >= 0.0 { r - d } else { r + d };
                if rho <= ON_ELEMENT {
                    return Err(FilletError::TooLarge);
                }
                Ok(Curve::Circle(centre, rho))
            }
        }
    }

    /// The point of the element nearest to `m` (the tangent point of a circle about `m`).
    fn foot(&self, m: P2) -> P2 {
        match *self {
            Elem::Line { from, .. } => {
                let t = self.tangent(false);
                let s = dot(sub(m, from), t);
                [from[0] + s * t[0], from[1] + s * t[1]]
            }
            Elem::Arc { from, centre, .. } => {
                let r = norm(sub(from, centre));
                let v = sub(m, centre);
                let n = norm(v);
                if n == 0.0 {
                    return from;
                }
                [centre[0] + v[0] * r / n, centre[1] + v[1] * r / n]
            }
        }
    }

    /// Where `p` (a point on the element's line or circle) lies along the element, as a
    /// fraction from the start (0) to the end (1).
    fn fraction(&self, p: P2) -> f64 {
        match *self {
            Elem::Line { from, to } => {
                let d = sub(to, from);
                let l2 = dot(d, d);
                if l2 == 0.0 {
                    0.0
                } else {
                    dot(sub(p, from), d) / l2
                }
            }
            Elem::Arc {
                from,
                centre,
                sweep,
                ..
            } => {
                if sweep == 0.0 {
                    return 0.0;
                }
                let a0 = angle(sub(from, centre));
                let a = angle(sub(p, centre));
                let turned = if sweep > 0.0 { a - a0 } else { a0 - a };
                let mut phi = turned.rem_euclid(360.0);
                // a point just before the start counts as the start, not as a full turn
                if phi > 360.0 - 1e-7 {
                    phi = 0.0;
                }
                phi / sweep.abs()
            }
        }
    }
}

/// An offset curve: a line (point, unit direction) or a circle (centre, radius).
#[derive(Debug, Clone, Copy)]
enum Curve {
    Line(P2, P2),
    Circle(P2, f64),
}

/// Intersections of two offset curves (up to two points).
fn intersect(a: Curve, b: Curve) -> Vec<P2> {
    match (a, b) {
        (Curve::Line(p, u), Curve::Line(q, v)) => {
            let den = cross(u, v);
            if den.abs() < 1e-12 {
                return Vec::new();
            }
            let s = cross(sub(q, p), v) / den;
            vec![[p[0] + s * u[0], p[1] + s * u[1]]]
        }
        (Curve::Line(p, u), Curve::Circle(c, r)) | (Curve::Circle(c, r), Curve::Line(p, u)) => {
            // |p + s u - c| = r, u a unit vector
            let w = sub(p, c);
            let b = dot(w, u);
            let disc = b * b - (dot(w, w) - r * r);
            if disc < 0.0 {
                return Vec::new();
            }
            let h = disc.sqrt();
            [-b - h, -b + h]
                .iter()
                .map(|s| [p[0] + s * u[0], p[1] + s * u[1]])
                .collect()
        }
        (Curve::Circle(c1, r1), Curve::Circle(c2, r2)) => {
            let d = sub(c2, c1);
            let l = norm(d);
            if l < 1e-12 || l > r1 + r2 || l < (r1 - r2).abs() {
                return Vec::new();
            }
            let a = (r1 * r1 - r2 * r2 + l * l) / (2.0 * l);
            let h = (r1 * r1 - a * a).max(0.0).sqrt();
            let m = [c1[0] + a * d[0] / l, c1[1] + a * d[1] / l];
            let n = [-d[1] / l, d[0] / l];
            vec![
                [m[0] + h * n[0], m[1] + h * n[1]],
                [m[0] - h * n[0], m[1] - h * n[1]],
            ]
        }
    }
}

/// The rounding arc of radius `r` between `e1` and `e2`, which meet at the end of `e1`:
/// tangent to both, on the inside of the corner. Its centre lies at distance `r` from both
/// elements (on the offset curves); of the offset intersections the one nearest to the
/// corner is taken, and both tangent points must lie on the elements.
pub(crate) fn fillet(e1: &Elem, e2: &Elem, r: f64) -> Result<Fillet, FilletError> {
    let (t1, t2) = (e1.tangent(true), e2.tangent(false));
    let turn = cross(t1, t2);
    if turn.abs() < 1e-9 {
        return Err(FilletError::NoCorner);
    }
    // the rounding centre lies on the side the contour turns to
    let side = turn.signum();
    let corner = match *e1 {
        Elem::Line { to, .. } | Elem::Arc { to, .. } => to,
    };
    let (o1, o2) = (e1.offset(side * r)?, e2.offset(side * r)?);
    let centre = intersect(o1, o2)
        .into_iter()
        .min_by(|a, b| norm(sub(*a, corner)).total_cmp(&norm(sub(*b, corner))))
        .ok_or(FilletError::TooLarge)?;
    let p1 = e1.foot(centre);
    let p2 = e2.foot(centre);
    let keep1 = e1.fraction(p1);
    let cut2 = e2.fraction(p2);
    let ok = |f: f64| (-ON_ELEMENT..=1.0 + ON_ELEMENT).contains(&f);
    if !ok(keep1) || !ok(cut2) {
        return Err(FilletError::TooLarge);
    }
    let sweep = directed_sweep(angle(sub(p1, centre)), angle(sub(p2, centre)), side > 0.0);
    // a rounding turns by less than a half circle; more means the centre is on the far side
    if sweep.abs() >= 180.0 {
        return Err(FilletError::TooLarge);
    }
    Ok(Fillet {
        centre,
        t1: p1,
        t2: p2,
        sweep,
        keep1: keep1.clamp(0.0, 1.0),
        cut2: cut2.clamp(0.0, 1.0),
    })
}
