//! Cubic polynomial segment (spline block): per axis `P(t) = K3·t³ + K2·t² + K1·t + end`
//! with t running from 1 (start) to 0 (end), travelled at constant speed along the curve.
//!
//! The polynomial parameter is `u = 1 − t`. Path distance is its arc length, integrated with
//! 5-point Gauss–Legendre quadrature on [`TABLE_INTERVALS`] equal intervals of `u` into a
//! cumulative table; a distance is turned back into `u` by a table look-up and Newton steps
//! on the same quadrature (with bisection as a fallback).
//!
//! The per-axis bounds of the first three path derivatives, which the planner turns into
//! speed limits, are the maxima over 257 evenly spaced parameter values times 1.1: for a
//! smooth cubic the maxima between samples differ far less than that, but it is a sampled
//! bound, not a proven one. Curves whose parameter speed nearly vanishes (cusps) are refused.

use super::{
    AxisBounds, GeomError, Metric, PathPoint, ZERO_LENGTH, arclen, delta, finite_pose, letter,
};
use klar_interp::Pose;
use klar_interp::op::SplineAxis;

/// Number of equal intervals of the polynomial parameter in the arc-length table.
pub const TABLE_INTERVALS: usize = 64;

/// Largest accepted gap (mm or degrees) between the current position and the polynomial at
/// t = 1. The gap is folded into the linear coefficient so the curve starts exactly there.
pub const SPLINE_START_TOLERANCE: f64 = 0.001;

/// Points per segment at which the derivative bounds are sampled.
const BOUND_SAMPLES: usize = 256;

/// Safety factor on sampled derivative bounds (the maxima between samples of a smooth cubic
/// differ from the sampled ones by far less than this).
const BOUND_MARGIN: f64 = 1.1;

/// Smallest accepted ratio of the parameter speed |dP/du| to its mean: below it the curve
/// (nearly) stops and turns, which no finite axis acceleration can follow at speed.
const MIN_PARAMETER_SPEED: f64 = 1e-6;

/// A spline segment parameterised by arc length.
#[derive(Debug, Clone, PartialEq)]
pub struct Poly {
    from: Pose,
    to: Pose,
    /// `[K3, K2, K1]` per pose index; K1 includes the start correction.
    k: [[f64; 3]; 9],
    metric: Metric,
    /// Arc length from u = 0 to u = i / TABLE_INTERVALS.
    table: [f64; TABLE_INTERVALS + 1],
    bounds: AxisBounds,
}

/// Polynomial derivatives with respect to u at one parameter value.
struct UDerivs {
    p: [f64; 9],
    d1: [f64; 9],
    d2: [f64; 9],
    d3: [f64; 9],
}

impl Poly {
    /// A spline of zero length at the origin that nothing follows: what a slot made up
    /// front holds until a spline is written into it.
    pub(crate) fn placeholder() -> Poly {
        Poly {
            from: Pose::default(),
            to: Pose::default(),
            k: [[0.0; 3]; 9],
            metric: Metric::Linear,
            table: [0.0; TABLE_INTERVALS + 1],
            bounds: AxisBounds::default(),
        }
    }

    /// The spline from `from` (the current position) to `to` with coefficients per axis;
    /// axes without coefficients move linearly from `from` to `to` (they should be equal).
    /// `None` when the curve has zero length.
    pub fn new(from: Pose, to: Pose, axes: &[SplineAxis]) -> Result<Option<Poly>, GeomError> {
        if !finite_pose(&from) || !finite_pose(&to) {
            return Err(GeomError::NonFinite("spline end point"));
        }
        let mut k = [[0.0; 3]; 9];
        for a in axes {
            if !a.k.iter().all(|c| c.is_finite()) {
                return Err(GeomError::NonFinite("spline coefficient"));
            }
            if let Some(slot) = k.get_mut(a.axis.index()) {
                *slot = a.k;
            }
        }
        // Start gap: from − P(t = 1), folded into K1 so that P(t = 1) = from.
        let d = delta(&to, &from);
        let mut worst = (0usize, 0.0f64);
        for (i, ki) in k.iter_mut().enumerate() {
            let gap = d[i] - (ki[0] + ki[1] + ki[2]);
            if gap.abs() > worst.1 {
                worst = (i, gap.abs());
            }
            ki[2] += gap;
        }
        if worst.1 > SPLINE_START_TOLERANCE {
            return Err(GeomError::SplineStart {
                axis: letter(worst.0),
                deviation: worst.1,
            });
        }
        let mut poly = Poly {
            from,
            to,
            k,
            metric: Metric::Linear,
            table: [0.0; TABLE_INTERVALS + 1],
            bounds: AxisBounds::default(),
        };
        poly.build_table();
        if poly.length() <= ZERO_LENGTH {
            poly.metric = Metric::Rotary;
            poly.build_table();
            if poly.length() <= ZERO_LENGTH {
                return Ok(None);
            }
        }
        poly.bounds = poly.sample_bounds()?;
        Ok(Some(poly))
    }

