//! The quintic Hermite blend curve, parameterised by path distance.
//!
//! With end points A, B, unit tangents t₀, t₁, curvature vectors k₀, k₁ and the chord
//! λ = |B − A|, the curve P(u), u ∈ [0, 1], has P(0) = A, P′(0) = λ·t₀, P″(0) = λ²·k₀ and the
//! same at u = 1 with B, t₁, k₁. Since k ⊥ t, the arc-length derivatives at the ends are
//! exactly t and k: the curve continues position, tangent and curvature of its neighbours.
//!
//! Path distance is the arc length over X Y Z U V W, tabulated by [`crate::geom::arclen`]
//! (Gauss–Legendre quadrature on 2 or [`TABLE_INTERVALS`] intervals of u, inverted by
//! safeguarded Newton steps).

use super::bounds::{Exact, derivative_bounds};
use super::memo::{BoundsMemo, MemoKey};
use crate::geom::{AxisBounds, Metric, PathPoint, arclen};
use klar_interp::Pose;

/// Intervals of u in the arc-length table at most.
pub const TABLE_INTERVALS: usize = 16;

/// Smallest accepted parameter speed |P′(u)| relative to the chord: below it the curve
/// nearly stops and turns (a cusp), which no axis could follow at speed.
const MIN_PARAMETER_SPEED: f64 = 1e-3;

