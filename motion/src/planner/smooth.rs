//! Split points of dense code, placed on a curve fitted to the polyline around them.
//!
//! CAM systems print chord end points rounded, to 1 µm or 0.1 µm. On chords of 0.01–0.1 mm
//! that rounding turns a chord's direction by up to a tenth of a radian, far more than the
//! polyline turns from one chord to the next, so the curvature estimated from the two
//! neighbouring directions alone is mostly noise. Blends through such estimates wiggle,
//! their curvature and its rate of change are large, and their limits hold the path to a
//! crawl (an R25 circle in 0.01 mm chords at a quarter of its feed and less).
//!
//! So a split point is taken from a least-squares fit instead: each axis as a quadratic in
//! the path distance along the polyline, over the vertices within [`SPAN`] on either side
//! of the line's midpoint (at most [`LOOK`] a side), stopping at a vertex
//! where the polyline turns more than a split point allows (a real corner) or where the
//! chords taken would turn by more than a quadratic follows (`FIT_ARC`). The fit's
//! position, unit tangent and curvature vector at the midpoint make the split point. The
//! noise of a fit falls with the square of its span: over 0.5 mm a rounding of 1 µm leaves a
//! curvature error of a few thousandths per mm. The fitted point may lie off the line by at
//! most half the tolerance (`SHIFT`: a curve through the vertices of 0.3 mm chords round a
//! 4 mm radius passes 2.8 µm from their midpoints), and the blends through it are checked
//! against the tolerance band like any other blend.

use crate::geom::{Line, Metric, PathPoint};
use klar_interp::Pose;

/// Path distance (mm) the fit reaches on either side of a split point.
pub const SPAN: f64 = 0.5;

/// Vertices a side the fit takes at least where they lie within [`SPAN_MAX`] (sparser
/// chords: the span grows until enough rounding errors average out).
pub const MIN_SIDE: usize = 12;

/// Path distance (mm) the fit reaches at most on either side.
pub const SPAN_MAX: f64 = 2.0;

/// Largest angle (radians) the polyline may turn between the line and a chord the fit
/// takes: a quadratic follows a curve closely only while it turns little.
const FIT_TURN: f64 = 0.15;

/// Largest angle (radians) the polyline may turn between the line and any chord the fit
/// takes, within the span too: round a tight arc (0.1 mm chords on R0.3, turning by a
/// third of a radian each) the span of 0.5 mm holds most of a turn, which no quadratic
/// follows; over ±0.3 rad one does to a fraction of a micrometre (r·θ³/6).
const FIT_ARC: f64 = 0.6;

/// Vertices a side the fit uses at most, which bounds the work per split point.
pub const LOOK: usize = 96;

/// Largest distance of the fitted point from the line's midpoint, as a share of the
/// tolerance.
const SHIFT: f64 = 0.5;

/// The polyline vertices around a line that may become a split point, in path order.
#[derive(Debug, Clone, Copy)]
pub struct Stencil<'a> {
    /// Vertices up to the line's start (the last one).
    pub behind: &'a [Pose],
    /// Vertices from the line's end (the first one) on.
    pub ahead: &'a [Pose],
}

/// Running sums of the least-squares fit `q(s) = c₀ + c₁·s + c₂·s²` per axis, with `s`
/// scaled by `scale` to keep the normal equations well conditioned.
struct Sums {
    scale: f64,
    n: f64,
    s: [f64; 5],
    q: [[f64; 3]; 9],
}

impl Sums {
    fn new(scale: f64) -> Sums {
        Sums {
            scale,
            n: 0.0,
            s: [0.0; 5],
            q: [[0.0; 3]; 9],
        }
    }

    /// Adds vertex `p` (relative to the centre) at path distance `s` from it.
    fn add(&mut self, s: f64, p: &[f64; 9]) {
        let u = s / self.scale;
        let mut w = 1.0;
        for k in self.s.iter_mut() {
            *k += w;
            w *= u;
        }
        for (q, x) in self.q.iter_mut().zip(p) {
            q[0] += x;
            q[1] += x * u;
            q[2] += x * u * u;
        }
        self.n += 1.0;
    }

    /// Coefficients (0, c₁, c₂) per axis of the quadratic through the centre itself
    /// (c₀ = 0), in the unscaled distance; `None` when the vertices do not determine it.
    fn solve_through(&self) -> Option<[[f64; 3]; 9]> {
        if self.n < 2.0 {
            return None;
        }
        let [_, _, s2, s3, s4] = self.s;
        let det = s2 * s4 - s3 * s3;
        if !(det.is_finite() && det > 1e-12 * s2 * s4) {
            return None;
        }
        let mut out = [[0.0; 3]; 9];
        for (o, q) in out.iter_mut().zip(&self.q) {
            let c1 = (s4 * q[1] - s3 * q[2]) / det;
            let c2 = (s2 * q[2] - s3 * q[1]) / det;
            *o = [0.0, c1 / self.scale, c2 / (self.scale * self.scale)];
        }
        Some(out)
    }

