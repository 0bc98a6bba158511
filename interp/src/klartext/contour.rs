//! Contour blocks that depend on their neighbours or on coefficients: RND and CHF corners,
//! SPL splines and the APPR/DEP approach and departure ops.
//!
//! RND and CHF (HEIDENHAIN rules): the block stands between two contour elements and
//! replaces their common corner. CHF cuts the corner with a straight line whose ends lie the
//! chamfer length away from the corner on both lines; RND inserts an arc of the given radius
//! tangent to both elements. The F of the block acts for the inserted element only; without
//! it the modal feed applies. This version rounds and chamfers corners between two straight
//! lines in the working plane (an arc next to RND or CHF is reported as not supported).
//!
//! SPL: each axis written in the block follows `P(t) = K3·t³ + K2·t² + K1·t + end` while t
//! runs from 1 to 0, so the start is `end + K3 + K2 + K1`; it must lie within 1 µm of the
//! previous end point. Every end coordinate needs its K3, K2, K1, in that order; 2 to 5 axes.
//!
//! APPR/DEP: the interpreter resolves the programmed points (PA for APPR, PN for DEP LCT),
//! the shape parameters and the feeds; the paths themselves are built on the compensated
//! contour by the radius-compensation stage. APPR LCT moves at the feed of its block all the
//! way from PS to PA; LT, LN and CT move to PH at the feed of the last motion before the
//! block (rapid after FMAX) and from PH to PA at the block's feed. APPR switches
//! compensation on (it needs RL or RR and R0 before); DEP needs active compensation and
//! switches it off.

use super::exec::{ExecError, Machine, at, here};
use super::geom;
use super::parser::{ApprKind, FeedWord, SplineWords, Stmt, Words};
use crate::diag::ProgramError;
use crate::op::{ApproachShape, AxisLetter, CompSide, Feed, Op, OpKind, Pose, SplineAxis};
use std::collections::VecDeque;

/// Largest distance (mm) between a spline's start and the previous end point.
pub const SPLINE_START_TOLERANCE: f64 = 0.001;

/// An RND or CHF block waiting for the element after the corner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Corner {
    /// True for RND, false for CHF.
    round: bool,
    /// Radius (RND) or chamfer length (CHF), mm.
    size: f64,
    /// Feed of the inserted element.
    feed: Feed,
}

impl Machine {
    /// Records an RND or CHF block; the next contour element resolves it.
    pub(super) fn corner_request(&mut self, stmt: &Stmt, w: &Words) -> Result<(), ExecError> {
        let round = matches!(stmt, Stmt::Round);
        let what = if round { "RND" } else { "CHF" };
        if self.held_at.is_none() || self.corner.is_some() {
            return Err(here(ProgramError::Geometry(format!(
                "{what} must follow a contour element (L, C, CR, CT, LP, CP, CTP)"
            ))));
        }
        let Some((v, pos)) = w.radius else {
            return Err(here(ProgramError::Missing("RND/CHF needs its size")));
        };
        let size = self.params.value(v) * self.unit;
        if !(size > 0.0 && size.is_finite()) {
            return Err(at(
                pos,
                ProgramError::Geometry(format!("{what} size {size} mm must be positive")),
            ));
        }
        // the F of RND/CHF acts on the inserted element only
        let feed = match w.feed {
            Some(FeedWord::Value(fv)) => {
                let f = self.params.value(fv);
                if !(f > 0.0 && f.is_finite()) {
                    return Err(here(ProgramError::OutOfRange(format!(
                        "feed rate F{f} must be positive"
                    ))));
                }
                Feed::Rate(f * if self.unit == 1.0 { 1.0 } else { 2.54 } / 60.0)
            }
            Some(FeedWord::Max) => Feed::Rapid,
            other => {
                let saved = self.feed;
                let f = self.feed(other)?;
                self.feed = saved;
                self.need_feed(f)?
            }
        };
        self.corner = Some(Corner { round, size, feed });
        Ok(())
    }

