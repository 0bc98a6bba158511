//! Building one blend and proving it stays inside the tolerance band.
//!
//! The blend's distance from the programmed contour near the corner (the parts of the two
//! elements the blend replaces) must stay below [`TOLERANCE_SHARE`] of the tolerance. First
//! a bound over the whole curve is tried: the curve lies in the convex hull of its Bézier
//! control points, so their distances from the contour bound the curve's (see
//! `hull_deviation`). Where that bound is too coarse, the blend is sampled at
//! [`DEVIATION_SAMPLES`] interior points instead: distances to a line part are exact; to an
//! arc, helix or spline part they are taken to a fine polyline through it plus the largest
//! sagitta of that polyline, which can only overstate the distance.

use super::{BoundsMemo, Quintic};
use crate::geom::{Metric, PathPoint, Segment};
use klar_interp::Pose;

/// Interior sample points at which a blend's deviation is measured.
pub const DEVIATION_SAMPLES: usize = 32;

/// Share of the tolerance a blend may use (where it is sampled, the rest covers the curve
/// between samples).
pub const TOLERANCE_SHARE: f64 = 0.9;

/// Chords per curved contour part when measuring distances to it.
const CURVE_CHORDS: usize = 32;

/// A stretch `[from, to]` (path distance) of a programmed element.
#[derive(Debug, Clone, Copy)]
pub struct ContourPart<'a> {
    /// The element.
    pub segment: &'a Segment,
    /// Start of the stretch.
    pub from: f64,
    /// End of the stretch.
    pub to: f64,
}

