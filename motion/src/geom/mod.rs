//! Path geometry: the primitives a motion op describes (line, arc/helix, cubic polynomial),
//! each parameterised by path distance `s` from its start, behind one [`Segment`] type.
//!
//! Path distance is measured in the linear axes X Y Z U V W (mm); a move of rotary axes
//! only is measured in degrees over A B C (see [`Metric`]). Every primitive returns its start
//! and end poses exactly at `s = 0` and `s = length`.

pub mod arc;
pub mod arclen;
pub mod line;
pub mod poly;

pub use arc::Arc;
pub use line::Line;
pub use poly::Poly;

use klar_interp::{AxisLetter, Pose};

/// Moves shorter than this (mm, or degrees for rotary-only moves) count as zero length.
pub const ZERO_LENGTH: f64 = 1e-9;

/// Pose indices of the linear axes X Y Z U V W.
const LINEAR: [usize; 6] = [0, 1, 2, 6, 7, 8];
/// Pose indices of the rotary axes A B C.
const ROTARY: [usize; 3] = [3, 4, 5];

/// Which axes measure path length along a segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Metric {
    /// Euclidean length over X Y Z U V W in mm (any move of a linear axis).
    Linear,
    /// Euclidean length over A B C in degrees (moves of rotary axes only).
    Rotary,
}

impl Metric {
    /// The metric of a move with the given per-axis displacement.
    pub fn of_displacement(delta: &[f64; 9]) -> Metric {
        if Metric::Linear.norm(delta) > ZERO_LENGTH {
            Metric::Linear
        } else {
            Metric::Rotary
        }
    }

    /// Pose indices of the axes this metric measures.
    pub fn axes(self) -> &'static [usize] {
        match self {
            Metric::Linear => &LINEAR,
            Metric::Rotary => &ROTARY,
        }
    }

    /// Dot product over the measured axes.
    pub fn dot(self, a: &[f64; 9], b: &[f64; 9]) -> f64 {
        self.axes().iter().map(|&i| a[i] * b[i]).sum()
    }

    /// Euclidean norm over the measured axes.
    pub fn norm(self, v: &[f64; 9]) -> f64 {
        self.dot(v, v).sqrt()
    }
}

/// Position and its first two derivatives with respect to path distance at one point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathPoint {
    /// The pose.
    pub pose: Pose,
    /// d pose / ds per axis: the unit tangent in the segment's [`Metric`].
    pub d1: [f64; 9],
    /// d² pose / ds² per axis: its norm in the metric is the curvature.
    pub d2: [f64; 9],
}

/// Upper bounds of |dⁿq/dsⁿ| per axis over a whole segment, n = 1, 2, 3: what turns path
/// speed, acceleration and jerk into per-axis speed, acceleration and jerk.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxisBounds {
    /// max |dq/ds| per axis.
    pub d1: [f64; 9],
    /// max |d²q/ds²| per axis.
    pub d2: [f64; 9],
    /// max |d³q/ds³| per axis.
    pub d3: [f64; 9],
    /// Amplitude of the part of dq/ds that turns with the angle on the in-plane axes of an
    /// arc or helix (0 elsewhere). There `q′ = −W·sin θ + o`, `q″ = −d2·cos θ` and
    /// `q‴ = d3·sin θ` with `W = wave`, `o = d1 − W` a constant, so the speed and curvature
    /// terms of an axis's acceleration and jerk peak at different angles and add in
    /// quadrature (see [`crate::limits`]).
    pub wave: [f64; 9],
    /// Bound of the curvature |d²q/ds²| over the linear axes X Y Z U V W, for a segment
    /// whose path distance is its length over those axes (0 otherwise, e.g. rotary-only
    /// moves). The unit tangent and the curvature direction are orthogonal, so on every
    /// linear axis `|q′·A + q″·V²| ≤ √(A² + (κ·V²)²)` (see [`crate::limits`]).
    pub curvature: f64,
}

