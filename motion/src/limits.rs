//! Path limits from per-axis limits: how fast, how hard and how jerky the tool may move
//! along a stretch of path so that every axis stays within its own speed, acceleration and
//! jerk.
//!
//! For an axis position q(s) along the path and path speed v, acceleration a, jerk j:
//!
//! ```text
//! q̇ = q′·v        q̈ = q′·a + q″·v²        q⃛ = q′·j + 3·q″·v·a + q‴·v³
//! ```
//!
//! With c₁, c₂, c₃ bounds of |q′|, |q″|, |q‴| over the stretch ([`AxisBounds`]), each axis
//! stays within its (v, a, j) limits when
//!
//! ```text
//! c₁·v ≤ v_max      c₁·|a| + c₂·v² ≤ a_max      c₁·|j| + 3·c₂·v·|a| + c₃·v³ ≤ j_max
//! ```
//!
//! These are the per-axis inequalities of time-optimal path parameterisation, taken with
//! magnitudes over the stretch: on a short stretch (the planner cuts curves into pieces of
//! a few degrees of turning) they are close to the exact constraints at each point. They
//! depend on the path speed, so [`Dynamics`] keeps the bounds and answers per speed:
//! * the top speed ([`Dynamics::top_speed`]): the maximum-velocity curve of the stretch,
//!   where the centripetal terms c₂·v² and c₃·v³ still leave a share of the axis limits for
//!   speed changes ([`ACCEL_RESERVE`], [`JERK_RESERVE`]);
//! * the path acceleration at speed v ([`Dynamics::accel`]): what the centripetal term
//!   c₂·v² leaves of each axis limit, through c₁; it also leaves half of the jerk budget
//!   left after c₃·v³ to the path jerk, so the term 3·c₂·v·a (the rate of change of the
//!   centripetal acceleration as the speed changes) gets the other half;
//! * the path jerk at speed v and acceleration a ([`Dynamics::jerk`]).
//!
//! On a line (c₂ = c₃ = 0) these are exactly the axis limits projected on the direction.

use crate::config::AxisLimits;
use crate::geom::{AxisBounds, ZERO_LENGTH};
use crate::profile::PathLimits;
use klar_interp::AxisLetter;

/// Share of each axis's acceleration budget (at a standstill) that the top speed leaves for
/// speeding up and slowing down: at the top speed of a curved stretch the path acceleration
/// is still at least this share of what it is at rest.
pub const ACCEL_RESERVE: f64 = 0.1;

/// Share of each axis's jerk limit the curvature-change term c₃·v³ may not take at the top
/// speed.
pub const JERK_RESERVE: f64 = 0.2;

/// Why no path limits exist for a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LimitError {
    /// The segment moves an axis the machine does not have.
    AbsentAxis(AxisLetter),
}

/// The bounds and limits of one moving axis over a stretch.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct Term {
    c1: f64,
    c2: f64,
    c3: f64,
    vmax: f64,
    amax: f64,
    jmax: f64,
}

/// Speed-dependent path limits of one stretch of path (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dynamics {
    terms: [Term; 9],
    n: usize,
    /// Largest path speed the axes allow (no feed).
    top: f64,
    /// Path acceleration at rest.
    rest_accel: f64,
}

