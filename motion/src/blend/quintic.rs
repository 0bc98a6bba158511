//! The quintic Hermite blend curve, parameterised by path distance.
//!
//! With end points A, B, unit tangents t₀, t₁, curvature vectors k₀, k₁ and the chord
//! λ = |B − A|, the curve P(u), u ∈ [0, 1], has P(0) = A, P′(0) = λ·t₀, P″(0) = λ²·k₀ and the
//! same at u = 1 with B, t₁, k₁. Since k ⊥ t, the arc-length derivatives at the ends are
//! exactly t and k: the curve continues position, tangent and curvature of its neighbours.
//!
//! Path distance is the arc length over X Y Z U V W, tabulated by [`crate::geom::arclen`]
//! (Gauss–Legendre quadrature on [`TABLE_INTERVALS`] intervals of u, inverted by safeguarded
//! Newton steps).

use crate::geom::{AxisBounds, Metric, PathPoint, arclen};
use klar_interp::Pose;

/// Intervals of u in the arc-length table.
pub const TABLE_INTERVALS: usize = 16;

/// Parameter values at which derivative bounds are sampled (plus both ends).
const BOUND_SAMPLES: usize = 32;

/// Safety factor on sampled derivative bounds.
const BOUND_MARGIN: f64 = 1.1;

/// Smallest accepted parameter speed |P′(u)| relative to the chord: below it the curve
/// nearly stops and turns (a cusp), which no axis could follow at speed.
const MIN_PARAMETER_SPEED: f64 = 1e-3;

/// A quintic blend curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Quintic {
    /// Monomial coefficients per pose index: P(u) = Σ c[n]·uⁿ.
    c: [[f64; 6]; 9],
    from: Pose,
    to: Pose,
    /// Arc length from u = 0 to u = i / TABLE_INTERVALS.
    table: [f64; TABLE_INTERVALS + 1],
    bounds: AxisBounds,
    /// Pose indices whose coordinate changes along the curve (the others stay at `c[i][0]`
    /// and are skipped when evaluating).
    moving: [bool; 9],
}

/// P and its first three u-derivatives at one parameter value.
struct Derivs {
    p: [f64; 9],
    d1: [f64; 9],
    d2: [f64; 9],
    d3: [f64; 9],
}

fn dot(a: &[f64; 9], b: &[f64; 9]) -> f64 {
    Metric::Linear.dot(a, b)
}

impl Quintic {
    /// The blend from `start` to `end`, each given as a pose with its unit tangent (`d1`)
    /// and curvature vector (`d2`). `None` when the ends coincide, a value is not finite or
    /// the curve has a cusp.
    pub fn hermite(start: &PathPoint, end: &PathPoint) -> Option<Quintic> {
        Quintic::shape(start, end)?.finish()
    }

    /// The curve's coefficients only: enough for [`Quintic::pose_at_parameter`], which the
    /// tolerance check needs before the rest ([`Quintic::finish`]) is worth computing.
    pub(crate) fn shape(start: &PathPoint, end: &PathPoint) -> Option<Quintic> {
        let mut chord = [0.0; 9];
        for (i, c) in chord.iter_mut().enumerate() {
            *c = end.pose.0[i] - start.pose.0[i];
        }
        let lambda = Metric::Linear.norm(&chord);
        if !(lambda.is_finite() && lambda > 1e-12) {
            return None;
        }
        let mut c = [[0.0; 6]; 9];
        for (i, ci) in c.iter_mut().enumerate() {
            let d = chord[i];
            let (v0, v1) = (lambda * start.d1[i], lambda * end.d1[i]);
            let (w0, w1) = (lambda * lambda * start.d2[i], lambda * lambda * end.d2[i]);
            *ci = [
                start.pose.0[i],
                v0,
                0.5 * w0,
                10.0 * d - 6.0 * v0 - 4.0 * v1 - 0.5 * (3.0 * w0 - w1),
                -15.0 * d + 8.0 * v0 + 7.0 * v1 + 0.5 * (3.0 * w0 - 2.0 * w1),
                6.0 * d - 3.0 * v0 - 3.0 * v1 - 0.5 * (w0 - w1),
            ];
        }
        if !c.iter().flatten().all(|x| x.is_finite()) {
            return None;
        }
        let mut moving = [false; 9];
        for (m, ci) in moving.iter_mut().zip(&c) {
            *m = ci[1..].iter().any(|x| *x != 0.0);
        }
        Some(Quintic {
            c,
            from: start.pose,
            to: end.pose,
            table: [0.0; TABLE_INTERVALS + 1],
            bounds: AxisBounds::default(),
            moving,
        })
    }