    /// Cuts the corner between the held element and `next` (a motion op starting at the
    /// corner): shortens the held line, pushes the chamfer or rounding, and returns `next`
    /// starting where the inserted element ends.
    pub(super) fn resolve_corner(
        &mut self,
        next: &OpKind,
        out: &mut VecDeque<Op>,
    ) -> Result<OpKind, ExecError> {
        let Some(corner) = self.corner.take() else {
            return Ok(next.clone());
        };
        let what = if corner.round { "RND" } else { "CHF" };
        let plane = self.plane;
        let (a, b, _) = plane.axes();
        let held = self.held_at.and_then(|i| out.get_mut(i));
        let Some(Op {
            kind: OpKind::Line {
                from: p0, to: p1, ..
            },
            loc,
        }) = held
        else {
            return Err(here(ProgramError::NotSupported(format!(
                "{what} after an arc or spline (only between two straight lines)"
            ))));
        };
        let OpKind::Line { to: p2, feed, .. } = next else {
            return Err(here(ProgramError::NotSupported(format!(
                "{what} before an arc (only between two straight lines)"
            ))));
        };
        let corner_pt = [p1[a], p1[b]];
        let d1 = geom::sub(corner_pt, [p0[a], p0[b]]);
        let d2 = geom::sub([p2[a], p2[b]], corner_pt);
        let (l1, l2) = (geom::norm(d1), geom::norm(d2));
        if l1 < 1e-9 || l2 < 1e-9 {
            return Err(here(ProgramError::Geometry(format!(
                "{what} needs both neighbouring lines to move in the working plane"
            ))));
        }
        let u1 = [d1[0] / l1, d1[1] / l1];
        let u2 = [d2[0] / l2, d2[1] / l2];
        let cross = u1[0] * u2[1] - u1[1] * u2[0];
        let dot = u1[0] * u2[0] + u1[1] * u2[1];
        // turning angle between the lines, in (-180, 180)
        let turn = cross.atan2(dot);
        if turn.abs() < 1e-9 {
            return Err(here(ProgramError::Geometry(format!(
                "{what} between two collinear lines: there is no corner"
            ))));
        }
        // distance from the corner to the tangent (or chamfer) points along each line
        let dist = if corner.round {
            corner.size * (turn.abs() / 2.0).tan()
        } else {
            corner.size
        };
        if dist > l1 + 1e-9 || dist > l2 + 1e-9 {
            return Err(here(ProgramError::Geometry(format!(
                "{what} {:.4} mm does not fit: it needs {:.4} mm of each line, the lines are {:.4} and {:.4} mm",
                corner.size, dist, l1, l2
            ))));
        }
        // points on the full 3-D lines at the in-plane distance `dist` from the corner
        let t1 = lerp(p1, p0, dist / l1);
        let t2 = lerp(p1, p2, dist / l2);
        *p1 = t1;
        let loc = *loc;
        let inserted = if corner.round {
            let left = [-u1[1], u1[0]];
            let side = turn.signum();
            let centre = [
                t1[a] + side * corner.size * left[0],
                t1[b] + side * corner.size * left[1],
            ];
            OpKind::Arc {
                from: t1,
                to: t2,
                center: centre,
                plane,
                sweep: turn.to_degrees(),
                feed: corner.feed,
            }
        } else {
            OpKind::Line {
                from: t1,
                to: t2,
                feed: corner.feed,
            }
        };
        self.last_feed = Some(corner.feed);
        out.push_back(Op {
            kind: inserted,
            loc,
        });
        Ok(OpKind::Line {
            from: t2,
            to: *p2,
            feed: *feed,
        })
    }