impl Dynamics {
    /// The limits of a stretch of `length` with derivative `bounds` on a machine with
    /// `limits`. Fails when a moving axis is not on the machine.
    pub fn new(
        bounds: &AxisBounds,
        length: f64,
        limits: &[Option<AxisLimits>; 9],
    ) -> Result<Dynamics, LimitError> {
        let mut d = Dynamics {
            terms: [Term::default(); 9],
            n: 0,
            top: f64::INFINITY,
            rest_accel: f64::INFINITY,
        };
        for (i, axis) in AxisLetter::ALL.into_iter().enumerate() {
            let (c1, c2, c3) = (bounds.d1[i], bounds.d2[i], bounds.d3[i]);
            // An axis moves when its excursion along the stretch is measurable.
            if c1 * length <= ZERO_LENGTH && c2 * length * length <= ZERO_LENGTH {
                continue;
            }
            let Some(l) = limits[i] else {
                return Err(LimitError::AbsentAxis(axis));
            };
            if let Some(t) = d.terms.get_mut(d.n) {
                *t = Term {
                    c1,
                    c2,
                    c3,
                    vmax: l.max_velocity,
                    amax: l.max_acceleration,
                    jmax: l.max_jerk,
                };
                d.n += 1;
            }
        }
        d.rest_accel = d.accel_only(0.0);
        let reserve = ACCEL_RESERVE * d.rest_accel;
        let mut top = f64::INFINITY;
        for t in d.terms() {
            if t.c1 > 0.0 {
                top = top.min(t.vmax / t.c1);
            }
            if t.c2 > 0.0 {
                let room = if t.c1 > 0.0 && reserve.is_finite() {
                    t.amax - reserve * t.c1
                } else {
                    t.amax
                };
                top = top.min((room.max(0.0) / t.c2).sqrt());
            }
            if t.c3 > 0.0 {
                top = top.min(((1.0 - JERK_RESERVE) * t.jmax / t.c3).cbrt());
            }
        }
        d.top = top;
        Ok(d)
    }

    fn terms(&self) -> &[Term] {
        self.terms.get(..self.n).unwrap_or(&[])
    }

    /// Largest path speed the axes allow on the stretch (the maximum-velocity curve).
    pub fn top_speed(&self) -> f64 {
        self.top
    }

    /// Path acceleration limit at rest.
    pub fn rest_accel(&self) -> f64 {
        self.rest_accel
    }

    /// The acceleration limit from the acceleration inequalities alone.
    fn accel_only(&self, v: f64) -> f64 {
        let mut a = f64::INFINITY;
        for t in self.terms() {
            if t.c1 > 0.0 {
                a = a.min((t.amax - t.c2 * v * v) / t.c1);
            }
        }
        a.max(0.0)
    }

    /// Path acceleration limit (speeding up or slowing down) at path speed `v` (at most
    /// [`Dynamics::top_speed`]).
    pub fn accel(&self, v: f64) -> f64 {
        let mut a = f64::INFINITY;
        for t in self.terms() {
            if t.c1 > 0.0 {
                a = a.min((t.amax - t.c2 * v * v) / t.c1);
            }
            if t.c2 > 0.0 && v > 0.0 {
                let left = t.jmax - t.c3 * v * v * v;
                a = a.min(left / (6.0 * t.c2 * v));
            }
        }
        a.max(0.0)
    }

    /// Path jerk limit at path speed `v` and |acceleration| `a`.
    pub fn jerk(&self, v: f64, a: f64) -> f64 {
        let mut j = f64::INFINITY;
        for t in self.terms() {
            if t.c1 > 0.0 {
                j = j.min((t.jmax - 3.0 * t.c2 * v * a - t.c3 * v * v * v) / t.c1);
            }
        }
        j.max(0.0)
    }

    /// Acceleration and jerk limits at speed `v`.
    pub fn at(&self, v: f64) -> (f64, f64) {
        let a = self.accel(v);
        (a, self.jerk(v, a))
    }

    /// Acceleration limit at speed `v` and jerk limit, both valid for every speed up to
    /// `top` ≥ `v` (the jerk share of the acceleration is kept at `top`, and the jerk taken
    /// there), so the jerk does not fall while the speed rises towards `top`.
    pub fn up_to(&self, v: f64, top: f64) -> (f64, f64) {
        let top = top.max(v);
        let share = self.jerk_share(top);
        // The jerk is taken for the largest acceleration allowed, so it does not change
        // with the speed either.
        let cap = if share.is_finite() {
            share.max(self.accel(top))
        } else {
            self.accel(v).max(self.accel(top))
        };
        (self.accel(v).min(cap), self.jerk(top, cap))
    }

