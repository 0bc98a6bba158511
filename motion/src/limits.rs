//! Path limits from per-axis limits: how fast, how hard and how jerky the tool may move
//! along one segment so that every axis stays within its own speed, acceleration and jerk.
//!
//! For an axis position q(s) along the path and path speed v, acceleration a, jerk j:
//!
//! ```text
//! q̇ = q′·v        q̈ = q′·a + q″·v²        q⃛ = q′·j + 3·q″·v·a + q‴·v³
//! ```
//!
//! With c₁, c₂, c₃ the segment's bounds of |q′|, |q″|, |q‴| ([`AxisBounds`]) and constant
//! path limits V, A, J over the segment, each axis stays within (v, a, j) limits when
//!
//! ```text
//! c₁·V ≤ v_max      c₁·A + c₂·V² ≤ a_max      c₁·J + 3·c₂·V·A + c₃·V³ ≤ j_max
//! ```
//!
//! The peak magnitudes are added, which is conservative where they occur at different
//! places. On the in-plane axes of an arc or helix they do: there `q′ = −W·sin θ + o`,
//! `q″ = −c₂·cos θ`, `q‴ = c₃·sin θ` (W the turning part of c₁, o = c₁ − W a constant end
//! correction), so the terms add in quadrature instead:
//!
//! ```text
//! √((W·A)² + (c₂·V²)²) + o·A ≤ a_max      √((W·J + c₃·V³)² + (3·c₂·V·A)²) + o·J ≤ j_max
//! ```
//!
//! More generally, on any move whose path distance is its length over the linear axes, the
//! unit tangent q′ and the curvature vector q″ (length κ) are orthogonal, so each linear
//! axis's acceleration `q′·A + q″·V²` is at most `√(A² + (κ·V²)²)` (Cauchy–Schwarz with
//! `q′ᵢ² + (q″ᵢ/κ)² ≤ 1`). Blends and splines use whichever of the two forms allows more.
//!
//! The budget is split so the speed keeps a share of each limit for speeding up and slowing
//! down: the curvature term gets at most half of the acceleration limit (0.8 of it where the
//! quadrature applies, which leaves 0.6), c₃·V³ at most a quarter of the jerk limit, 3·c₂·V·A at
//! most a quarter (0.6 in quadrature on arcs); A and J then take what is left. On a line
//! (c₂ = c₃ = 0) this is exactly the axis limits projected on the direction.

use crate::config::AxisLimits;
use crate::geom::{AxisBounds, ZERO_LENGTH};
use crate::profile::PathLimits;
use klar_interp::AxisLetter;

/// Share of an axis's acceleration limit the curvature term c₂·V² may take on an arc (the
/// rest, √(1 − 0.8²) = 0.6 of the limit in quadrature, is left for changing speed).
const ARC_CURVE_SHARE: f64 = 0.8;

/// Share of an axis's jerk limit the term 3·c₂·V·A may take on an arc (0.8 of the limit is
/// left in quadrature for the path jerk and c₃·V³).
const ARC_JERK_SHARE: f64 = 0.6;

/// A moving axis: its limits, the bounds c₁, c₂, c₃, the turning part W of c₁ (arcs) and
/// the curvature bound κ that applies to it (linear axes of a linear move, else 0).
#[derive(Debug, Clone, Copy)]
struct Moving {
    l: AxisLimits,
    c1: f64,
    c2: f64,
    c3: f64,
    wave: f64,
    kappa: f64,
}

/// Why no path limits exist for a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LimitError {
    /// The segment moves an axis the machine does not have.
    AbsentAxis(AxisLetter),
}

