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
//! This is conservative (it adds peak magnitudes that on an arc occur at different angles).
//! The budget is split so the curvature terms use at most half of each axis limit:
//! c₂·V² ≤ a_max/2, c₃·V³ ≤ j_max/4 and 3·c₂·V·A ≤ j_max/4; A and J then take what is left.
//! On a line (c₂ = c₃ = 0) this is exactly the axis limits projected on the direction.

use crate::config::AxisLimits;
use crate::geom::{AxisBounds, ZERO_LENGTH};
use crate::profile::PathLimits;
use klar_interp::AxisLetter;

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
    let mut moving: [Option<(AxisLimits, f64, f64, f64)>; 9] = [None; 9];
    for (i, axis) in AxisLetter::ALL.into_iter().enumerate() {
        let (c1, c2, c3) = (bounds.d1[i], bounds.d2[i], bounds.d3[i]);
        // An axis moves when its excursion along the segment is measurable.
        if c1 * length <= ZERO_LENGTH && c2 * length * length <= ZERO_LENGTH {
            continue;
        }
        match limits[i] {
            Some(l) => moving[i] = Some((l, c1, c2, c3)),
            None => return Err(LimitError::AbsentAxis(axis)),
        }
    }
    let axes = || moving.iter().flatten();

    let mut v = feed.unwrap_or(f64::INFINITY);
    for &(l, c1, c2, c3) in axes() {
        if c1 > 0.0 {
            v = v.min(l.max_velocity / c1);
        }
        if c2 > 0.0 {
            v = v.min((0.5 * l.max_acceleration / c2).sqrt());
        }
        if c3 > 0.0 {
            v = v.min((0.25 * l.max_jerk / c3).cbrt());
        }
    }
    let mut a = f64::INFINITY;
    for &(l, c1, c2, _) in axes() {
        if c1 > 0.0 {
            a = a.min((l.max_acceleration - c2 * v * v) / c1);
        }
        if c2 > 0.0 && v > 0.0 {
            a = a.min(l.max_jerk / (12.0 * c2 * v));
        }
    }
    let mut j = f64::INFINITY;
    for &(l, c1, c2, c3) in axes() {
        if c1 > 0.0 {
            j = j.min((l.max_jerk - 3.0 * c2 * v * a - c3 * v.powi(3)) / c1);
        }
    }
    Ok(PathLimits {
        velocity: v,
        acceleration: a,
        jerk: j,
    })
}
