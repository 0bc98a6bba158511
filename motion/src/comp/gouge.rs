//! The window check for gouges beyond the neighbouring blocks (the job M120 LOOK AHEAD does
//! on the control): the tool path of every block still held back must stay at least the tool
//! radius away from every programmed contour element in the window. Corners between
//! neighbours are settled exactly by [`super::corner`]; this check catches the rest, such as
//! a later part of the contour coming back within the tool radius of an earlier one.

use super::element::Shape;
use super::plane::{V2, project};
use klar_interp::{Op, OpKind, Plane};
use std::f64::consts::TAU;

/// How far (mm) a tool path may come inside the tool radius before it counts as a gouge: 1 µm,
/// the radius tolerance the interpreter allows on arc end points.
pub const GOUGE_TOLERANCE: f64 = 1e-3;

/// Coarse samples per full turn of an arc (at least [`MIN_SAMPLES`] per arc).
const SAMPLES_PER_TURN: f64 = 32.0;
/// Coarse samples of a line, and the least number per arc.
const MIN_SAMPLES: usize = 8;
/// Golden-section steps: the bracket shrinks to 0.618^40 ≈ 5e-9 of its width.
const GOLDEN_STEPS: usize = 40;

/// Distance from `q` to a programmed element.
pub fn distance(q: V2, shape: &Shape) -> f64 {
    match *shape {
        Shape::Line { a, b } => {
            let v = b - a;
            let len2 = v.dot(v);
            let t = if len2 > 0.0 {
                ((q - a).dot(v) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            q.dist(a + v * t)
        }
        Shape::Arc { c, r, phi0, sweep } => {
            let along = (((q - c).angle() - phi0) * sweep.signum()).rem_euclid(TAU);
            if sweep.abs() >= TAU || along <= sweep.abs() {
                (q.dist(c) - r).abs()
            } else {
                let e0 = c + V2::polar(phi0) * r;
                let e1 = c + V2::polar(phi0 + sweep) * r;
                q.dist(e0).min(q.dist(e1))
            }
        }
    }
}

/// One in-plane piece of a compensated tool path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PathPiece {
    /// Segment from the first to the second point.
    Line(V2, V2),
    /// Arc: centre, radius, start angle, signed sweep (radians).
    Arc(V2, f64, f64, f64),
}

impl PathPiece {
    /// The point at parameter `u` in [0, 1].
    fn at(&self, u: f64) -> V2 {
        match *self {
            PathPiece::Line(a, b) => a + (b - a) * u,
            PathPiece::Arc(c, r, a0, sweep) => c + V2::polar(a0 + sweep * u) * r,
        }
    }

    /// Number of coarse samples before refinement.
    fn samples(&self) -> usize {
        match *self {
            PathPiece::Line(..) => MIN_SAMPLES,
            PathPiece::Arc(.., sweep) => {
                ((sweep.abs() / TAU * SAMPLES_PER_TURN).ceil() as usize).max(MIN_SAMPLES)
            }
        }
    }

    /// A circle enclosing the piece: (centre, radius).
    fn bounds(&self) -> (V2, f64) {
        match *self {
            PathPiece::Line(a, b) => ((a + b) * 0.5, a.dist(b) * 0.5),
            PathPiece::Arc(c, r, a0, sweep) => arc_bounds(c, r, a0, sweep),
        }
    }

    /// Path length of the piece.
    fn length(&self) -> f64 {
        match *self {
            PathPiece::Line(a, b) => a.dist(b),
            PathPiece::Arc(_, r, _, sweep) => r * sweep.abs(),
        }
    }

    /// The smallest distance from this piece to a programmed element, where it is below
    /// `limit`; otherwise some value at least `limit`.
    ///
    /// From a line to a segment the distance is convex along the line, so a golden-section
    /// search over the whole piece finds it. Otherwise the piece is sampled; the distance
    /// changes no faster than the path length, so between two samples `Δs` apart it can dip
    /// at most `Δs/2` below the lower one, and only the intervals where such a dip could
    /// reach below `limit` are searched further.
    fn min_distance(&self, shape: &Shape, limit: f64) -> f64 {
        let f = |u: f64| distance(self.at(u), shape);
        if let (PathPiece::Line(..), Shape::Line { .. }) = (self, shape) {
            return golden(f, 0.0, 1.0, limit, self.length())
                .min(f(0.0))
                .min(f(1.0));
        }
        let n = self.samples();
        let half_gap = self.length() / n as f64 / 2.0;
        let d: Vec<f64> = (0..=n).map(|i| f(i as f64 / n as f64)).collect();
        let mut best = d.iter().copied().fold(f64::INFINITY, f64::min);
        for (i, pair) in d.windows(2).enumerate() {
            if let [d0, d1] = pair
                && d0.min(*d1) - half_gap < limit
            {
                let lo = i as f64 / n as f64;
                let hi = (i + 1) as f64 / n as f64;
                best = best.min(golden(f, lo, hi, limit, self.length()));
            }
        }
        best
    }
}

/// A circle enclosing an arc: the circle on its chord for sweeps up to a half turn (the
/// arc bulges no further than that), else the full circle.
fn arc_bounds(c: V2, r: f64, a0: f64, sweep: f64) -> (V2, f64) {
    if sweep.abs() <= std::f64::consts::PI {
        let e0 = c + V2::polar(a0) * r;
        let e1 = c + V2::polar(a0 + sweep) * r;
        ((e0 + e1) * 0.5, e0.dist(e1) * 0.5)
    } else {
        (c, r)
    }
}

/// A circle enclosing a programmed element.
fn shape_bounds(shape: &Shape) -> (V2, f64) {
    match *shape {
        Shape::Line { a, b } => ((a + b) * 0.5, a.dist(b) * 0.5),
        Shape::Arc { c, r, phi0, sweep } => arc_bounds(c, r, phi0, sweep),
    }
}

/// Golden-section search for the minimum of `f` on [lo, hi] (parameters of a piece
/// `length` mm long). Stops early once the bracket proves nothing in it is below `limit`
/// (the distance changes no faster than the path length).
fn golden(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64, limit: f64, length: f64) -> f64 {
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut x1, mut x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
    let (mut f1, mut f2) = (f(x1), f(x2));
    for _ in 0..GOLDEN_STEPS {
        if f1.min(f2) - (hi - lo) * length >= limit {
            break;
        }
        if f1 < f2 {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = hi - g * (hi - lo);
            f1 = f(x1);
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = lo + g * (hi - lo);
            f2 = f(x2);
        }
    }
    f1.min(f2)
}

/// The in-plane pieces of the line and arc ops (moves without in-plane travel left out).
pub fn pieces(ops: &[Op], plane: Plane) -> Vec<PathPiece> {
    let mut out = Vec::new();
    for op in ops {
        match &op.kind {
            OpKind::Line { from, to, .. } => {
                let (a, b) = (project(from, plane), project(to, plane));
                if a != b {
                    out.push(PathPiece::Line(a, b));
                }
            }
            OpKind::Arc {
                from,
                center,
                sweep,
                ..
            } => {
                let c = V2::new(center[0], center[1]);
                let rel = project(from, plane) - c;
                out.push(PathPiece::Arc(
                    c,
                    rel.norm(),
                    rel.angle(),
                    sweep.to_radians(),
                ));
            }
            _ => {}
        }
    }
    out
}

/// The smallest distance from the path pieces to the element, if below `tool − tolerance`.
/// Pieces whose enclosing circle is at least the tool radius away are skipped unmeasured.
pub fn intrusion(path: &[PathPiece], shape: &Shape, tool: f64) -> Option<f64> {
    let (sc, sr) = shape_bounds(shape);
    let d = path
        .iter()
        .filter(|p| {
            let (pc, pr) = p.bounds();
            pc.dist(sc) - pr - sr < tool
        })
        .map(|p| p.min_distance(shape, tool - GOUGE_TOLERANCE))
        .fold(f64::INFINITY, f64::min);
    (d < tool - GOUGE_TOLERANCE).then_some(d)
}