/// Path limits of a segment of `length` with derivative `bounds`, at the programmed path
/// speed `feed` (`None` for rapid traverse: as fast as the axes allow).
pub fn path_limits(
    bounds: &AxisBounds,
    length: f64,
    limits: &[Option<AxisLimits>; 9],
    feed: Option<f64>,
) -> Result<PathLimits, LimitError> {
    let mut moving: [Option<Moving>; 9] = [None; 9];
    for (i, axis) in AxisLetter::ALL.into_iter().enumerate() {
        let (c1, c2, c3) = (bounds.d1[i], bounds.d2[i], bounds.d3[i]);
        // An axis moves when its excursion along the segment is measurable.
        if c1 * length <= ZERO_LENGTH && c2 * length * length <= ZERO_LENGTH {
            continue;
        }
        match limits[i] {
            Some(l) => {
                moving[i] = Some(Moving {
                    l,
                    c1,
                    c2,
                    c3,
                    wave: bounds.wave[i].min(c1),
                    kappa: if axis.is_rotary() {
                        0.0
                    } else {
                        bounds.curvature
                    },
                })
            }
            None => return Err(LimitError::AbsentAxis(axis)),
        }
    }
    let axes = || moving.iter().flatten();

    let mut v = feed.unwrap_or(f64::INFINITY);
    for m in axes() {
        let l = m.l;
        if m.c1 > 0.0 {
            v = v.min(l.max_velocity / m.c1);
        }
        if m.c2 > 0.0 {
            let mut top = if m.wave > 0.0 {
                (ARC_CURVE_SHARE * l.max_acceleration / m.c2).sqrt()
            } else {
                (0.5 * l.max_acceleration / m.c2).sqrt()
            };
            if m.kappa > 0.0 {
                top = top.max((ARC_CURVE_SHARE * l.max_acceleration / m.kappa).sqrt());
            }
            v = v.min(top);
        }
        if m.c3 > 0.0 {
            v = v.min((0.25 * l.max_jerk / m.c3).cbrt());
        }
    }
    let mut a = f64::INFINITY;
    for m in axes() {
        let (l, c1, c2, w) = (m.l, m.c1, m.c2, m.wave);
        let curve = c2 * v * v;
        // Any curve in arc length: √(A² + (κ·V²)²) ≤ a_max on a linear axis.
        let quad = if m.kappa > 0.0 {
            let k = m.kappa * v * v;
            (l.max_acceleration * l.max_acceleration - k * k)
                .max(0.0)
                .sqrt()
        } else {
            0.0
        };
        let mut ai = if w > 0.0 {
            // √((W·A)² + X²) + o·A ≤ a_max holds for A = √(ã² − X²)/c₁ with
            // ã = a_max·(1 − o/c₁): o·A ≤ o·a_max/c₁ and W ≤ c₁.
            let am = l.max_acceleration * (1.0 - (c1 - w) / c1);
            ((am * am - curve * curve).max(0.0).sqrt() / c1).max(quad)
        } else if c1 > 0.0 {
            ((l.max_acceleration - curve) / c1).max(quad)
        } else {
            quad.max(if curve <= l.max_acceleration {
                f64::INFINITY
            } else {
                0.0
            })
        };
        if c2 > 0.0 && v > 0.0 {
            let share = if w > 0.0 {
                ARC_JERK_SHARE / 3.0
            } else {
                1.0 / 12.0
            };
            ai = ai.min(share * l.max_jerk / (c2 * v));
        }
        a = a.min(ai);
    }
    let mut j = f64::INFINITY;
    for m in axes() {
        let (l, c1, c2, c3, w) = (m.l, m.c1, m.c2, m.c3, m.wave);
        if c1 <= 0.0 {
            continue;
        }
        if w > 0.0 {
            // The same construction as for the acceleration.
            let jm = l.max_jerk * (1.0 - (c1 - w) / c1);
            let cross = 3.0 * c2 * v * a;
            j = j.min(((jm * jm - cross * cross).max(0.0).sqrt() - c3 * v.powi(3)) / c1);
        } else {
            j = j.min((l.max_jerk - 3.0 * c2 * v * a - c3 * v.powi(3)) / c1);
        }
    }
    Ok(PathLimits {
        velocity: v,
        acceleration: a,
        jerk: j,
    })
}