    fn build_table(&mut self) {
        let mut table = [0.0; TABLE_INTERVALS + 1];
        arclen::fill_table(&mut table, |u| self.speed(u));
        self.table = table;
    }

    /// |dP/du| in the metric.
    fn speed(&self, u: f64) -> f64 {
        self.metric.norm(&self.derivs(u).d1)
    }

    fn derivs(&self, u: f64) -> UDerivs {
        let t = 1.0 - u;
        let mut r = UDerivs {
            p: [0.0; 9],
            d1: [0.0; 9],
            d2: [0.0; 9],
            d3: [0.0; 9],
        };
        for (i, [k3, k2, k1]) in self.k.iter().copied().enumerate() {
            r.p[i] = ((k3 * t + k2) * t + k1) * t + self.to.0[i];
            r.d1[i] = -((3.0 * k3 * t + 2.0 * k2) * t + k1);
            r.d2[i] = 6.0 * k3 * t + 2.0 * k2;
            r.d3[i] = -6.0 * k3;
        }
        r
    }

    /// Path length.
    pub fn length(&self) -> f64 {
        self.table[TABLE_INTERVALS]
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

    /// The polynomial parameter u = 1 − t at path distance `s`.
    pub fn parameter_at(&self, s: f64) -> f64 {
        arclen::parameter_at(&self.table, s, |u| self.speed(u))
    }

    /// Pose and derivatives with respect to path distance at `s`; exactly `from` at the
    /// start and `to` at the end.
    pub fn point(&self, s: f64) -> PathPoint {
        let u = self.parameter_at(s);
        let r = self.derivs(u);
        let sigma = self.metric.norm(&r.d1);
        let mut d1 = [0.0; 9];
        let mut d2 = [0.0; 9];
        if sigma > 0.0 {
            let sigma_u = self.metric.dot(&r.d1, &r.d2) / sigma;
            let up = 1.0 / sigma;
            let upp = -sigma_u / (sigma * sigma * sigma);
            for i in 0..9 {
                d1[i] = r.d1[i] * up;
                d2[i] = r.d2[i] * up * up + r.d1[i] * upp;
            }
        }
        let pose = if u <= 0.0 {
            self.from
        } else if u >= 1.0 {
            self.to
        } else {
            Pose(r.p)
        };
        PathPoint { pose, d1, d2 }
    }

    /// Derivative bounds, sampled at 257 evenly spaced parameter values with a 10 % margin
    /// (a sampled bound, not a proven one; see the module notes).
    pub fn bounds(&self) -> AxisBounds {
        self.bounds
    }

    fn sample_bounds(&self) -> Result<AxisBounds, GeomError> {
        let mean = self.length();
        let mut b = AxisBounds::default();
        for j in 0..=BOUND_SAMPLES {
            let u = j as f64 / BOUND_SAMPLES as f64;
            let r = self.derivs(u);
            let m = self.metric;
            let sigma = m.norm(&r.d1);
            if sigma.is_nan() || sigma <= MIN_PARAMETER_SPEED * mean {
                return Err(GeomError::SplineCusp { parameter: u });
            }
            // Chain rule for q(s) = P(u(s)): u' = 1/σ, u'' = −σ_u/σ³,
            // u''' = (3σ_u² − σ·σ_uu)/σ⁵.
            let sigma_u = m.dot(&r.d1, &r.d2) / sigma;
            let sigma_uu = (m.dot(&r.d2, &r.d2) + m.dot(&r.d1, &r.d3) - sigma_u * sigma_u) / sigma;
            let up = 1.0 / sigma;
            let upp = -sigma_u / sigma.powi(3);
            let uppp = (3.0 * sigma_u * sigma_u - sigma * sigma_uu) / sigma.powi(5);
            for i in 0..9 {
                let q1 = r.d1[i] * up;
                let q2 = r.d2[i] * up * up + r.d1[i] * upp;
                let q3 = r.d3[i] * up.powi(3) + 3.0 * r.d2[i] * up * upp + r.d1[i] * uppp;
                b.d1[i] = b.d1[i].max(q1.abs() * BOUND_MARGIN);
                b.d2[i] = b.d2[i].max(q2.abs() * BOUND_MARGIN);
                b.d3[i] = b.d3[i].max(q3.abs() * BOUND_MARGIN);
            }
        }
        if self.metric == Metric::Linear {
            b.curvature = Metric::Linear.norm(&b.d2);
        }
        Ok(b)
    }
}
