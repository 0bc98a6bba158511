//! Joining two consecutive compensated elements at their common programmed corner.
//!
//! How the control treats the corner (HEIDENHAIN TNC user manuals, "radius compensation:
//! machining corners"), in our words:
//! - Tangent transition: the offset curves already meet (the normals agree), nothing is added.
//! - Outside corner (the contour turns away from the tool side): the tool rolls around the
//!   programmed corner point on a transition arc whose centre is that point and whose radius
//!   is the tool radius, from the offset end of the first element to the offset start of the
//!   second. A 180° reversal is an outside corner too: a half circle around the turning point.
//! - Inside corner (the contour turns towards the tool side): the offset curves are cut at
//!   their intersection; the first element ends there and the second starts there. The tool
//!   radius that fits is therefore limited by the contour: when the curves do not meet, or
//!   when cutting would make an element run backwards, that is a contour violation.
//! - M97 in the block that ends at an outside corner between two straight elements: no
//!   transition arc; both offset lines are extended to their intersection, as at an inside
//!   corner. A step smaller than the tool radius can then be passed without damaging the
//!   contour (the step itself is left partly uncut). Parallel lines (a reversal) and corners
//!   with an arc keep the transition arc.
//! - M98 in the block that ends at an inside corner: the offsets are not cut at their
//!   intersection. The tool runs to the full offset end of the first element (on the normal
//!   at the corner), goes straight to the full offset start of the second, and goes on from
//!   there, so that an open corner is machined completely. The two elements' paths may come
//!   closer to each other's contour than the tool radius; that is what M98 asks for, so the
//!   gouge check between the two is waived.

use super::element::{CornerArc, Curve, Pending};
use super::error::CompError;
use klar_interp::CornerRule;
use std::f64::consts::PI;

/// Offset end points closer than this (mm) join without a corner.
pub const JOIN_EPS: f64 = 1e-9;
/// Trims (mm) this far past an element's end still count as touching it.
pub const TRIM_EPS: f64 = 1e-7;
/// Offset end points this close (mm) at a nearly tangent inside join whose offset curves do
/// not meet (arc end points the interpreter accepted within its radius tolerance) join
/// without a corner; the next element starts where the tool is.
pub const JOIN_SLACK: f64 = 1e-3;

/// Sets the trims or the transition arc between `a` and the following element `b`.
///
/// `d` is the signed offset (+R for RL, −R for RR), `tool` the tool radius for diagnostics.
pub fn join(a: &mut Pending, b: &mut Pending, d: f64, tool: f64) -> Result<(), CompError> {
    b.prev = Some(a.elem.loc);
    if a.lead_in {
        // The block that switches compensation on ends perpendicular to the next element.
        a.lead_end = Some(b.curve.point_from_start(0.0));
        return Ok(());
    }
    let pa = a.curve.point_from_end(0.0);
    let pb = b.curve.point_from_start(0.0);
    if pa.dist(pb) <= JOIN_EPS {
        return Ok(());
    }
    let ta = a.elem.tangent_end();
    let tb = b.elem.tangent_start();
    let mut theta = ta.cross(tb).atan2(ta.dot(tb));
    if theta.abs() > PI - 1e-9 {
        theta = -d.signum() * PI;
    }
    let corner = b.elem.start();
    if theta * d < 0.0
        && a.end_rule == Some(CornerRule::Intersect)
        && let (Curve::Line { .. }, Curve::Line { .. }) = (a.curve, b.curve)
        && let Some(x) = a.curve.intersect(&b.curve).first().copied()
    {
        a.trim1 = a.curve.trim_end_to(x);
        b.trim0 = b.curve.trim_start_to(x);
        return Ok(());
    }
    if theta * d > 0.0 && a.end_rule == Some(CornerRule::Open) {
        a.bridge = Some(pb);
        a.open_to.push(b.elem.loc);
        b.open_to.push(a.elem.loc);
        return Ok(());
    }
    if theta * d < 0.0 {
        a.corner = Some(CornerArc {
            center: corner,
            to: pb,
            sweep: theta,
        });
        return Ok(());
    }
    let meet = a
        .curve
        .intersect(&b.curve)
        .into_iter()
        .min_by(|p, q| p.dist(corner).total_cmp(&q.dist(corner)))
        .map(|x| (a.curve.trim_end_to(x), b.curve.trim_start_to(x)))
        .filter(|(t1, t0)| t1 * a.curve.scale() >= -TRIM_EPS && t0 * b.curve.scale() >= -TRIM_EPS);
    match meet {
        Some((t1, t0)) => {
            a.trim1 = t1.max(0.0);
            b.trim0 = t0.max(0.0);
            Ok(())
        }
        None if pa.dist(pb) <= JOIN_SLACK => Ok(()),
        None => Err(CompError::NoIntersection {
            blocks: vec![a.elem.loc, b.elem.loc],
            tool,
        }),
    }
}

/// Checks that an element whose both ends are known does not run backwards.
///
/// `next` is the block after it (for the diagnostic), if any.
pub fn check_forward(
    p: &Pending,
    next: Option<klar_interp::SourceLoc>,
    tool: f64,
) -> Result<(), CompError> {
    if p.lead_in {
        return Ok(());
    }
    let remaining = (p.curve.extent() - p.trim0 - p.trim1) * p.curve.scale();
    if remaining < -TRIM_EPS {
        let blocks = p
            .prev
            .into_iter()
            .chain(std::iter::once(p.elem.loc))
            .chain(next)
            .collect();
        return Err(CompError::RunsBackwards {
            blocks,
            overlap: -remaining,
            tool,
        });
    }
    Ok(())
}
