//! Mapping the points of an op, shared by the transforms that move ops as a whole (the
//! coordinate transform cycles, the tilted working plane): the ends of lines, splines and
//! APPR/DEP paths go through a point map, and the X Y Z coefficients of a spline through
//! the linear part of that map.

use crate::op::{AxisLetter, OpKind, Pose, SplineAxis};

/// `kind` with its points passed through `point` and, for a spline, its X Y Z coefficients
/// through `vector`; every other field unchanged. `None` for any op but a line, a spline,
/// APPR or DEP (arcs and the rest are each transform's own).
pub(super) fn map_points(
    kind: &OpKind,
    point: impl Fn(&Pose) -> Pose,
    vector: impl Fn([f64; 3]) -> [f64; 3],
) -> Option<OpKind> {
    let mut out = kind.clone();
    match &mut out {
        OpKind::Line { from, to, .. } | OpKind::Approach { from, to, .. } => {
            *from = point(from);
            *to = point(to);
        }
        OpKind::Spline { from, to, axes, .. } => {
            *from = point(from);
            *to = point(to);
            *axes = map_spline(axes, vector);
        }
        OpKind::Depart { from, to, .. } => {
            *from = point(from);
            *to = to.as_ref().map(&point);
        }
        _ => return None,
    }
    Some(out)
}

/// Spline coefficients with the X, Y, Z coefficients of each power of t taken as a vector
/// through `vector` (the other axes keep theirs). An axis of X, Y, Z appears in the result
/// when it had coefficients or gets non-zero ones; the result is sorted by axis.
pub(super) fn map_spline(
    axes: &[SplineAxis],
    vector: impl Fn([f64; 3]) -> [f64; 3],
) -> Vec<SplineAxis> {
    let mut k = [[0.0; 3]; 3]; // k[power][X/Y/Z]
    let mut present = [false; 3];
    let mut out = Vec::with_capacity(axes.len() + 2);
    for ax in axes {
        let i = ax.axis.index();
        if i < 3 {
            present[i] = true;
            for (row, value) in k.iter_mut().zip(ax.k) {
                row[i] = value;
            }
        } else {
            out.push(*ax);
        }
    }
    let mapped = k.map(vector);
    for (i, letter) in [AxisLetter::X, AxisLetter::Y, AxisLetter::Z]
        .into_iter()
        .enumerate()
    {
        let c = [mapped[0][i], mapped[1][i], mapped[2][i]];
        if present[i] || c.iter().any(|v| *v != 0.0) {
            out.push(SplineAxis { axis: letter, k: c });
        }
    }
    out.sort_by_key(|a| a.axis);
    out
}
