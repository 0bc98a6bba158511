//! APPR and DEP: approaching and leaving a contour, constructed on the compensated path.
//!
//! The rules, in our words, after the HEIDENHAIN TNC user manuals ("Approaching and departing
//! a contour"). PS is the start point (reached without compensation), PA the first contour
//! point, PE the last contour point, PN the end point, PH an auxiliary point the control
//! computes. Below, PA and PE stand for the tool-centre points: the contour point moved by the
//! tool radius along the normal of the first (last) element to the compensation side, so the
//! tool arrives at (leaves) the contour perpendicular to it. t is the direction of travel of
//! the contour element at that point and n its left normal; the side sign σ is +1 for RL and
//! −1 for RR.
//! - LT: PH lies LEN before PA on the tangent: PH = PA − LEN·t. PS → PH → PA in straight lines.
//! - LN: PH lies LEN out from PA along the normal, away from the material (towards the
//!   compensation side): PH = PA + σ·LEN·n; on the contour this is LEN plus the tool radius.
//! - CT: an arc of central angle CCA and radius |R| ends in PA tangent to the contour. Its
//!   direction: RL with R > 0 and RR with R < 0 turn counter-clockwise, the other two
//!   clockwise. PS → PH is a straight line; PH is where that arc starts. R is taken as the
//!   radius of the tool-centre arc.
//! - LCT: an arc of radius R (turning as CT with R > 0) ends in PA tangent to the contour, and
//!   the straight line from PS touches it tangentially in PH, so the radius alone fixes the
//!   path. The block's tool-axis coordinate is reached on the way to PH (all axes move
//!   together), the arc runs in the working plane only.
//! - DEP LT: a straight line continues the last element's tangent LEN beyond PE.
//! - DEP LN: a straight line leaves PE along the normal towards the compensation side, LEN long.
//! - DEP CT: an arc of radius |R| and central angle CCA starts at PE tangent to the contour,
//!   turning as for APPR CT; its end is PN.
//! - DEP LCT: an arc of radius R leaves PE tangentially and a straight line tangent to it ends
//!   in the programmed PN; PH is the tangent point. The line moves all programmed axes.
//!
//! Feeds: APPR moves PS → PH at the feed given with the op (the last feed for LT/LN/CT, the
//! block's feed for LCT) and PH → PA at the block's feed; DEP uses the block's feed.

use super::element::{Element, line};
use super::error::CompError;
use super::plane::{V2, project, with_point};
use klar_interp::{ApproachShape, Feed, Op, OpKind, Plane, Pose, SourceLoc};
use std::f64::consts::TAU;

/// Checked parameters of one APPR/DEP shape.
enum Shape {
    /// LT: tangent line, length.
    Tangent(f64),
    /// LN: normal line, length.
    Normal(f64),
    /// CT: arc with central angle (radians) and signed rotation ±1 and radius.
    Circle { cca: f64, turn: f64, r: f64 },
    /// LCT: line and arc of radius r, rotation ±1.
    LineCircle { turn: f64, r: f64 },
}

fn check(shape: &ApproachShape, side: f64, loc: SourceLoc) -> Result<Shape, CompError> {
    let bad = |what| CompError::BadApproach { loc, what };
    match *shape {
        ApproachShape::LineTangent { len } | ApproachShape::LineNormal { len } => {
            if !len.is_finite() {
                return Err(CompError::NonFinite { loc, what: "LEN" });
            }
            if len <= 0.0 {
                return Err(bad("LEN must be greater than 0"));
            }
            Ok(if matches!(shape, ApproachShape::LineTangent { .. }) {
                Shape::Tangent(len)
            } else {
                Shape::Normal(len)
            })
        }
        ApproachShape::CircleTangent { cca, radius } => {
            if !cca.is_finite() || !radius.is_finite() {
                return Err(CompError::NonFinite {
                    loc,
                    what: "CCA or R",
                });
            }
            if cca <= 0.0 || cca > 360.0 {
                return Err(bad("CCA must lie in (0°, 360°]"));
            }
            if radius == 0.0 {
                return Err(bad("R must not be 0"));
            }
            Ok(Shape::Circle {
                cca: cca.to_radians(),
                turn: side * radius.signum(),
                r: radius.abs(),
            })
        }
        ApproachShape::LineCircleTangent { radius } => {
            if !radius.is_finite() {
                return Err(CompError::NonFinite { loc, what: "R" });
            }
            if radius <= 0.0 {
                return Err(bad("LCT needs R greater than 0"));
            }
            Ok(Shape::LineCircle {
                turn: side,
                r: radius,
            })
        }
    }
}

/// The tangent point on the circle (c, r) of a line through `p`, for a circle traversed in
/// rotation `turn` (±1): `towards` true picks the point the line reaches travelling with the
/// circle's direction (approach), false the point where leaving the circle heads to `p`.
fn tangent_point(p: V2, c: V2, r: f64, turn: f64, towards: bool) -> Option<V2> {
    let v = p - c;
    let dist = v.norm();
    if dist <= r {
        return None;
    }
    let alpha = (r / dist).acos();
    let u = v * (1.0 / dist);
    [u.rotated(alpha), u.rotated(-alpha)]
        .into_iter()
        .map(|w| c + w * r)
        .find(|&q| {
            let dir = (q - c).left() * turn;
            let along = if towards { q - p } else { p - q };
            along.dot(dir) > 0.0
        })
}