    /// Completes a curve from [`Quintic::shape`]: refuses cusps, tabulates the arc length
    /// and samples the derivative bounds.
    pub(crate) fn finish(mut self) -> Option<Quintic> {
        let mut chord = [0.0; 9];
        for (i, c) in chord.iter_mut().enumerate() {
            *c = self.to.0[i] - self.from.0[i];
        }
        let lambda = Metric::Linear.norm(&chord);
        let q = &mut self;
        // Refuse cusps: the parameter speed must stay well away from zero.
        q.bounds = q.sample_bounds(MIN_PARAMETER_SPEED * lambda)?;
        let mut table = [0.0; TABLE_INTERVALS + 1];
        arclen::fill_table(&mut table, |u| q.speed(u));
        q.table = table;
        let total = table[TABLE_INTERVALS];
        if !(total.is_finite() && total > 0.0) {
            return None;
        }
        Some(self)
    }

    fn derivs(&self, u: f64) -> Derivs {
        let mut d = Derivs {
            p: [0.0; 9],
            d1: [0.0; 9],
            d2: [0.0; 9],
            d3: [0.0; 9],
        };
        for (i, c) in self.c.iter().enumerate() {
            if !self.moving[i] {
                d.p[i] = c[0];
                continue;
            }
            d.p[i] = c[0] + u * (c[1] + u * (c[2] + u * (c[3] + u * (c[4] + u * c[5]))));
            d.d1[i] =
                c[1] + u * (2.0 * c[2] + u * (3.0 * c[3] + u * (4.0 * c[4] + u * 5.0 * c[5])));
            d.d2[i] = 2.0 * c[2] + u * (6.0 * c[3] + u * (12.0 * c[4] + u * 20.0 * c[5]));
            d.d3[i] = 6.0 * c[3] + u * (24.0 * c[4] + u * 60.0 * c[5]);
        }
        d
    }

    /// |P′(u)| over the linear axes.
    fn speed(&self, u: f64) -> f64 {
        let mut sum = 0.0;
        for &i in Metric::Linear.axes() {
            if !self.moving[i] {
                continue;
            }
            let c = &self.c[i];
            let d1 = c[1] + u * (2.0 * c[2] + u * (3.0 * c[3] + u * (4.0 * c[4] + u * 5.0 * c[5])));
            sum += d1 * d1;
        }
        sum.sqrt()
    }

    /// Path length (mm).
    pub fn length(&self) -> f64 {
        self.table[TABLE_INTERVALS]
    }

    /// Start pose.
    pub fn start(&self) -> Pose {
        self.from
    }

    /// End pose.
    pub fn end(&self) -> Pose {
        self.to
    }

    /// The parameter u at path distance `s` (clamped to the curve).
    pub fn parameter_at(&self, s: f64) -> f64 {
        arclen::parameter_at(&self.table, s, |u| self.speed(u))
    }