    /// SPL: checks the coefficients and the start point, returns the spline op.
    pub(super) fn spline(&mut self, w: &Words, sw: &SplineWords) -> Result<OpKind, ExecError> {
        let from = self.pos;
        let to = self.target(w);
        let mut axes = Vec::with_capacity(5);
        for axis in AxisLetter::ALL {
            let end = w.axes[axis.index()];
            let k = sw.k[axis.index()];
            let given = k.iter().filter(|c| c.is_some()).count();
            match (end, given) {
                (None, 0) => continue,
                (None, _) => {
                    return Err(here(ProgramError::Geometry(format!(
                        "SPL: coefficients for {axis} but no end point {axis}"
                    ))));
                }
                (Some(c), n) if n < 3 => {
                    return Err(at(
                        c.pos,
                        ProgramError::Missing(
                            "SPL: every end coordinate needs its K3, K2 and K1 (an axis is missing its triple)",
                        ),
                    ));
                }
                _ => {}
            }
            let mut coef = [0.0; 3];
            for (slot, c) in coef.iter_mut().zip(k.iter()) {
                if let Some((v, e)) = c {
                    let x = self.params.value(*v) * 10f64.powi(*e);
                    *slot = self.length(axis, x);
                }
            }
            if coef.iter().any(|c| !c.is_finite()) {
                return Err(here(ProgramError::OutOfRange(format!(
                    "SPL: coefficient of {axis} out of range"
                ))));
            }
            let start = to[axis] + coef[0] + coef[1] + coef[2];
            let gap = (start - from[axis]).abs();
            if gap > SPLINE_START_TOLERANCE {
                return Err(here(ProgramError::Geometry(format!(
                    "SPL starts at {axis}{start:+.4}, {:.4} mm away from the previous end point {axis}{:+.4} (more than {SPLINE_START_TOLERANCE} mm)",
                    gap, from[axis]
                ))));
            }
            axes.push(SplineAxis { axis, k: coef });
        }
        if !(2..=5).contains(&axes.len()) {
            return Err(here(ProgramError::Geometry(format!(
                "SPL needs 2 to 5 axes, this block has {}",
                axes.len()
            ))));
        }
        let f = self.feed(w.feed)?;
        Ok(OpKind::Spline {
            from,
            to,
            axes,
            feed: self.need_feed(f)?,
        })
    }

    /// APPR or DEP: the op with its points, shape and feeds.
    pub(super) fn approach_depart(
        &mut self,
        w: &Words,
        approach: bool,
        kind: ApprKind,
        polar: bool,
    ) -> Result<OpKind, ExecError> {
        let last_feed = self.last_feed;
        let value = |m: &Machine,
                     word: Option<(crate::klartext::expr::Value, u32)>,
                     name: &'static str|
         -> Result<(f64, u32), ExecError> {
            match word {
                Some((v, pos)) => Ok((m.params.value(v), pos)),
                None => Err(here(ProgramError::Missing(name))),
            }
        };
        let shape = match kind {
            ApprKind::Lt | ApprKind::Ln => {
                let (len, pos) = value(self, w.len, "LT/LN need the length LEN")?;
                let len = len * self.unit;
                if !(len > 0.0 && len.is_finite()) {
                    return Err(at(
                        pos,
                        ProgramError::Geometry(format!("LEN {len} must be positive")),
                    ));
                }
                if kind == ApprKind::Lt {
                    ApproachShape::LineTangent { len }
                } else {
                    ApproachShape::LineNormal { len }
                }
            }
            ApprKind::Ct => {
                let (cca, pos) = value(self, w.cca, "CT needs the central angle CCA")?;
                if !(cca > 0.0 && cca < 360.0) {
                    return Err(at(
                        pos,
                        ProgramError::OutOfRange(format!(
                            "CCA {cca} must lie between 0 and 360 degrees"
                        )),
                    ));
                }
                let (r, pos) = value(self, w.radius, "CT needs the radius R")?;
                let r = r * self.unit;
                if r == 0.0 || !r.is_finite() {
                    return Err(at(pos, ProgramError::Geometry("R must not be 0".into())));
                }
                ApproachShape::CircleTangent { cca, radius: r }
            }
            ApprKind::Lct => {
                let (r, pos) = value(self, w.radius, "LCT needs the radius R")?;
                let r = r * self.unit;
                if !(r > 0.0 && r.is_finite()) {
                    return Err(at(
                        pos,
                        ProgramError::Geometry(format!("LCT radius R {r} must be positive")),
                    ));
                }
                ApproachShape::LineCircleTangent { radius: r }
            }
        };
        let f = self.feed(w.feed)?;
        let feed = self.need_feed(f)?;
        let plane = self.plane;
        let from = self.pos;
        if approach {
            let side = match w.comp {
                Some(s @ (CompSide::Left | CompSide::Right)) => s,
                _ => {
                    return Err(here(ProgramError::Missing(
                        "APPR needs RL or RR: it switches radius compensation on",
                    )));
                }
            };
            if self.comp != CompSide::Off {
                return Err(here(ProgramError::Geometry(
                    "APPR with radius compensation already on: program R0 before the approach"
                        .into(),
                )));
            }
            let to = if polar {
                self.polar_end(w, "APPR")?
            } else {
                self.target(w)
            };
            let with_tool_axis = w.axes[self.tool_axis.index()].is_some();
            let feed_to_aux = match kind {
                ApprKind::Lct => feed,
                _ => last_feed.unwrap_or(feed),
            };
            self.comp = side;
            self.pos = to;
            self.tangent = None;
            self.last_feed = Some(feed);
            Ok(OpKind::Approach {
                from,
                to,
                shape,
                side,
                feed_to_aux,
                feed,
                plane,
                with_tool_axis,
            })
        } else {
            if self.comp == CompSide::Off {
                return Err(here(ProgramError::Geometry(
                    "DEP without active radius compensation (RL/RR)".into(),
                )));
            }
            if matches!(w.comp, Some(CompSide::Left | CompSide::Right)) {
                return Err(here(ProgramError::Geometry(
                    "DEP switches radius compensation off: RL/RR not allowed".into(),
                )));
            }
            let to = if kind == ApprKind::Lct {
                Some(if polar {
                    self.polar_end(w, "DEP")?
                } else {
                    self.target(w)
                })
            } else {
                None
            };
            let side = self.comp;
            self.comp = CompSide::Off;
            // where the programmed contour continues to: the interpreter's position after DEP
            self.pos = match to {
                Some(p) => p,
                None => self.depart_end(shape, side),
            };
            self.tangent = None;
            self.last_feed = Some(feed);
            Ok(OpKind::Depart {
                from,
                to,
                shape,
                feed,
                plane,
            })
        }
    }