    /// Coefficients (c₀, c₁, c₂) per axis in the unscaled distance; `None` when the
    /// vertices do not determine a quadratic.
    fn solve(&self) -> Option<[[f64; 3]; 9]> {
        if self.n < 3.0 {
            return None;
        }
        let [s0, s1, s2, s3, s4] = self.s;
        // The inverse of the symmetric matrix [[s0 s1 s2] [s1 s2 s3] [s2 s3 s4]] by
        // cofactors.
        let a00 = s2 * s4 - s3 * s3;
        let a01 = s2 * s3 - s1 * s4;
        let a02 = s1 * s3 - s2 * s2;
        let a11 = s0 * s4 - s2 * s2;
        let a12 = s1 * s2 - s0 * s3;
        let a22 = s0 * s2 - s1 * s1;
        let det = s0 * a00 + s1 * a01 + s2 * a02;
        if !(det.is_finite() && det > 1e-12 * s0 * s2 * s4) {
            return None;
        }
        let mut out = [[0.0; 3]; 9];
        for (o, q) in out.iter_mut().zip(&self.q) {
            let c0 = (a00 * q[0] + a01 * q[1] + a02 * q[2]) / det;
            let c1 = (a01 * q[0] + a11 * q[1] + a12 * q[2]) / det;
            let c2 = (a02 * q[0] + a12 * q[1] + a22 * q[2]) / det;
            *o = [c0, c1 / self.scale, c2 / (self.scale * self.scale)];
        }
        Some(out)
    }
}

/// The vertices on one side of the midpoint, nearest first: path distance from the
/// midpoint (positive) and offset from `centre`, up to [`SPAN`] and up to a turn sharper than
/// `max_turn` (radians); `first_dir` is the direction of the line itself, pointing away
/// from the midpoint towards this side.
fn side<'a>(
    vertices: impl Iterator<Item = &'a Pose> + 'a,
    half: f64,
    first_dir: [f64; 9],
    centre: &Pose,
    max_turn: f64,
) -> impl Iterator<Item = (f64, [f64; 9])> + 'a {
    let m = Metric::Linear;
    let centre = *centre;
    let mut prev: Option<Pose> = None;
    let mut dir = first_dir;
    let mut s = half;
    let mut count = 0;
    let cos_max = max_turn.cos();
    let cos_fit = (0.5 * FIT_TURN).cos();
    let cos_arc = (0.5 * FIT_ARC).cos();
    vertices.take(LOOK).map_while(move |v| {
        if let Some(p) = prev {
            let mut d = [0.0; 9];
            for ((d, a), b) in d.iter_mut().zip(&p.0).zip(&v.0) {
                *d = b - a;
            }
            let len = m.norm(&d);
            if !(len > 0.0 && len.is_finite()) {
                return None;
            }
            let d = d.map(|x| x / len);
            if m.dot(&d, &dir) < cos_max {
                return None;
            }
            s += len;
            dir = d;
        }
        let mut off = [0.0; 9];
        for ((o, a), b) in off.iter_mut().zip(&v.0).zip(&centre.0) {
            *o = a - b;
        }
        if prev.is_some() {
            // Only while the polyline turns little (the secant from the centre turns by
            // half the curve), and beyond the span only while too few vertices were taken.
            let secant = m.dot(&off, &first_dir) / m.norm(&off).max(f64::MIN_POSITIVE);
            if secant < cos_arc
                || s > SPAN && (count >= MIN_SIDE || s > SPAN_MAX || secant < cos_fit)
            {
                return None;
            }
        }
        count += 1;
        prev = Some(*v);
        Some((s, off))
    })
}

/// The split point at the midpoint of `mid` fitted to the vertices of `stencil` (see the
/// module documentation); `None` when they do not determine one or it lies too far from
/// the line for tolerance `tol`.
pub fn split_point(
    mid: &Line,
    stencil: &Stencil<'_>,
    tol: f64,
    max_turn: f64,
) -> Option<PathPoint> {
    let m = Metric::Linear;
    let half = 0.5 * mid.length();
    let here = mid.point(half);
    let dir = here.d1;
    let back = dir.map(|x| -x);
    let mut sums = Sums::new(SPAN);
    let mut sides = 0;
    for (s, off) in side(
        stencil.behind.iter().rev(),
        half,
        back,
        &here.pose,
        max_turn,
    ) {
        sums.add(-s, &off);
        sides |= 1;
    }
    for (s, off) in side(stencil.ahead.iter(), half, dir, &here.pose, max_turn) {
        sums.add(s, &off);
        sides |= 2;
    }
    if sides != 3 {
        return None;
    }
    let c = sums.solve()?;
    let shift = m.norm(&c.map(|x| x[0]));
    if shift > SHIFT * tol {
        return None;
    }
    point_of(&here.pose, &c)
}