/// Geometry an op describes that cannot be followed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeomError {
    /// A coordinate, centre, sweep or coefficient is NaN or infinite.
    #[error("{0} is not a finite number")]
    NonFinite(&'static str),
    /// The arc's end point is not on the circle at the programmed sweep.
    #[error("arc end point is {deviation:.6} mm away from where the circle ends")]
    ArcEnd {
        /// Distance in the plane between the programmed and the computed end.
        deviation: f64,
    },
    /// The spline polynomial at t = 1 does not start where the tool is.
    #[error("spline starts {deviation:.6} away from the current position (axis {axis})")]
    SplineStart {
        /// The axis with the largest gap.
        axis: AxisLetter,
        /// The gap in mm or degrees.
        deviation: f64,
    },
    /// The spline (nearly) stops and turns back: its parameter speed vanishes.
    #[error("spline has a cusp near parameter {parameter:.4} (the curve stops and turns)")]
    SplineCusp {
        /// The polynomial parameter u = 1 − t where it was found.
        parameter: f64,
    },
}

/// One path primitive, parameterised by path distance.
#[derive(Debug, Clone, PartialEq)]
pub enum Segment {
    /// Straight line in all axes.
    Line(Line),
    /// Circular arc or helix.
    Arc(Arc),
    /// Cubic polynomial per axis (spline block), shared by the pieces cut from it (the
    /// planner keeps it in a slot made up front: `planner::splines`).
    Poly(std::sync::Arc<Poly>),
}

impl Segment {
    /// Path length (mm, or degrees for rotary-only moves).
    pub fn length(&self) -> f64 {
        match self {
            Segment::Line(g) => g.length(),
            Segment::Arc(g) => g.length(),
            Segment::Poly(g) => g.length(),
        }
    }

    /// Which axes measure the length.
    pub fn metric(&self) -> Metric {
        match self {
            Segment::Line(g) => g.metric(),
            Segment::Arc(_) => Metric::Linear,
            Segment::Poly(g) => g.metric(),
        }
    }

    /// The pose at `s = 0`.
    pub fn start(&self) -> Pose {
        match self {
            Segment::Line(g) => g.start(),
            Segment::Arc(g) => g.start(),
            Segment::Poly(g) => g.start(),
        }
    }

    /// The pose at `s = length`.
    pub fn end(&self) -> Pose {
        match self {
            Segment::Line(g) => g.end(),
            Segment::Arc(g) => g.end(),
            Segment::Poly(g) => g.end(),
        }
    }

    /// Pose and derivatives at path distance `s` (clamped to `[0, length]`).
    pub fn point(&self, s: f64) -> PathPoint {
        match self {
            Segment::Line(g) => g.point(s),
            Segment::Arc(g) => g.point(s),
            Segment::Poly(g) => g.point(s),
        }
    }

    /// Pose at path distance `s` (clamped to `[0, length]`).
    pub fn position(&self, s: f64) -> Pose {
        self.point(s).pose
    }

    /// Unit tangent (d pose / ds) at path distance `s`.
    pub fn tangent(&self, s: f64) -> [f64; 9] {
        self.point(s).d1
    }

    /// Curvature at path distance `s`: |d² pose / ds²| in the segment's metric
    /// (1/mm; 1/radius on a circle).
    pub fn curvature(&self, s: f64) -> f64 {
        self.metric().norm(&self.point(s).d2)
    }

    /// Per-axis derivative bounds over the whole segment.
    pub fn bounds(&self) -> AxisBounds {
        match self {
            Segment::Line(g) => g.bounds(),
            Segment::Arc(g) => g.bounds(),
            Segment::Poly(g) => g.bounds(),
        }
    }
}

/// Component-wise difference `b - a`.
pub(crate) fn delta(a: &Pose, b: &Pose) -> [f64; 9] {
    let mut d = [0.0; 9];
    for ((d, x), y) in d.iter_mut().zip(&a.0).zip(&b.0) {
        *d = y - x;
    }
    d
}

/// True when every value of the pose is finite.
pub(crate) fn finite_pose(p: &Pose) -> bool {
    p.0.iter().all(|v| v.is_finite())
}

/// The axis letter of a pose index (indices are always below 9 here).
pub(crate) fn letter(i: usize) -> AxisLetter {
    AxisLetter::ALL.get(i).copied().unwrap_or(AxisLetter::X)
}