/// A quintic blend curve. The default is the empty curve at the origin (length 0): what
/// the slots of a [`super::BlendPool`] hold before a blend is written into them.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Quintic {
    /// Monomial coefficients per pose index: P(u) = Σ c[n]·uⁿ.
    c: [[f64; 6]; 9],
    from: Pose,
    to: Pose,
    /// Arc length from u = 0 to u = i / intervals.
    table: [f64; TABLE_INTERVALS + 1],
    /// Intervals of u used in `table` (at most [`TABLE_INTERVALS`]).
    intervals: usize,
    bounds: AxisBounds,
    /// Pose indices whose coordinate changes along the curve (the others stay at `c[i][0]`
    /// and are skipped when evaluating).
    moving: [bool; 9],
    /// Coefficients of |P′(u)|² over the linear axes (lowest first), set by `finish`.
    speed2: [f64; 9],
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
        let mut q = Quintic::shape(start, end)?;
        q.finish(&mut BoundsMemo::new(0))?;
        Some(q)
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
            intervals: TABLE_INTERVALS,
            bounds: AxisBounds::default(),
            moving,
            speed2: [0.0; 9],
        })
    }

    /// Completes a curve from [`Quintic::shape`]: refuses cusps, bounds the derivatives
    /// (taken from `memo` where a blend with the same derivatives was bounded before) and
    /// tabulates the arc length.
    pub(crate) fn finish(&mut self, memo: &mut BoundsMemo) -> Option<()> {
        self.bounds = self.bounds_over(0.0, 1.0, memo)?;
        self.speed2 = self.speed_squared();
        let mut table = [0.0; TABLE_INTERVALS + 1];
        self.intervals = arclen::fill_table_adaptive(&mut table, |u| self.speed(u));
        self.table = table;
        let total = self.length();
        (total.is_finite() && total > 0.0).then_some(())
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
        let g = self.speed2.iter().rev().fold(0.0, |acc, k| acc * u + k);
        g.max(0.0).sqrt()
    }

    /// The coefficients of |P′(u)|² over the linear axes.
    fn speed_squared(&self) -> [f64; 9] {
        let mut g = [0.0; 9];
        for &i in Metric::Linear.axes() {
            if !self.moving[i] {
                continue;
            }
            let c = &self.c[i];
            let d = [c[1], 2.0 * c[2], 3.0 * c[3], 4.0 * c[4], 5.0 * c[5]];
            for (j, a) in d.iter().enumerate() {
                for (k, b) in d.iter().enumerate() {
                    g[j + k] += a * b;
                }
            }
        }
        g
    }

    /// Path length (mm).
    pub fn length(&self) -> f64 {
        self.table().last().copied().unwrap_or(0.0)
    }

    /// The used part of the arc-length table.
    fn table(&self) -> &[f64] {
        self.table.get(..=self.intervals).unwrap_or(&self.table)
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
        arclen::parameter_at(self.table(), s, |u| self.speed(u))
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

    /// The curve's Bézier control points (Bernstein coefficients on u ∈ [0, 1]): the curve
    /// lies in their convex hull.
    pub(crate) fn control_points(&self) -> [Pose; 6] {
        let mut b = [Pose([0.0; 9]); 6];
        for (i, c) in self.c.iter().enumerate() {
            // bⱼ = Σₖ₌₀..ⱼ C(j, k) / C(5, k) · cₖ.
            let (c1, c2, c3, c4) = (c[1] / 5.0, c[2] / 10.0, c[3] / 10.0, c[4] / 5.0);
            b[0].0[i] = c[0];
            b[1].0[i] = c[0] + c1;
            b[2].0[i] = c[0] + 2.0 * c1 + c2;
            b[3].0[i] = c[0] + 3.0 * c1 + 3.0 * c2 + c3;
            b[4].0[i] = c[0] + 4.0 * c1 + 6.0 * c2 + 4.0 * c3 + c4;
            b[5].0[i] = c[0] + c[1] + c[2] + c[3] + c[4] + c[5];
        }
        b
    }

    /// Bounds of |dⁿq/dsⁿ| per axis, n = 1, 2, 3, over the whole curve (see
    /// `blend::bounds`).
    pub fn bounds(&self) -> AxisBounds {
        self.bounds
    }

    /// Bounds of |dⁿq/dsⁿ| per axis, n = 1, 2, 3, and of the curvature over the part of the
    /// curve from path distance `from` to `to` (clamped to the curve); the whole curve's
    /// bounds where the part's cannot be had.
    pub fn bounds_between(&self, from: f64, to: f64) -> AxisBounds {
        self.bounds_between_in(from, to, &mut BoundsMemo::new(0))
    }

    /// [`Quintic::bounds_between`], taking the bounds from `memo` where the same stretch of
    /// a blend with the same derivatives was bounded before.
    pub fn bounds_between_in(&self, from: f64, to: f64, memo: &mut BoundsMemo) -> AxisBounds {
        let (u0, u1) = (self.parameter_at(from), self.parameter_at(to));
        if u0 <= 0.0 && u1 >= 1.0 {
            return self.bounds;
        }
        self.bounds_over(u0, u1.max(u0), memo)
            .map_or(self.bounds, |b| tighter(&b, &self.bounds))
    }

    /// Derivative bounds over u ∈ [u0, u1] ([`derivative_bounds`]); `None` where the curve
    /// has a cusp there: the parameter speed must stay well away from zero. They depend on
    /// the derivatives, the smallest speed and the range only: `memo` holds them by those.
    fn bounds_over(&self, u0: f64, u1: f64, memo: &mut BoundsMemo) -> Option<AxisBounds> {
        let chord: [f64; 9] = std::array::from_fn(|i| self.to.0[i] - self.from.0[i]);
        let min_speed = MIN_PARAMETER_SPEED * Metric::Linear.norm(&chord);
        let key = MemoKey::new(&self.c, &self.moving, min_speed, (u0, u1));
        memo.get_or_compute(&key, || {
            derivative_bounds(&self.c, &self.moving, min_speed, (u0, u1), |u| {
                self.exact(u)
            })
        })
    }

    /// Exact arc-length derivatives and the parameter speed at `u`.
    fn exact(&self, u: f64) -> Exact {
        let d = self.derivs(u);
        let sigma = dot(&d.d1, &d.d1).sqrt();
        let (t1, t2, t3) = arc_derivs(&d, &self.moving);
        Exact {
            t: [t1, t2, t3],
            sigma,
        }
    }
}

