//! Runs of dense code: a stretch of short lines blended as one curve between split points
//! (see [`super::path`] for where runs fit among the corner rules).

use super::path::{
    Committed, Element, NewPiece, SPLIT_MAX_ANGLE, Shape, Vertices, Waiting, angle, gentle,
    min_feed,
};
use super::smooth::{end_point, split_point};
use crate::blend::{BlendPool, ContourPart, blend_within};
use crate::geom::{Metric, PathPoint, Segment};
use crate::limits::Headroom;

/// Path length (mm) a blend through dense code spans at most: a run of short lines is
/// blended as one curve between split points this far apart, over which the noise of their
/// fits ([`split_point`]) bends the curve far less than between neighbouring chords.
pub const RUN_LENGTH: f64 = 1.0;

/// Lines a run spans at most.
pub const RUN_ELEMENTS: usize = 64;

/// True for a line that moves linear axes only (runs leave rotary moves, whose limits
/// depend on the machine's kinematics along the way, to blends between neighbours).
fn linear_only(e: &Element) -> bool {
    e.is_linear_line() && Metric::Rotary.norm(&e.segment.point(0.0).d1) == 0.0
}

/// Blends a run of dense code: from the split point `cur` starts at (or its start, where
/// the path stands still) to the split point of a later short line, using up the short
/// lines between. The run ends at the last line within [`RUN_LENGTH`] whose corners a split
/// point allows, or at the end of the last line before a stop (`last`); where the blend
/// leaves the tolerance band, runs half as long are tried. `None` when no run of at least
/// two lines fits (the corner is then decided as usual), or when `pool` has no free slot
/// for the run's curve.
pub(super) fn try_run(
    cur: &Element,
    rest: &mut [Waiting],
    last: bool,
    vertices: &Vertices<'_>,
    pool: &mut BlendPool,
) -> Option<Committed> {
    if !linear_only(cur) || !pool.has_free() {
        return None;
    }
    let len = cur.segment.length();
    let mut tol = cur.tolerance;
    let mut reach = len - cur.trim;
    let mut prev = cur.segment.point(len).d1;
    let mut longest = 0;
    let mut to_stop = None;
    for j in 0..rest.len().min(RUN_ELEMENTS + 1) {
        let e = &rest[j].element;
        // A run is planned at one feed: it ends where the feed changes, and the corner
        // there is blended with each feed on its own side (`path::blend_parts`).
        if !linear_only(e) || e.feed != cur.feed {
            break;
        }
        let lj = e.segment.length();
        let dir = e.segment.point(0.0).d1;
        let t = tol.min(e.tolerance);
        let Some(after) = rest.get(j + 1).map(|w| &w.element) else {
            // The last line before a stop: the run may end at its end.
            let turn = angle(&prev, &dir);
            if last && gentle(lj, turn, t) && reach + lj <= RUN_LENGTH {
                to_stop = Some((j, t));
            }
            break;
        };
        let turn = angle(&prev, &dir).max(angle(&dir, &after.segment.point(0.0).d1));
        if after.segment.metric() != Metric::Linear
            || !gentle(lj, turn, t)
            || t.min(after.tolerance) <= 0.0
            || reach + 0.5 * lj > RUN_LENGTH
        {
            break;
        }
        tol = t;
        longest = j;
        reach += lj;
        prev = dir;
    }
    if tol <= 0.0 || (longest == 0 && to_stop.is_none()) {
        return None;
    }
    let start = match cur.split {
        Some(p) => p,
        None if cur.from_rest && cur.trim == 0.0 => {
            let Segment::Line(line) = &cur.segment else {
                return None;
            };
            // The vertices from the line's end on.
            let ahead = vertices.around(0);
            end_point(line, false, &ahead, SPLIT_MAX_ANGLE)?
        }
        None => return None,
    };
    if let Some((j, t)) = to_stop
        && let Some(done) = run_to(cur, rest, j, &start, t, vertices, true, pool)
    {
        return Some(done);
    }
    let mut m = longest;
    while m >= 1 {
        if let Some(done) = run_to(cur, rest, m, &start, tol, vertices, false, pool) {
            return Some(done);
        }
        m /= 2;
    }
    None
}

/// The run from `start` to the split point of the `m`-th waiting element (or to its end,
/// where the path stops: `to_end`), if its blend keeps within `tol`; its curve goes into
/// `pool`.
#[allow(clippy::too_many_arguments)] // the run's ends, its contour and where its curve goes
fn run_to(
    cur: &Element,
    rest: &mut [Waiting],
    m: usize,
    start: &PathPoint,
    tol: f64,
    vertices: &Vertices<'_>,
    to_end: bool,
    pool: &mut BlendPool,
) -> Option<Committed> {
    let Segment::Line(line) = &rest.get(m)?.element.segment else {
        return None;
    };
    let (end, upto) = if to_end {
        let p = end_point(line, true, &vertices.around(m), SPLIT_MAX_ANGLE)?;
        (p, line.length())
    } else {
        let p = split_point(line, &vertices.around(m), tol, SPLIT_MAX_ANGLE)?;
        (p, 0.5 * line.length())
    };
    // The contour on the stack: the first element, the `m` before the last, the last.
    let first = ContourPart {
        segment: &cur.segment,
        from: cur.trim,
        to: cur.segment.length(),
    };
    let mut parts = [first; RUN_ELEMENTS + 2];
    let contour = parts.get_mut(..m + 2)?;
    for (part, w) in contour[1..].iter_mut().zip(&rest[..m]) {
        *part = ContourPart {
            segment: &w.element.segment,
            from: 0.0,
            to: w.element.segment.length(),
        };
    }
    contour[m + 1] = ContourPart {
        segment: &rest[m].element.segment,
        from: 0.0,
        to: upto,
    };
    let (curve, _) = blend_within(start, &end, contour, tol, pool.memo())?;
    let feed = rest[..=m]
        .iter()
        .fold(cur.feed, |f, w| min_feed(f, w.element.feed));
    let length = curve.length();
    // The caller made sure a slot is free.
    let shape = Shape::Blend(pool.store(curve)?);
    let mut out = Committed::default();
    let last = &mut rest[m].element;
    out.pieces.push(NewPiece {
        shape,
        offset: 0.0,
        length,
        feed,
        loc: last.loc,
        headroom: Headroom::Ample,
    });
    if to_end {
        out.consumed = m + 1;
        out.stop_at_end = true;
    } else {
        last.trim = upto;
        last.split = Some(end);
        out.consumed = m;
    }
    Some(out)
}