    /// Pose and its first two derivatives with respect to path distance at `s`; exactly
    /// the start pose at `s = 0` and the end pose at the end.
    pub fn point(&self, s: f64) -> PathPoint {
        let u = self.parameter_at(s);
        let d = self.derivs(u);
        let (t1, t2, _) = arc_derivs(&d, &self.moving);
        let pose = if u <= 0.0 {
            self.from
        } else if u >= 1.0 {
            self.to
        } else {
            Pose(d.p)
        };
        PathPoint {
            pose,
            d1: t1,
            d2: t2,
        }
    }

    /// The pose at parameter `u` ∈ [0, 1].
    pub fn pose_at_parameter(&self, u: f64) -> Pose {
        let u = u.clamp(0.0, 1.0);
        let mut p = [0.0; 9];
        for (i, (x, c)) in p.iter_mut().zip(&self.c).enumerate() {
            *x = if self.moving[i] {
                c[0] + u * (c[1] + u * (c[2] + u * (c[3] + u * (c[4] + u * c[5]))))
            } else {
                c[0]
            };
        }
        Pose(p)
    }

    /// Bounds of |dⁿq/dsⁿ| per axis, n = 1, 2, 3 (sampled maxima times a margin).
    pub fn bounds(&self) -> AxisBounds {
        self.bounds
    }

    /// The sampled bounds; `None` when the parameter speed falls below `min_speed` at a
    /// sample (a cusp).
    fn sample_bounds(&self, min_speed: f64) -> Option<AxisBounds> {
        let mut b = AxisBounds::default();
        for k in 0..=BOUND_SAMPLES {
            let d = self.derivs(k as f64 / BOUND_SAMPLES as f64);
            let sigma = dot(&d.d1, &d.d1).sqrt();
            if sigma.is_nan() || sigma < min_speed {
                return None;
            }
            let (t1, t2, t3) = arc_derivs(&d, &self.moving);
            for i in 0..9 {
                b.d1[i] = b.d1[i].max(t1[i].abs());
                b.d2[i] = b.d2[i].max(t2[i].abs());
                b.d3[i] = b.d3[i].max(t3[i].abs());
            }
        }
        for x in b.d2.iter_mut().chain(b.d3.iter_mut()) {
            *x *= BOUND_MARGIN;
        }
        for (i, x) in b.d1.iter_mut().enumerate() {
            *x *= BOUND_MARGIN;
            // A unit tangent has no linear component above 1.
            if Metric::Linear.axes().contains(&i) {
                *x = x.min(1.0);
            }
        }
        // Blends join linear moves only: their path distance is the linear arc length.
        b.curvature = Metric::Linear.norm(&b.d2);
        Some(b)
    }
}

/// First three derivatives with respect to arc length from the u-derivatives:
/// with σ = |P′|, T₁ = P′/σ, T₂ = P″/σ² − P′σ′/σ³ and T₃ = (dT₂/du)/σ.
fn arc_derivs(d: &Derivs, moving: &[bool; 9]) -> ([f64; 9], [f64; 9], [f64; 9]) {
    let sigma = dot(&d.d1, &d.d1).sqrt().max(f64::MIN_POSITIVE);
    let s1 = dot(&d.d1, &d.d2) / sigma;
    let s2 = (dot(&d.d2, &d.d2) + dot(&d.d1, &d.d3) - s1 * s1) / sigma;
    let (i1, i2, i3, i4) = (
        1.0 / sigma,
        1.0 / (sigma * sigma),
        1.0 / sigma.powi(3),
        1.0 / sigma.powi(4),
    );
    let mut t1 = [0.0; 9];
    let mut t2 = [0.0; 9];
    let mut t3 = [0.0; 9];
    for i in 0..9 {
        if !moving[i] {
            continue;
        }
        let (x, y, z) = (d.d1[i], d.d2[i], d.d3[i]);
        t1[i] = x * i1;
        t2[i] = y * i2 - x * s1 * i3;
        let dt2 = z * i2 - 3.0 * y * s1 * i3 - x * s2 * i3 + 3.0 * x * s1 * s1 * i4;
        t3[i] = dt2 * i1;
    }
    (t1, t2, t3)
}