/// Angle in [0, 2π) travelled from `from` to `to` about `c` in rotation `turn`.
fn travel(c: V2, from: V2, to: V2, turn: f64) -> f64 {
    (((to - c).angle() - (from - c).angle()) * turn).rem_euclid(TAU)
}

fn arc(from: Pose, to: Pose, c: V2, plane: Plane, sweep: f64, feed: Feed, loc: SourceLoc) -> Op {
    Op {
        kind: OpKind::Arc {
            from,
            to,
            center: [c.x, c.y],
            plane,
            sweep: sweep.to_degrees(),
            feed,
        },
        loc,
    }
}

/// What an APPR block asks for.
#[derive(Debug, Clone, PartialEq)]
pub struct Approach {
    /// First contour point PA as programmed (its off-plane axes are the block's).
    pub to: Pose,
    /// Path shape.
    pub shape: ApproachShape,
    /// +1 for RL, −1 for RR.
    pub side: f64,
    /// Feed PS → PH.
    pub feed_to_aux: Feed,
    /// Feed PH → PA.
    pub feed: Feed,
    /// The block.
    pub loc: SourceLoc,
}

/// The moves of an APPR block from the tool pose `pos` to the compensated first contour
/// point of `first`, whose tool-centre start point is `pa`.
pub fn approach(
    a: &Approach,
    first: &Element,
    pa: V2,
    pos: Pose,
    plane: Plane,
) -> Result<Vec<Op>, CompError> {
    let shape = check(&a.shape, a.side, a.loc)?;
    let t = first.tangent_start();
    let n = t.left();
    let end = with_point(&a.to, plane, pa);
    let mut out = Vec::new();
    let aux = |ph: V2, out: &mut Vec<Op>| {
        let p = with_point(&a.to, plane, ph);
        if p != pos {
            out.push(line(pos, p, a.feed_to_aux, a.loc));
        }
        p
    };
    match shape {
        Shape::Tangent(len) => {
            let ph = aux(pa - t * len, &mut out);
            out.push(line(ph, end, a.feed, a.loc));
        }
        Shape::Normal(len) => {
            let ph = aux(pa + n * (a.side * len), &mut out);
            out.push(line(ph, end, a.feed, a.loc));
        }
        Shape::Circle { cca, turn, r } => {
            let c = pa + n * (turn * r);
            let ph = aux(c + (pa - c).rotated(-turn * cca), &mut out);
            out.push(arc(ph, end, c, plane, turn * cca, a.feed, a.loc));
        }
        Shape::LineCircle { turn, r } => {
            let c = pa + n * (turn * r);
            let ps = project(&pos, plane);
            let q = tangent_point(ps, c, r, turn, true).ok_or(CompError::LctInsideCircle {
                loc: a.loc,
                radius: r,
            })?;
            let ph = aux(q, &mut out);
            let sweep = turn * travel(c, q, pa, turn);
            if sweep.abs() * r > 1e-9 {
                out.push(arc(ph, end, c, plane, sweep, a.feed, a.loc));
            } else {
                out.push(line(ph, end, a.feed, a.loc));
            }
        }
    }
    Ok(out)
}

/// What a DEP block asks for.
#[derive(Debug, Clone, PartialEq)]
pub struct Depart {
    /// Programmed end point PN (LCT), if any.
    pub to: Option<Pose>,
    /// Path shape.
    pub shape: ApproachShape,
    /// +1 for RL, −1 for RR.
    pub side: f64,
    /// Feed.
    pub feed: Feed,
    /// The block.
    pub loc: SourceLoc,
}

/// The moves of a DEP block from the compensated last contour point `pos` of `last`.
pub fn depart(d: &Depart, last: &Element, pos: Pose, plane: Plane) -> Result<Vec<Op>, CompError> {
    let shape = check(&d.shape, d.side, d.loc)?;
    let t = last.tangent_end();
    let n = t.left();
    let pe = project(&pos, plane);
    let mut out = Vec::new();
    match shape {
        Shape::Tangent(len) => {
            out.push(line(
                pos,
                with_point(&pos, plane, pe + t * len),
                d.feed,
                d.loc,
            ));
        }
        Shape::Normal(len) => {
            let pn = pe + n * (d.side * len);
            out.push(line(pos, with_point(&pos, plane, pn), d.feed, d.loc));
        }
        Shape::Circle { cca, turn, r } => {
            let c = pe + n * (turn * r);
            let pn = with_point(&pos, plane, c + (pe - c).rotated(turn * cca));
            out.push(arc(pos, pn, c, plane, turn * cca, d.feed, d.loc));
        }
        Shape::LineCircle { turn, r } => {
            let target = d.to.ok_or(CompError::BadApproach {
                loc: d.loc,
                what: "DEP LCT needs an end point",
            })?;
            if !target.0.iter().all(|v| v.is_finite()) {
                return Err(CompError::NonFinite {
                    loc: d.loc,
                    what: "DEP end point",
                });
            }
            let c = pe + n * (turn * r);
            let q = tangent_point(project(&target, plane), c, r, turn, false).ok_or(
                CompError::LctInsideCircle {
                    loc: d.loc,
                    radius: r,
                },
            )?;
            let ph = with_point(&pos, plane, q);
            let sweep = turn * travel(c, pe, q, turn);
            if sweep.abs() * r > 1e-9 {
                out.push(arc(pos, ph, c, plane, sweep, d.feed, d.loc));
            }
            out.push(line(ph, target, d.feed, d.loc));
        }
    }
    Ok(out)
}
