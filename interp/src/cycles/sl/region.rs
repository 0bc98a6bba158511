//! The machining region of the SL cycles: contours flattened to polygons, sorted into
//! pockets and islands, with the distance and inside tests the tool paths need.

use super::super::pocket::geom::EPS;
use super::super::{Contour, ContourSeg};
use std::f64::consts::TAU;

/// Largest distance between an arc and the chords that replace it, mm. Clearances are
/// widened by this much so that the tool keeps its distance from the true arc.
pub(super) const CHORD_TOL: f64 = 1e-3;

/// A closed polygon (last point joins the first).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Poly {
    /// Corners.
    pub pts: Vec<[f64; 2]>,
}

impl Poly {
    /// Twice the signed area (positive counter-clockwise).
    pub fn area2(&self) -> f64 {
        let n = self.pts.len();
        (0..n)
            .map(|i| {
                let (a, b) = (self.pts[i], self.pts[(i + 1) % n]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum()
    }

    /// Edges as point pairs.
    pub fn edges(&self) -> impl Iterator<Item = ([f64; 2], [f64; 2])> + '_ {
        let n = self.pts.len();
        (0..n).map(move |i| (self.pts[i], self.pts[(i + 1) % n]))
    }
}

/// Pockets and islands.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Region {
    /// Areas to clear.
    pub pockets: Vec<Poly>,
    /// Areas to leave standing.
    pub islands: Vec<Poly>,
}

/// Why contours cannot be turned into a region.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum RegionError {
    /// No contour at all.
    Empty,
    /// Contour `n` (0-based) encloses no area.
    Degenerate(usize),
    /// Contour `n` has an arc whose end does not lie on its circle.
    BadArc(usize),
}

/// Flattens `contours` and sorts them: a contour is a pocket when its radius
/// compensation puts the tool inside it — running counter-clockwise with RL or clockwise
/// with RR — and an island otherwise. Without compensation (R0) the first contour is the
/// pocket and the others are islands.
pub(super) fn build(contours: &[Contour]) -> Result<Region, RegionError> {
    if contours.is_empty() {
        return Err(RegionError::Empty);
    }
    let mut region = Region {
        pockets: Vec::new(),
        islands: Vec::new(),
    };
    for (i, c) in contours.iter().enumerate() {
        let poly = flatten(c).ok_or(RegionError::BadArc(i))?;
        let a2 = poly.area2();
        if poly.pts.len() < 3 || a2.abs() < 1e-9 || !a2.is_finite() {
            return Err(RegionError::Degenerate(i));
        }
        let pocket = match c.left {
            Some(left) => left == (a2 > 0.0),
            None => i == 0,
        };
        if pocket {
            region.pockets.push(poly);
        } else {
            region.islands.push(poly);
        }
    }
    Ok(region)
}

/// The contour as a polygon, arcs replaced by chords within [`CHORD_TOL`]; `None` for an
/// arc whose ends lie at different distances from its centre.
fn flatten(c: &Contour) -> Option<Poly> {
    let mut pts = vec![c.start];
    let mut cur = c.start;
    for seg in &c.segs {
        match *seg {
            ContourSeg::Line { to } => pts.push(to),
            ContourSeg::Arc { to, centre, ccw } => {
                let r = (cur[0] - centre[0]).hypot(cur[1] - centre[1]);
                let r1 = (to[0] - centre[0]).hypot(to[1] - centre[1]);
                if (r - r1).abs() > 1e-3 * r.max(1.0) || !r.is_finite() {
                    return None;
                }
                let a0 = (cur[1] - centre[1]).atan2(cur[0] - centre[0]);
                let a1 = (to[1] - centre[1]).atan2(to[0] - centre[0]);
                let mut sweep = if ccw {
                    (a1 - a0).rem_euclid(TAU)
                } else {
                    -(a0 - a1).rem_euclid(TAU)
                };
                if sweep.abs() < 1e-12 {
                    sweep = if ccw { TAU } else { -TAU };
                }
                // Chord angle with sagitta r (1 − cos(θ/2)) ≤ tolerance.
                let max_angle = if r > CHORD_TOL {
                    2.0 * (1.0 - CHORD_TOL / r).acos()
                } else {
                    TAU
                };
                let n = (sweep.abs() / max_angle.max(1e-3))
                    .ceil()
                    .clamp(1.0, 100_000.0);
                // n is a small positive whole number.
                let count = n as usize;
                for k in 1..count {
                    let a = a0 + sweep * k as f64 / n;
                    pts.push([centre[0] + r * a.cos(), centre[1] + r * a.sin()]);
                }
                pts.push(to);
            }
        }
        cur = to_of(seg);
    }
    // The contour closes itself: drop a last point equal to the first, and repeats.
    pts.dedup_by(|a, b| (a[0] - b[0]).hypot(a[1] - b[1]) < EPS);
    if pts.len() > 1
        && pts
            .first()
            .zip(pts.last())
            .is_some_and(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]) < EPS)
    {
        pts.pop();
    }
    Some(Poly { pts })
}

/// End point of a contour element.
fn to_of(seg: &ContourSeg) -> [f64; 2] {
    match *seg {
        ContourSeg::Line { to } | ContourSeg::Arc { to, .. } => to,
    }
}

/// Distance from `p` to the segment `a`–`b`.
pub(super) fn dist_point_seg(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// Distance between the segments `p`–`q` and `a`–`b` (0 when they cross).
pub(super) fn dist_seg_seg(p: [f64; 2], q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let cross = |o: [f64; 2], u: [f64; 2], v: [f64; 2]| {
        (u[0] - o[0]) * (v[1] - o[1]) - (u[1] - o[1]) * (v[0] - o[0])
    };
    let (d1, d2) = (cross(p, q, a), cross(p, q, b));
    let (d3, d4) = (cross(a, b, p), cross(a, b, q));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return 0.0;
    }
    dist_point_seg(p, a, b)
        .min(dist_point_seg(q, a, b))
        .min(dist_point_seg(a, p, q))
        .min(dist_point_seg(b, p, q))
}