/// The smaller of two bounds of the same curve, value by value.
fn tighter(a: &AxisBounds, b: &AxisBounds) -> AxisBounds {
    let min = |x: &[f64; 9], y: &[f64; 9]| std::array::from_fn(|i| x[i].min(y[i]));
    AxisBounds {
        d1: min(&a.d1, &b.d1),
        d2: min(&a.d2, &b.d2),
        d3: min(&a.d3, &b.d3),
        wave: min(&a.wave, &b.wave),
        curvature: a.curvature.min(b.curvature),
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A path point from position, tangent and curvature vector in X Y Z (plus extra axes).
    fn at(p: [f64; 3], t: [f64; 3], k: [f64; 3]) -> PathPoint {
        let mut pp = PathPoint {
            pose: Pose::ZERO,
            d1: [0.0; 9],
            d2: [0.0; 9],
        };
        pp.pose.0[..3].copy_from_slice(&p);
        pp.d1[..3].copy_from_slice(&t);
        pp.d2[..3].copy_from_slice(&k);
        pp
    }

    /// Blends of different character: sharp and gentle line corners, a short stretch of a
    /// circle (dense CAM code), a spatial corner, and one with a rotary axis turning along.
    fn blends() -> Vec<Quintic> {
        let mut v = Vec::new();
        for deg in [5.0f64, 30.0, 60.0, 90.0, 119.0] {
            let th = deg.to_radians();
            let d = 0.7;
            let a = at([-d, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0; 3]);
            let b = at(
                [d * th.cos(), d * th.sin(), 0.0],
                [th.cos(), th.sin(), 0.0],
                [0.0; 3],
            );
            v.push(Quintic::hermite(&a, &b).expect("corner blend"));
        }
        // Circle R25, 2000 chords per turn: from one chord midpoint to the next.
        let r = 25.0;
        let circle = |phi: f64| {
            at(
                [r * phi.cos(), r * phi.sin(), 0.0],
                [-phi.sin(), phi.cos(), 0.0],
                [-phi.cos() / r, -phi.sin() / r, 0.0],
            )
        };
        let step = std::f64::consts::TAU / 2000.0;
        v.push(Quintic::hermite(&circle(0.3), &circle(0.3 + step)).expect("arc blend"));
        // A corner in space with a curvature jump at one end.
        let n = (1.0f64 + 0.25 + 0.04).sqrt();
        let a = at([0.0; 3], [1.0 / n, 0.5 / n, 0.2 / n], [0.0, 0.0, 0.0]);
        let b = at([0.5, 0.6, 0.3], [0.0, 1.0, 0.0], [-2.0, 0.0, 0.0]);
        v.push(Quintic::hermite(&a, &b).expect("spatial blend"));
        // X Y corner with A turning 10°/mm along it.
        let mut a = at([-0.5, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0; 3]);
        let mut b = at([0.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0; 3]);
        a.d1[3] = 10.0;
        b.d1[3] = 10.0;
        b.pose.0[3] = 7.5;
        v.push(Quintic::hermite(&a, &b).expect("blend with a rotary axis"));
        v
    }

    #[test]
    fn derivative_bounds_cover_dense_samples_and_finite_differences() {
        for q in blends() {
            let b = q.bounds();
            // Exact derivatives on a grid 64 times finer than any interval bound.
            for k in 0..=2048 {
                let e = q.exact(k as f64 / 2048.0);
                for i in 0..9 {
                    assert!(
                        e.t[0][i].abs() <= b.d1[i],
                        "q′ axis {i}: {} > {}",
                        e.t[0][i],
                        b.d1[i]
                    );
                    assert!(
                        e.t[1][i].abs() <= b.d2[i],
                        "q″ axis {i}: {} > {}",
                        e.t[1][i],
                        b.d2[i]
                    );
                    assert!(
                        e.t[2][i].abs() <= b.d3[i],
                        "q‴ axis {i}: {} > {}",
                        e.t[2][i],
                        b.d3[i]
                    );
                }
            }
            // Independently of the chord-rule formulas: central differences of the pose
            // along the path (step h; their error is far below the 2 % allowed).
            let len = q.length();
            let h = len / 400.0;
            let pos = |s: f64| q.point(s).pose.0;
            let mut s = 2.0 * h;
            while s <= len - 2.0 * h {
                let (m2, m1, p0, p1, p2) = (
                    pos(s - 2.0 * h),
                    pos(s - h),
                    pos(s),
                    pos(s + h),
                    pos(s + 2.0 * h),
                );
                for i in 0..9 {
                    let d2 = (p1[i] - 2.0 * p0[i] + m1[i]) / (h * h);
                    let d3 = (p2[i] - 2.0 * p1[i] + 2.0 * m1[i] - m2[i]) / (2.0 * h * h * h);
                    assert!(
                        d2.abs() <= 1.02 * b.d2[i] + 1e-6,
                        "fd q″ axis {i} at {s}: {d2} > {}",
                        b.d2[i]
                    );
                    assert!(
                        d3.abs() <= 1.02 * b.d3[i] + 1e-3 * (1.0 + b.d3[i]),
                        "fd q‴ axis {i} at {s}: {d3} > {}",
                        b.d3[i]
                    );
                }
                s += h;
            }
        }
    }

    #[test]
    fn derivative_bounds_exceed_the_largest_value_by_a_tenth_at_most() {
        // Where the interval bounds are tight, each bound is 1.1 times exact values; an axis
        // whose bound is below 1 % of the largest of the same order may keep a wider one.
        for (j, q) in blends().into_iter().enumerate() {
            let b = q.bounds();
            let mut top = [[0.0f64; 9]; 3];
            for k in 0..=4096 {
                let e = q.exact(k as f64 / 4096.0);
                for (top_n, t_n) in top.iter_mut().zip(&e.t) {
                    for (m, t) in top_n.iter_mut().zip(t_n) {
                        *m = m.max(t.abs());
                    }
                }
            }
            for i in 0..9 {
                for (n, bound) in [b.d1[i], b.d2[i], b.d3[i]].into_iter().enumerate() {
                    let floor = 0.011 * top[n].iter().fold(0.0f64, |m, x| m.max(*x));
                    assert!(
                        bound <= (1.1 * top[n][i]).max(floor) * (1.0 + 1e-9),
                        "blend {j} order {} axis {i}: {bound} vs largest {}",
                        n + 1,
                        top[n][i]
                    );
                }
            }
        }
    }

    #[test]
    fn bounds_of_a_stretch_cover_it_and_stay_within_the_whole_curves() {
        for q in blends() {
            let whole = q.bounds();
            let len = q.length();
            for (from, to) in [(0.0, 0.25), (0.25, 0.5), (0.4, 0.9), (0.75, 1.0)] {
                let (a, b) = (from * len, to * len);
                let part = q.bounds_between(a, b);
                let (u0, u1) = (q.parameter_at(a), q.parameter_at(b));
                for k in 0..=512 {
                    let e = q.exact(u0 + (u1 - u0) * k as f64 / 512.0);
                    let kappa = Metric::Linear.norm(&e.t[1]);
                    assert!(kappa <= part.curvature, "κ {kappa} > {}", part.curvature);
                    for i in 0..9 {
                        for n in 0..3 {
                            let bound = [part.d1[i], part.d2[i], part.d3[i]][n];
                            assert!(
                                e.t[n][i].abs() <= bound,
                                "order {} axis {i} on {from}..{to}: {} > {bound}",
                                n + 1,
                                e.t[n][i]
                            );
                        }
                    }
                }
                for i in 0..9 {
                    assert!(part.d2[i] <= whole.d2[i] && part.d3[i] <= whole.d3[i]);
                }
                assert!(part.curvature <= whole.curvature);
            }
            // The curvature bound is never above the norm of the per-axis bounds, and not
            // far above the curvature found on a fine grid.
            let top = (0..=4096)
                .map(|k| Metric::Linear.norm(&q.exact(k as f64 / 4096.0).t[1]))
                .fold(0.0, f64::max);
            assert!(whole.curvature <= Metric::Linear.norm(&whole.d2) * (1.0 + 1e-12));
            assert!(
                whole.curvature <= 1.1 * top + 1e-9,
                "{} vs {top}",
                whole.curvature
            );
        }
    }

    #[test]
    fn a_blend_that_nearly_stops_and_turns_is_refused() {
        // Ends 1 µm apart with opposite tangents: the curve has to turn back on itself.
        let a = at([0.0; 3], [1.0, 0.0, 0.0], [0.0; 3]);
        let b = at([1e-3, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0; 3]);
        assert!(Quintic::hermite(&a, &b).is_none());
    }
}