    /// The acceleration the jerk budget allows at speed `v` (half of what c₃·v³ leaves).
    fn jerk_share(&self, v: f64) -> f64 {
        let mut a = f64::INFINITY;
        for t in self.terms() {
            if t.c2 > 0.0 && v > 0.0 {
                a = a.min((t.jmax - t.c3 * v * v * v) / (6.0 * t.c2 * v));
            }
        }
        a.max(0.0)
    }
}

/// Path limits of a segment of `length` with derivative `bounds`, at the programmed path
/// speed `feed` (`None` for rapid traverse: as fast as the axes allow): the top speed, and
/// the acceleration and jerk limits at that speed.
pub fn path_limits(
    bounds: &AxisBounds,
    length: f64,
    limits: &[Option<AxisLimits>; 9],
    feed: Option<f64>,
) -> Result<PathLimits, LimitError> {
    let d = Dynamics::new(bounds, length, limits)?;
    let v = d.top_speed().min(feed.unwrap_or(f64::INFINITY));
    let (a, j) = d.at(v);
    Ok(PathLimits {
        velocity: v,
        acceleration: a,
        jerk: j,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn axis(v: f64, a: f64, j: f64) -> Option<AxisLimits> {
        Some(AxisLimits {
            max_velocity: v,
            max_acceleration: a,
            max_jerk: j,
        })
    }

    fn xy(l: Option<AxisLimits>) -> [Option<AxisLimits>; 9] {
        [l, l, None, None, None, None, None, None, None]
    }

    #[test]
    fn a_diagonal_line_gets_the_axis_limits_over_the_direction_cosine() {
        // Unit direction (1, 1)/√2: each axis sees 1/√2 of the path values.
        let c = std::f64::consts::FRAC_1_SQRT_2;
        let mut b = AxisBounds::default();
        b.d1[0] = c;
        b.d1[1] = c;
        let d = Dynamics::new(&b, 10.0, &xy(axis(100.0, 1000.0, 1e5))).expect("axes present");
        let root2 = 2f64.sqrt();
        assert!((d.top_speed() - 100.0 * root2).abs() < 1e-9);
        assert!((d.accel(50.0) - 1000.0 * root2).abs() < 1e-9);
        assert!((d.jerk(50.0, 500.0) - 1e5 * root2).abs() < 1e-6);
    }

    #[test]
    fn on_a_circle_where_one_axis_carries_the_centripetal_term() {
        // Radius r, at the point where the tangent is +Y: X has q′ = 0, q″ = 1/r, and Y
        // has q′ = 1, q‴ = 1/r² (bounds over a stretch around that point).
        let r = 10.0;
        let mut b = AxisBounds::default();
        b.d2[0] = 1.0 / r;
        b.d1[1] = 1.0;
        b.d3[1] = 1.0 / (r * r);
        let (amax, jmax) = (1000.0, 1e5);
        let d = Dynamics::new(&b, 1.0, &xy(axis(500.0, amax, jmax))).expect("axes present");
        // X: v²/r ≤ a_max (no tangential share on X), so the top speed is √(a_max·r).
        assert!((d.top_speed() - (amax * r).sqrt()).abs() < 1e-9);
        // Y takes the path acceleration alone; X's jerk share caps it: 3·v·a/r ≤ j_max/2.
        let v = 50.0;
        let expected = amax.min(jmax * r / (6.0 * v));
        assert!((d.accel(v) - expected).abs() < 1e-9);
        // Y's jerk: j_max − v³/r² (X has no tangential share).
        assert!((d.jerk(v, expected) - (jmax - v * v * v / (r * r))).abs() < 1e-6);
    }

    #[test]
    fn an_absent_moving_axis_is_refused() {
        let mut b = AxisBounds::default();
        b.d1[2] = 1.0;
        let got = Dynamics::new(&b, 5.0, &xy(axis(1.0, 1.0, 1.0)));
        assert_eq!(got.err(), Some(LimitError::AbsentAxis(AxisLetter::Z)));
    }
}