/// The blend from `start` to `end` (poses with unit tangents and curvature vectors) if it
/// keeps within `tolerance` of `contour`; with its largest deviation (a bound of it where the
/// control points decided, the largest sampled one where the samples did). The curve's
/// derivative bounds come from `memo` where a blend with the same derivatives was bounded
/// before.
pub fn blend_within(
    start: &PathPoint,
    end: &PathPoint,
    contour: &[ContourPart<'_>],
    tolerance: f64,
    memo: &mut BoundsMemo,
) -> Option<(Quintic, f64)> {
    // The tolerance check needs only the curve's shape; the rest is computed once it passes.
    let mut curve = Quintic::shape(start, end)?;
    let limit = TOLERANCE_SHARE * tolerance;
    let worst = match hull_deviation(&curve, contour, limit) {
        Some(w) => w,
        None => sampled_deviation(&curve, contour, limit)?,
    };
    curve.finish(memo)?;
    Some((curve, worst))
}

/// Halvings of the curve at most in [`hull_deviation`].
const HULL_DEPTH: u32 = 2;

/// Contour parts [`hull_deviation`] handles (more go to the samples).
const HULL_PARTS: usize = 4;

/// A bound of the curve's largest distance from `contour` if it is at most `limit`.
///
/// The curve lies in the convex hull of its control points. The distance from a straight
/// chord is a convex function of the point, so over the hull it is largest at a control
/// point. Every point of a part's chord lies within the part's sagitta κ·L²/8 of the part
/// (κ its curvature bound, L its length; 0 for a line), so a (piece of the) curve whose
/// control points all lie within `limit − sagitta` of one part's chord lies within `limit`
/// of the contour. Pieces that fail are halved (de Casteljau) up
/// to [`HULL_DEPTH`] times; `None` when one still fails.
fn hull_deviation(curve: &Quintic, contour: &[ContourPart<'_>], limit: f64) -> Option<f64> {
    if contour.is_empty() || contour.len() > HULL_PARTS {
        return None;
    }
    let mut chords = [Chord::default(); HULL_PARTS];
    for (chord, part) in chords.iter_mut().zip(contour) {
        let (a, b) = (part.from.min(part.to), part.from.max(part.to));
        let sagitta = match part.segment {
            Segment::Line(_) => 0.0,
            seg => (b - a) * (b - a) * Metric::Linear.norm(&seg.bounds().d2) / 8.0,
        };
        *chord = Chord::new(
            &part.segment.position(a),
            &part.segment.position(b),
            sagitta,
        );
    }
    let chords = chords.get(..contour.len())?;
    let points = curve.control_points().map(|p| linear(&p));
    if chords.len() > 1 {
        // A curve joining two parts rarely stays near one of them as a whole: start with
        // its halves.
        halves(&points, chords, limit, HULL_DEPTH - 1)
    } else {
        hull_piece(&points, chords, limit, HULL_DEPTH, false)
    }
}

/// The linear axes X Y Z U V W of a pose.
fn linear(p: &Pose) -> [f64; 6] {
    let mut out = [0.0; 6];
    for (o, &i) in out.iter_mut().zip(Metric::Linear.axes()) {
        *o = p.0[i];
    }
    out
}

/// A straight chord of a contour part over the linear axes, with the part's sagitta.
#[derive(Debug, Clone, Copy, Default)]
struct Chord {
    a: [f64; 6],
    ab: [f64; 6],
    ab2: f64,
    sagitta: f64,
}

impl Chord {
    fn new(a: &Pose, b: &Pose, sagitta: f64) -> Chord {
        let (a, b) = (linear(a), linear(b));
        let mut ab = [0.0; 6];
        for ((d, x), y) in ab.iter_mut().zip(&a).zip(&b) {
            *d = y - x;
        }
        Chord {
            a,
            ab,
            ab2: ab.iter().map(|x| x * x).sum(),
            sagitta,
        }
    }

    /// Distance from `p` to the chord.
    fn distance(&self, p: &[f64; 6]) -> f64 {
        let mut ap = [0.0; 6];
        let mut dot = 0.0;
        for ((d, x), (a, ab)) in ap.iter_mut().zip(p).zip(self.a.iter().zip(&self.ab)) {
            *d = x - a;
            dot += *d * ab;
        }
        let t = if self.ab2 > 0.0 {
            (dot / self.ab2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        ap.iter()
            .zip(&self.ab)
            .map(|(d, ab)| (d - t * ab) * (d - t * ab))
            .sum::<f64>()
            .sqrt()
    }
}

/// [`hull_deviation`] for one piece of the curve given by its control points (linear axes),
/// halved at most `levels` more times; `from_end` tries the contour parts from the last one
/// (for pieces near the curve's end).
fn hull_piece(
    points: &[[f64; 6]; 6],
    chords: &[Chord],
    limit: f64,
    levels: u32,
    from_end: bool,
) -> Option<f64> {
    // Any part whose band holds every control point bounds the piece.
    let within = |c: &Chord| {
        let mut worst = 0.0f64;
        for p in points {
            let d = c.distance(p) + c.sagitta;
            // NaN distances count as too far.
            if d.is_nan() || d > limit {
                return None;
            }
            worst = worst.max(d);
        }
        Some(worst)
    };
    let whole = if from_end {
        chords.iter().rev().find_map(within)
    } else {
        chords.iter().find_map(within)
    };
    match whole {
        Some(w) => Some(w),
        None if levels > 0 => halves(points, chords, limit, levels - 1),
        None => None,
    }
}

/// [`hull_piece`] for both halves of a piece.
fn halves(points: &[[f64; 6]; 6], chords: &[Chord], limit: f64, levels: u32) -> Option<f64> {
    let (left, right) = halve(points);
    let l = hull_piece(&left, chords, limit, levels, false)?;
    let r = hull_piece(&right, chords, limit, levels, true)?;
    Some(l.max(r))
}

/// The control points of the two halves u ∈ [0, ½] and [½, 1] (de Casteljau).
fn halve(points: &[[f64; 6]; 6]) -> ([[f64; 6]; 6], [[f64; 6]; 6]) {
    let mut left = *points;
    let mut right = *points;
    let mut work = *points;
    for level in 1..6 {
        for k in 0..6 - level {
            let next = work[k + 1];
            for (x, y) in work[k].iter_mut().zip(&next) {
                *x = 0.5 * (*x + y);
            }
        }
        left[level] = work[0];
        right[5 - level] = work[5 - level];
    }
    (left, right)
}

/// Contour parts whose chord points [`sampled_deviation`] computes once, on the stack;
/// those of a longer contour (a run of dense code: lines, whose two points cost little) are
/// computed again for every sample. Both give the same distances.
const CACHED_PARTS: usize = 4;

/// The largest distance of the curve from `contour` at [`DEVIATION_SAMPLES`] − 1 interior
/// points, if none exceeds `limit`. Allocates nothing.
fn sampled_deviation(curve: &Quintic, contour: &[ContourPart<'_>], limit: f64) -> Option<f64> {
    let mut cached = [Polyline::EMPTY; CACHED_PARTS];
    let cache = cached.get_mut(..contour.len());
    let cached = match cache {
        Some(slots) => {
            for (slot, part) in slots.iter_mut().zip(contour) {
                slot.fill_through(part);
            }
            Some(&*slots)
        }
        None => None,
    };
    let mut worst = 0.0f64;
    // The middle first: where a blend that is too long fails first.
    let half = DEVIATION_SAMPLES / 2;
    for k in std::iter::once(half).chain((1..DEVIATION_SAMPLES).filter(|&k| k != half)) {
        let p = curve.pose_at_parameter(k as f64 / DEVIATION_SAMPLES as f64);
        let d = match cached {
            Some(lines) => lines
                .iter()
                .map(|line| line.distance(&p))
                .fold(f64::INFINITY, f64::min),
            None => contour
                .iter()
                .map(|part| distance_to_part(&p, part))
                .fold(f64::INFINITY, f64::min),
        };
        // NaN distances count as too far.
        if d.is_nan() || d > limit {
            return None;
        }
        worst = worst.max(d);
    }
    Some(worst)
}

/// Distance (over X Y Z U V W) from `p` to a stretch of an element; never less than the
/// true distance. Computes the chord points of [`Polyline::fill_through`] one after the other,
/// in the same order and so with the same result, without keeping them.
pub fn distance_to_part(p: &Pose, part: &ContourPart<'_>) -> f64 {
    let (a, b) = (part.from.min(part.to), part.from.max(part.to));
    match part.segment {
        Segment::Line(_) => {
            let (pa, pb) = (part.segment.position(a), part.segment.position(b));
            f64::INFINITY.min(distance_to_chord(p, &pa, &pb)) + 0.0
        }
        seg => {
            let (h, sagitta) = chords_of(seg, a, b);
            let mut before = seg.position(a);
            // The nearest chord by squared distance: the root of the least square is the
            // least root, bit for bit (the root is correctly rounded and never decreasing).
            let mut nearest = f64::INFINITY;
            for k in 1..=CURVE_CHORDS {
                let next = seg.position(a + h * k as f64);
                nearest = nearest.min(squared_distance_to_chord(p, &before, &next));
                before = next;
            }
            nearest.sqrt() + sagitta
        }
    }
}

/// Chord length (path distance) and sagitta of [`CURVE_CHORDS`] chords through the stretch
/// `[a, b]` of a curved element.
fn chords_of(seg: &Segment, a: f64, b: f64) -> (f64, f64) {
    let kappa = Metric::Linear.norm(&seg.bounds().d2);
    let h = (b - a) / CURVE_CHORDS as f64;
    (h, h * h * kappa / 8.0)
}

/// A stretch of an element as chords through it, with the largest distance of the stretch
/// from its chords (0 for a line); the points are kept inline (no allocation).
#[derive(Clone, Copy)]
struct Polyline {
    points: [Pose; CURVE_CHORDS + 1],
    /// Points in use.
    count: usize,
    sagitta: f64,
}

impl Polyline {
    /// No points: no distance (infinite).
    const EMPTY: Polyline = Polyline {
        points: [Pose([0.0; 9]); CURVE_CHORDS + 1],
        count: 0,
        sagitta: 0.0,
    };

    /// Makes `self` the chords through `part`, in place (a polyline is kilobytes: building
    /// it where it is kept saves copying it).
    fn fill_through(&mut self, part: &ContourPart<'_>) {
        let (a, b) = (part.from.min(part.to), part.from.max(part.to));
        match part.segment {
            Segment::Line(_) => {
                self.points[0] = part.segment.position(a);
                self.points[1] = part.segment.position(b);
                self.count = 2;
                self.sagitta = 0.0;
            }
            seg => {
                let (h, sagitta) = chords_of(seg, a, b);
                for (k, point) in self.points.iter_mut().enumerate() {
                    *point = seg.position(a + h * k as f64);
                }
                self.count = CURVE_CHORDS + 1;
                self.sagitta = sagitta;
            }
        }
    }

    /// Distance from `p`, never less than the true distance from the stretch.
    fn distance(&self, p: &Pose) -> f64 {
        self.points[..self.count]
            .windows(2)
            .map(|w| squared_distance_to_chord(p, &w[0], &w[1]))
            .fold(f64::INFINITY, f64::min)
            .sqrt()
            + self.sagitta
    }
}

/// Distance from `p` to the straight chord from `a` to `b` over the linear axes.
fn distance_to_chord(p: &Pose, a: &Pose, b: &Pose) -> f64 {
    squared_distance_to_chord(p, a, b).sqrt()
}

/// The square of [`distance_to_chord`] (before its root): nearest chords are found by it,
/// and only the nearest one's root is taken.
fn squared_distance_to_chord(p: &Pose, a: &Pose, b: &Pose) -> f64 {
    let axes = Metric::Linear.axes();
    let (mut ab2, mut ap_ab) = (0.0, 0.0);
    for &i in axes {
        let ab = b.0[i] - a.0[i];
        ab2 += ab * ab;
        ap_ab += (p.0[i] - a.0[i]) * ab;
    }
    let t = if ab2 > 0.0 {
        (ap_ab / ab2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    axes.iter()
        .map(|&i| {
            let q = a.0[i] + t * (b.0[i] - a.0[i]);
            (p.0[i] - q).powi(2)
        })
        .sum::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Arc, Line};
    use klar_interp::Plane;

    fn xy(x: f64, y: f64) -> Pose {
        Pose::xyz(x, y, 0.0)
    }

    /// Distance in the plane from `p` to the segment a–b (by hand: clamp the projection).
    fn to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
    }

    /// Distance in the plane from `p` to the counter-clockwise arc about `c` with radius `r`
    /// from angle `f0` to `f1`.
    fn to_arc(p: [f64; 2], c: [f64; 2], r: f64, f0: f64, f1: f64) -> f64 {
        let phi = (p[1] - c[1]).atan2(p[0] - c[0]);
        let mut rel = phi - f0;
        while rel < 0.0 {
            rel += std::f64::consts::TAU;
        }
        if rel <= f1 - f0 {
            ((p[0] - c[0]).hypot(p[1] - c[1]) - r).abs()
        } else {
            let end = |f: f64| [c[0] + r * f.cos(), c[1] + r * f.sin()];
            let (e0, e1) = (end(f0), end(f1));
            (p[0] - e0[0])
                .hypot(p[1] - e0[1])
                .min((p[0] - e1[0]).hypot(p[1] - e1[1]))
        }
    }

    /// The largest distance of the curve from a contour, at 4001 parameter values.
    fn dense(curve: &Quintic, dist: impl Fn([f64; 2]) -> f64) -> f64 {
        (0..=4000)
            .map(|k| {
                let p = curve.pose_at_parameter(k as f64 / 4000.0);
                dist([p.0[0], p.0[1]])
            })
            .fold(0.0, f64::max)
    }

    /// Line from (−1, 0) to the origin, then one turning by `deg` degrees; the blend from
    /// `d` before to `d` after the corner.
    fn corner(deg: f64, d: f64) -> (Segment, Segment, PathPoint, PathPoint) {
        let th = deg.to_radians();
        let l1 = Segment::Line(Line::new(xy(-1.0, 0.0), xy(0.0, 0.0)).unwrap().unwrap());
        let l2 = Segment::Line(
            Line::new(xy(0.0, 0.0), xy(th.cos(), th.sin()))
                .unwrap()
                .unwrap(),
        );
        let (a, b) = (l1.point(1.0 - d), l2.point(d));
        (l1, l2, a, b)
    }

    #[test]
    fn the_hull_bound_covers_the_curve_at_line_corners() {
        for (deg, d) in [
            (0.2, 0.04),
            (10.0, 0.05),
            (45.0, 0.1),
            (90.0, 0.02),
            (115.0, 0.3),
        ] {
            let (l1, l2, a, b) = corner(deg, d);
            let th = f64::to_radians(deg);
            let curve = Quintic::shape(&a, &b).unwrap();
            let contour = [
                ContourPart {
                    segment: &l1,
                    from: 1.0 - d,
                    to: 1.0,
                },
                ContourPart {
                    segment: &l2,
                    from: 0.0,
                    to: d,
                },
            ];
            let bound = hull_deviation(&curve, &contour, 1.0).expect("bound below 1 mm");
            let truth = dense(&curve, |p| {
                to_segment(p, [-d, 0.0], [0.0, 0.0]).min(to_segment(
                    p,
                    [0.0, 0.0],
                    [d * th.cos(), d * th.sin()],
                ))
            });
            assert!(bound >= truth, "{deg}°: bound {bound} below {truth}");
            // Not a wild overstatement either (control points hug a blend).
            assert!(
                bound <= 4.0 * truth + 1e-12,
                "{deg}°: bound {bound} vs {truth}"
            );
        }
    }

    #[test]
    fn the_hull_bound_covers_the_curve_where_a_line_meets_an_arc() {
        // Line along X into a counter-clockwise arc of radius 2 about (0, 2): tangent, with a
        // curvature jump from 0 to 1/2.
        let l = Segment::Line(Line::new(xy(-1.0, 0.0), xy(0.0, 0.0)).unwrap().unwrap());
        let arc = Segment::Arc(
            Arc::new(xy(0.0, 0.0), xy(2.0, 2.0), [0.0, 2.0], Plane::XY, 90.0)
                .unwrap()
                .unwrap(),
        );
        let d = 0.4;
        let (a, b) = (l.point(1.0 - d), arc.point(d));
        let curve = Quintic::shape(&a, &b).unwrap();
        let contour = [
            ContourPart {
                segment: &l,
                from: 1.0 - d,
                to: 1.0,
            },
            ContourPart {
                segment: &arc,
                from: 0.0,
                to: d,
            },
        ];
        let bound = hull_deviation(&curve, &contour, 1.0).expect("bound below 1 mm");
        let f0 = -std::f64::consts::FRAC_PI_2;
        let truth = dense(&curve, |p| {
            to_segment(p, [-d, 0.0], [0.0, 0.0]).min(to_arc(p, [0.0, 2.0], 2.0, f0, f0 + d / 2.0))
        });
        assert!(bound >= truth, "bound {bound} below {truth}");
    }

    #[test]
    fn a_blend_is_kept_only_inside_the_band() {
        let (l1, l2, a, b) = corner(60.0, 0.2);
        let th = 60f64.to_radians();
        let contour = [
            ContourPart {
                segment: &l1,
                from: 0.8,
                to: 1.0,
            },
            ContourPart {
                segment: &l2,
                from: 0.0,
                to: 0.2,
            },
        ];
        let curve = Quintic::shape(&a, &b).unwrap();
        let truth = dense(&curve, |p| {
            to_segment(p, [-0.2, 0.0], [0.0, 0.0]).min(to_segment(
                p,
                [0.0, 0.0],
                [0.2 * th.cos(), 0.2 * th.sin()],
            ))
        });
        // A band the curve leaves by half again: refused.
        assert!(
            blend_within(
                &a,
                &b,
                &contour,
                truth / 1.5 / TOLERANCE_SHARE,
                &mut BoundsMemo::new(0)
            )
            .is_none()
        );
        // A band twice as wide as the curve needs: kept, with a deviation it really has at
        // most.
        let (_, worst) = blend_within(
            &a,
            &b,
            &contour,
            2.0 * truth / TOLERANCE_SHARE,
            &mut BoundsMemo::new(0),
        )
        .expect("inside the band");
        assert!(worst >= truth && worst <= 2.0 * truth, "{worst} vs {truth}");
    }

    #[test]
    fn halving_keeps_the_curve() {
        let (_, _, a, b) = corner(75.0, 0.3);
        let curve = Quintic::shape(&a, &b).unwrap();
        let (left, right) = halve(&curve.control_points().map(|p| linear(&p)));
        // Bernstein form of degree 5 evaluated by hand.
        let bezier = |cp: &[[f64; 6]; 6], t: f64, i: usize| {
            let binom = [1.0, 5.0, 10.0, 10.0, 5.0, 1.0];
            (0..6)
                .map(|k| binom[k] * t.powi(k as i32) * (1.0 - t).powi(5 - k as i32) * cp[k][i])
                .sum::<f64>()
        };
        for k in 0..=20 {
            let t = k as f64 / 20.0;
            let (p, q) = (
                curve.pose_at_parameter(0.5 * t),
                curve.pose_at_parameter(0.5 + 0.5 * t),
            );
            for i in 0..2 {
                assert!((bezier(&left, t, i) - p.0[i]).abs() < 1e-14);
                assert!((bezier(&right, t, i) - q.0[i]).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn a_curved_parts_distance_is_its_nearest_chords_root_and_the_polylines_too() {
        // Arc of radius 2 about (0, 2), a quarter turn from the origin; points inside,
        // outside and off its ends.
        let arc = Segment::Arc(
            Arc::new(xy(0.0, 0.0), xy(2.0, 2.0), [0.0, 2.0], Plane::XY, 90.0)
                .unwrap()
                .unwrap(),
        );
        let part = ContourPart {
            segment: &arc,
            from: 0.3,
            to: 2.5,
        };
        let mut line = Polyline::EMPTY;
        line.fill_through(&part);
        let (h, sagitta) = chords_of(&arc, 0.3, 2.5);
        for p in [
            xy(0.5, 0.3),
            xy(1.9, 2.4),
            xy(-1.0, 0.0),
            xy(3.0, 3.0),
            xy(0.0, 2.0),
        ] {
            // One root per chord, the least of them: what the squared search must match.
            let roots = (1..=CURVE_CHORDS)
                .map(|k| {
                    let a = arc.position(0.3 + h * (k - 1) as f64);
                    let b = arc.position(0.3 + h * k as f64);
                    squared_distance_to_chord(&p, &a, &b).sqrt()
                })
                .fold(f64::INFINITY, f64::min)
                + sagitta;
            assert_eq!(
                distance_to_part(&p, &part).to_bits(),
                roots.to_bits(),
                "{p:?}"
            );
            assert_eq!(line.distance(&p).to_bits(), roots.to_bits(), "{p:?}");
            // And it is the distance from the arc (radius 2 about (0, 2)) within the sagitta
            // for the points whose nearest arc point lies on the stretch.
            let to_circle = (p.0[0].hypot(p.0[1] - 2.0) - 2.0).abs();
            if p.0[0] > 0.0 && p.0[1] < 2.0 {
                assert!((roots - to_circle).abs() <= 2.0 * sagitta + 1e-12, "{p:?}");
            }
        }
    }
}