/// The split point a run of dense code starts at (`at_end` false) or ends at (true) where
/// the path stands still: the start or end of `line` exactly, with the tangent and curvature
/// vector of the quadratic through it fitted to the vertices on the line's side (from the
/// line's far end on, `stencil.ahead` for a start, `stencil.behind` for an end). At rest
/// the direction may change, so the path can leave or reach the point on the fitted curve.
pub fn end_point(
    line: &Line,
    at_end: bool,
    stencil: &Stencil<'_>,
    max_turn: f64,
) -> Option<PathPoint> {
    let len = line.length();
    let here = line.point(if at_end { len } else { 0.0 });
    let dir = here.d1;
    let mut sums = Sums::new(SPAN);
    if at_end {
        let back = dir.map(|x| -x);
        for (s, off) in side(stencil.behind.iter().rev(), len, back, &here.pose, max_turn) {
            sums.add(-s, &off);
        }
    } else {
        for (s, off) in side(stencil.ahead.iter(), len, dir, &here.pose, max_turn) {
            sums.add(s, &off);
        }
    }
    point_of(&here.pose, &sums.solve_through()?)
}

/// The point `centre + c₀` with the unit tangent and curvature vector of the fitted
/// quadratic (coefficients `c` per axis) there.
fn point_of(centre: &Pose, c: &[[f64; 3]; 9]) -> Option<PathPoint> {
    let m = Metric::Linear;
    let mut pose = *centre;
    let mut t = [0.0; 9];
    let mut k = [0.0; 9];
    for i in 0..9 {
        pose.0[i] += c[i][0];
        t[i] = c[i][1];
        k[i] = 2.0 * c[i][2];
    }
    let speed = m.norm(&t);
    if !(speed > 0.5 && speed.is_finite()) {
        return None;
    }
    let d1 = t.map(|x| x / speed);
    // The second derivative with respect to the path distance of the fitted curve itself:
    // the part of q″ across the tangent, over |q′|².
    let along = m.dot(&k, &d1);
    let mut d2 = [0.0; 9];
    for ((o, x), u) in d2.iter_mut().zip(&k).zip(&d1) {
        *o = (x - along * u) / (speed * speed);
    }
    let finite = pose.0.iter().chain(&d1).chain(&d2).all(|x| x.is_finite());
    finite.then_some(PathPoint { pose, d1, d2 })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn on_circle(r: f64, phi: f64, round: f64) -> Pose {
        let q = |x: f64| (x / round).round() * round;
        Pose::xyz(q(r * phi.cos()), q(r * phi.sin()), 0.0)
    }

    /// The split point of the chord from `pts[mid]` to `pts[mid + 1]` with all of `pts`
    /// around it (tolerance 0.01 mm, turns up to 0.3 rad).
    fn split_at(pts: &[Pose], mid: usize) -> PathPoint {
        let Ok(Some(line)) = Line::new(pts[mid], pts[mid + 1]) else {
            panic!("a chord is a line")
        };
        let stencil = Stencil {
            behind: &pts[..=mid],
            ahead: &pts[mid + 1..],
        };
        let Some(p) = split_point(&line, &stencil, 0.01, 0.3) else {
            panic!("a split point")
        };
        p
    }

    #[test]
    fn a_rounded_circle_gives_its_curvature_tangent_and_radius_back() {
        // R25 in 0.01 mm chords rounded to 1 µm: each chord's direction is off by up to
        // 0.1 rad. The fit over 2 × 50 vertices within 0.5 mm has a curvature error of
        // σ ≈ 0.29 µm · 2 / (√100 · 0.5² · 0.3) ≈ 0.8e-3 per mm; 3σ allowed.
        let (r, step) = (25.0, 0.01 / 25.0);
        let pts: Vec<Pose> = (-80..=80)
            .map(|k| on_circle(r, k as f64 * step, 1e-3))
            .collect();
        let mid = 80;
        let p = split_at(&pts, mid);
        let m = Metric::Linear;
        let kappa = m.norm(&p.d2);
        assert!((kappa - 1.0 / r).abs() < 2.5e-3, "curvature {kappa}");
        // The curvature vector points at the centre, the tangent along the circle.
        let radial = p.pose.0[0].hypot(p.pose.0[1]);
        assert!((radial - r).abs() < 1e-3, "{radial}");
        let inward = -(p.d2[0] * p.pose.0[0] + p.d2[1] * p.pose.0[1]) / (kappa * radial);
        assert!(inward > 0.999, "{inward}");
        let across = (p.d1[0] * p.pose.0[0] + p.d1[1] * p.pose.0[1]) / radial;
        assert!(across.abs() < 2e-3, "{across}");
    }

    #[test]
    fn the_fit_stops_at_a_corner() {
        // A straight run into a 90° corner 0.05 mm ahead: the vertices beyond the corner
        // do not bend the split point (it stays on the straight line with no curvature).
        let mut pts: Vec<Pose> = (-30..=5)
            .map(|k| Pose::xyz(k as f64 * 0.01, 0.0, 0.0))
            .collect();
        pts.extend((1..=30).map(|k| Pose::xyz(0.05, k as f64 * 0.01, 0.0)));
        let mid = 30;
        let p = split_at(&pts, mid);
        assert!(Metric::Linear.norm(&p.d2) < 1e-9);
        assert!(p.pose.0[1].abs() < 1e-12 && (p.d1[0] - 1.0).abs() < 1e-12);
    }
}
