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
//! The budget is split so the speed keeps a share of each limit for speeding up and slowing
//! down: the curvature term gets at most half of the acceleration limit (0.8 of it on arcs,
//! which leaves 0.6 in quadrature), c₃·V³ at most a quarter of the jerk limit, 3·c₂·V·A at
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

/// A moving axis: its limits, c₁, c₂, c₃ and the turning part W of c₁.
type Moving = (AxisLimits, f64, f64, f64, f64);

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
            Some(l) => moving[i] = Some((l, c1, c2, c3, bounds.wave[i].min(c1))),
            None => return Err(LimitError::AbsentAxis(axis)),
        }
    }
    let axes = || moving.iter().flatten();

    let mut v = feed.unwrap_or(f64::INFINITY);
    for &(l, c1, c2, c3, w) in axes() {
        if c1 > 0.0 {
            v = v.min(l.max_velocity / c1);
        }
        if c2 > 0.0 {
            let share = if w > 0.0 { ARC_CURVE_SHARE } else { 0.5 };
            v = v.min((share * l.max_acceleration / c2).sqrt());
        }
        if c3 > 0.0 {
            v = v.min((0.25 * l.max_jerk / c3).cbrt());
        }
    }
    let mut a = f64::INFINITY;
    for &(l, c1, c2, _, w) in axes() {
        let curve = c2 * v * v;
        if w > 0.0 {
            // √((W·A)² + X²) + o·A ≤ a_max holds for A = √(ã² − X²)/c₁ with
            // ã = a_max·(1 − o/c₁): o·A ≤ o·a_max/c₁ and W ≤ c₁.
            let am = l.max_acceleration * (1.0 - (c1 - w) / c1);
            a = a.min((am * am - curve * curve).max(0.0).sqrt() / c1);
            if v > 0.0 {
                a = a.min(ARC_JERK_SHARE * l.max_jerk / (3.0 * c2 * v));
            }
        } else {
            if c1 > 0.0 {
                a = a.min((l.max_acceleration - curve) / c1);
            }
            if c2 > 0.0 && v > 0.0 {
                a = a.min(l.max_jerk / (12.0 * c2 * v));
            }
        }
    }
    let mut j = f64::INFINITY;
    for &(l, c1, c2, c3, w) in axes() {
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