    /// End point of DEP LT/LN/CT on the programmed contour: LEN along the last element's end
    /// tangent (LT), LEN along the normal towards the tool side (LN), or an arc of radius R
    /// and angle CCA tangent to the last element, turning towards the tool side (CT).
    fn depart_end(&self, shape: ApproachShape, side: CompSide) -> Pose {
        let (a, b, _) = self.plane.axes();
        let mut p = self.pos;
        let Some(t) = self
            .tangent
            .map(|d| [d[a.index()], d[b.index()]])
            .filter(|t| geom::norm(*t) > 0.0)
        else {
            return p;
        };
        let n = geom::norm(t);
        let t = [t[0] / n, t[1] / n];
        // the tool side: left of travel for RL, right for RR
        let s = if side == CompSide::Left { 1.0 } else { -1.0 };
        let normal = [-t[1] * s, t[0] * s];
        match shape {
            ApproachShape::LineTangent { len } => {
                p[a] += t[0] * len;
                p[b] += t[1] * len;
            }
            ApproachShape::LineNormal { len } => {
                p[a] += normal[0] * len;
                p[b] += normal[1] * len;
            }
            ApproachShape::CircleTangent { cca, radius } => {
                let r = radius.abs();
                let centre = [p[a] + normal[0] * r, p[b] + normal[1] * r];
                let start = geom::angle(geom::sub([p[a], p[b]], centre));
                let e = geom::polar(centre, r, start + s * cca);
                p[a] = e[0];
                p[b] = e[1];
            }
            ApproachShape::LineCircleTangent { .. } => {}
        }
        p
    }
}

/// The pose `s` of the way from `p` to `q`.
fn lerp(p: &Pose, q: &Pose, s: f64) -> Pose {
    let mut out = *p;
    for (o, (a, b)) in out.0.iter_mut().zip(p.0.iter().zip(q.0.iter())) {
        *o = a + (b - a) * s;
    }
    out
}
