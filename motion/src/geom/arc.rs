//! Circular arc or helix in a principal plane: the in-plane axes turn about a centre, every
//! other axis (the plane's normal axis included) moves linearly with the angle.

use super::{AxisBounds, GeomError, Metric, PathPoint, delta, finite_pose};
use klar_interp::{Plane, Pose};

/// Largest distance (mm) between the programmed end point and the end of the circle at the
/// programmed sweep that is accepted. The small remaining gap is spread linearly over the
/// arc, so the path still ends exactly at the programmed point.
pub const ARC_END_TOLERANCE: f64 = 0.01;

/// An arc or helix.
#[derive(Debug, Clone, PartialEq)]
pub struct Arc {
    from: Pose,
    to: Pose,
    /// Pose indices of the first and second in-plane axes.
    p: usize,
    q: usize,
    center: [f64; 2],
    radius: f64,
    /// Start angle in radians.
    phi0: f64,
    /// Signed sweep in radians.
    theta: f64,
    /// Programmed end minus computed circle end, in the plane.
    end_fix: [f64; 2],
    length: f64,
}

impl Arc {
    /// The arc from `from` about `center` (in-plane coordinates of `plane`) through `sweep`
    /// degrees (positive counter-clockwise, may exceed 360°), ending at `to`.
    ///
    /// Returns `None` when no linear axis moves (zero radius and no helix travel); a move of
    /// rotary axes only is then a [`super::Line`].
    pub fn new(
        from: Pose,
        to: Pose,
        center: [f64; 2],
        plane: Plane,
        sweep: f64,
    ) -> Result<Option<Arc>, GeomError> {
        if !finite_pose(&from) || !finite_pose(&to) {
            return Err(GeomError::NonFinite("arc end point"));
        }
        if !center.iter().all(|c| c.is_finite()) {
            return Err(GeomError::NonFinite("arc centre"));
        }
        if !sweep.is_finite() {
            return Err(GeomError::NonFinite("arc sweep"));
        }
        let (pa, qa, _) = plane.axes();
        let (p, q) = (pa.index(), qa.index());
        let dx = from.0[p] - center[0];
        let dy = from.0[q] - center[1];
        let radius = dx.hypot(dy);
        let phi0 = dy.atan2(dx);
        let theta = sweep.to_radians();
        let end_angle = phi0 + theta;
        let computed_end = [
            center[0] + radius * end_angle.cos(),
            center[1] + radius * end_angle.sin(),
        ];
        let end_fix = [to.0[p] - computed_end[0], to.0[q] - computed_end[1]];
        let deviation = end_fix[0].hypot(end_fix[1]);
        if deviation > ARC_END_TOLERANCE {
            return Err(GeomError::ArcEnd { deviation });
        }
        let d = delta(&from, &to);
        let travel_sq: f64 = Metric::Linear
            .axes()
            .iter()
            .filter(|&&i| i != p && i != q)
            .map(|&i| d[i] * d[i])
            .sum();
        let length = ((radius * theta).powi(2) + travel_sq).sqrt();
        if length <= super::ZERO_LENGTH {
            return Ok(None);
        }
        Ok(Some(Arc {
            from,
            to,
            p,
            q,
            center,
            radius,
            phi0,
            theta,
            end_fix,
            length,
        }))
    }

    /// Path length: √((r·θ)² + h²), h the travel of the other linear axes.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// Radius in the plane.
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Start pose.
    pub fn start(&self) -> Pose {
        self.from
    }

    /// End pose.
    pub fn end(&self) -> Pose {
        self.to
    }

    /// Pose and derivatives at path distance `s`; exactly `from` at the start and `to` at
    /// the end.
    pub fn point(&self, s: f64) -> PathPoint {
        let u = (s / self.length).clamp(0.0, 1.0);
        let w = self.theta / self.length; // dφ/ds
        let phi = self.phi0 + self.theta * u;
        let (sin, cos) = phi.sin_cos();
        let r = self.radius;
        let mut pose = if u <= 0.0 { self.from } else { self.to };
        let mut d1 = self.rates();
        let mut d2 = [0.0; 9];
        if u > 0.0 && u < 1.0 {
            for ((p, a), b) in pose.0.iter_mut().zip(&self.from.0).zip(&self.to.0) {
                *p = a + (b - a) * u;
            }
            pose.0[self.p] = self.center[0] + r * cos + self.end_fix[0] * u;
            pose.0[self.q] = self.center[1] + r * sin + self.end_fix[1] * u;
        }
        d1[self.p] = -r * sin * w + self.end_fix[0] / self.length;
        d1[self.q] = r * cos * w + self.end_fix[1] / self.length;
        d2[self.p] = -r * cos * w * w;
        d2[self.q] = -r * sin * w * w;
        PathPoint { pose, d1, d2 }
    }

    /// d pose / ds of the axes moving linearly with the angle (in-plane entries unused).
    fn rates(&self) -> [f64; 9] {
        let mut d = delta(&self.from, &self.to);
        for x in &mut d {
            *x /= self.length;
        }
        d
    }

    /// Derivative bounds: amplitudes of the circular terms (r·wⁿ, w = θ/L) plus the
    /// constant rates of the other axes.
    pub fn bounds(&self) -> AxisBounds {
        let mut b = AxisBounds {
            d1: self.rates().map(f64::abs),
            ..AxisBounds::default()
        };
        let w = (self.theta / self.length).abs();
        let r = self.radius;
        b.curvature = r * w * w;
        for (i, fix) in [(self.p, self.end_fix[0]), (self.q, self.end_fix[1])] {
            b.wave[i] = r * w;
            b.d1[i] = r * w + (fix / self.length).abs();
            b.d2[i] = r * w * w;
            b.d3[i] = r * w * w * w;
        }
        b
    }
}
