//! Straight line in all axes: every axis moves in proportion to path distance.

use super::{AxisBounds, GeomError, Metric, PathPoint, delta, finite_pose};
use klar_interp::Pose;

/// A straight move from one pose to another.
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    from: Pose,
    to: Pose,
    /// d pose / ds (constant).
    direction: [f64; 9],
    length: f64,
    metric: Metric,
}

impl Line {
    /// The line from `from` to `to`; `None` when it has zero length in every axis.
    pub fn new(from: Pose, to: Pose) -> Result<Option<Line>, GeomError> {
        if !finite_pose(&from) || !finite_pose(&to) {
            return Err(GeomError::NonFinite("line end point"));
        }
        let d = delta(&from, &to);
        let metric = Metric::of_displacement(&d);
        let length = metric.norm(&d);
        if length <= super::ZERO_LENGTH {
            return Ok(None);
        }
        let direction = d.map(|x| x / length);
        Ok(Some(Line {
            from,
            to,
            direction,
            length,
            metric,
        }))
    }

    /// Path length.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// Which axes measure the length.
    pub fn metric(&self) -> Metric {
        self.metric
    }

    /// Start pose.
    pub fn start(&self) -> Pose {
        self.from
    }

    /// End pose.
    pub fn end(&self) -> Pose {
        self.to
    }

    /// Pose and derivatives at path distance `s`; exactly `to` at the end.
    pub fn point(&self, s: f64) -> PathPoint {
        let u = (s / self.length).clamp(0.0, 1.0);
        let mut pose = self.to;
        if u < 1.0 {
            for ((p, a), b) in pose.0.iter_mut().zip(&self.from.0).zip(&self.to.0) {
                *p = a + (b - a) * u;
            }
        }
        PathPoint {
            pose,
            d1: self.direction,
            d2: [0.0; 9],
        }
    }

    /// Derivative bounds: constant direction, no curvature.
    pub fn bounds(&self) -> AxisBounds {
        AxisBounds {
            d1: self.direction.map(f64::abs),
            ..AxisBounds::default()
        }
    }
}
