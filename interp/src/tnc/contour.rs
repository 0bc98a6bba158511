//! Contour blocks that depend on their neighbours or on coefficients: RND and CHF corners,
//! SPL splines and the APPR/DEP approach and departure ops.
//!
//! RND and CHF (HEIDENHAIN rules): the block stands between two contour elements and
//! replaces their common corner. CHF cuts the corner with a straight line whose ends lie the
//! chamfer length away from the corner on both lines; RND inserts an arc of the given radius
//! tangent to both elements. The F of the block acts for the inserted element only; without
//! it the modal feed applies. RND rounds the corner between any two lines or arcs of the
//! working plane (line/line, line/arc, arc/line, arc/arc): the rounding arc's centre lies at
//! distance R from both elements on the inside of the corner, both elements are trimmed to
//! the tangent points, and a radius that needs more than an element offers is an error. CHF
//! is only defined between two straight lines (the TNC manuals list it as "chamfer between
//! two straight lines"); next to an arc it is an error.
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
use super::stmt::{ApprKind, FeedWord, SplineWords, Stmt, Words};
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
    /// corner): shortens the held element, pushes the chamfer or rounding, and returns `next`
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
        let held = self.held_at.and_then(|i| out.get_mut(i));
        let Some(Op { kind: held, loc }) = held else {
            return Err(here(ProgramError::Geometry(format!(
                "{what} must follow a contour element (L, C, CR, CT, LP, CP, CTP)"
            ))));
        };
        let loc = *loc;
        let (Some(e1), Some(e2)) = (plane_elem(held, plane), plane_elem(next, plane)) else {
            return Err(here(ProgramError::Geometry(format!(
                "{what} needs a line or an arc in the working plane on both sides, moving in that plane"
            ))));
        };
        let lines = matches!(e1, geom::Elem::Line { .. }) && matches!(e2, geom::Elem::Line { .. });
        if !corner.round && !lines {
            return Err(here(ProgramError::Geometry(
                "CHF only between two straight lines (use RND next to an arc)".into(),
            )));
        }
        let (keep1, cut2, inserted_centre, inserted_sweep) = if corner.round {
            let f = geom::fillet(&e1, &e2, corner.size).map_err(|e| {
                here(ProgramError::Geometry(match e {
                    geom::FilletError::NoCorner => {
                        "RND where the elements meet tangentially: there is no corner to round"
                            .into()
                    }
                    geom::FilletError::TooLarge => format!(
                        "RND R{:.4} does not fit: the rounding arc needs more than the neighbouring elements offer",
                        corner.size
                    ),
                }))
            })?;
            (f.keep1, f.cut2, Some(f.centre), f.sweep)
        } else {
            let (l1, l2) = (elem_len(&e1), elem_len(&e2));
            let (t1, t2) = (e1.tangent(true), e2.tangent(false));
            let turn = (t1[0] * t2[1] - t1[1] * t2[0]).atan2(t1[0] * t2[0] + t1[1] * t2[1]);
            if turn.abs() < 1e-9 {
                return Err(here(ProgramError::Geometry(
                    "CHF between two collinear lines: there is no corner".into(),
                )));
            }
            if corner.size > l1 + 1e-9 || corner.size > l2 + 1e-9 {
                return Err(here(ProgramError::Geometry(format!(
                    "CHF {:.4} mm does not fit: the lines are {:.4} and {:.4} mm",
                    corner.size, l1, l2
                ))));
            }
            (1.0 - corner.size / l1, corner.size / l2, None, 0.0)
        };
        // the held element ends at the first tangent (or chamfer) point
        let end1 = trim(held, keep1, true);
        let mut rest = next.clone();
        let start2 = trim(&mut rest, cut2, false);
        let inserted = match inserted_centre {
            Some(center) => OpKind::Arc {
                from: end1,
                to: start2,
                center,
                plane,
                sweep: inserted_sweep,
                feed: corner.feed,
            },
            None => OpKind::Line {
                from: end1,
                to: start2,
                feed: corner.feed,
            },
        };
        self.last_feed = Some(corner.feed);
        out.push_back(Op {
            kind: inserted,
            loc,
        });
        Ok(rest)
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
                     word: Option<(super::expr::Value, u32)>,
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

/// A line or arc op as a plane element; `None` for other ops, arcs in another plane and
/// lines that do not move in the plane.
fn plane_elem(op: &OpKind, plane: crate::op::Plane) -> Option<geom::Elem> {
    let (a, b, _) = plane.axes();
    match op {
        OpKind::Line { from, to, .. } => {
            let (f, t) = ([from[a], from[b]], [to[a], to[b]]);
            (geom::norm(geom::sub(t, f)) > 1e-9).then_some(geom::Elem::Line { from: f, to: t })
        }
        OpKind::Arc {
            from,
            to,
            center,
            plane: p,
            sweep,
            ..
        } if *p == plane && *sweep != 0.0 => Some(geom::Elem::Arc {
            from: [from[a], from[b]],
            to: [to[a], to[b]],
            centre: *center,
            sweep: *sweep,
        }),
        _ => None,
    }
}

/// In-plane length of a line element (0 for arcs, which CHF does not take).
fn elem_len(e: &geom::Elem) -> f64 {
    match *e {
        geom::Elem::Line { from, to } => geom::norm(geom::sub(to, from)),
        geom::Elem::Arc { .. } => 0.0,
    }
}

/// Shortens a line or arc op: keeps the part up to fraction `f` of the way (`at_end`) or
/// drops the part before it (`!at_end`). Returns the pose at `f`; the other axes follow the
/// element linearly (a helix stays a helix).
fn trim(op: &mut OpKind, f: f64, at_end: bool) -> Pose {
    match op {
        OpKind::Line { from, to, .. } => {
            let p = lerp(from, to, f);
            if at_end {
                *to = p;
            } else {
                *from = p;
            }
            p
        }
        OpKind::Arc {
            from,
            to,
            center,
            plane,
            sweep,
            ..
        } => {
            let (a, b, _) = plane.axes();
            let r = geom::norm(geom::sub([from[a], from[b]], *center));
            let start = geom::angle(geom::sub([from[a], from[b]], *center));
            let q = geom::polar(*center, r, start + *sweep * f);
            let mut p = lerp(from, to, f);
            p[a] = q[0];
            p[b] = q[1];
            if at_end {
                *to = p;
                *sweep *= f;
            } else {
                *from = p;
                *sweep *= 1.0 - f;
            }
            p
        }
        _ => Pose::ZERO,
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

#[cfg(test)]
mod tests {
    use crate::interpreter::Interpreter;
    use crate::op::{OpKind, Pose};

    fn run(body: &str) -> Result<Vec<OpKind>, String> {
        let src = format!("BEGIN PGM R MM\n{body}\nEND PGM R MM\n");
        Interpreter::from_source("r.h", &src, Pose::ZERO)
            .map(|r| r.map(|o| o.kind).map_err(|d| d.to_string()))
            .filter(|r| !matches!(r, Ok(OpKind::End)))
            .collect()
    }

    fn xy(p: &Pose) -> [f64; 2] {
        [p.0[0], p.0[1]]
    }

    fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
        (a[0] - b[0]).hypot(a[1] - b[1])
    }

    fn close(a: [f64; 2], b: [f64; 2]) {
        assert!(dist(a, b) < 1e-9, "{a:?} != {b:?}");
    }

    /// (from, to, centre, sweep) of an arc op.
    fn arc(op: &OpKind) -> ([f64; 2], [f64; 2], [f64; 2], f64) {
        match op {
            OpKind::Arc {
                from,
                to,
                center,
                sweep,
                ..
            } => (xy(from), xy(to), *center, *sweep),
            other => panic!("expected an arc, got {other:?}"),
        }
    }

    fn line(op: &OpKind) -> ([f64; 2], [f64; 2]) {
        match op {
            OpKind::Line { from, to, .. } => (xy(from), xy(to)),
            other => panic!("expected a line, got {other:?}"),
        }
    }

    #[test]
    fn rnd_between_line_and_arc() {
        // line along +X to (10,0); arc about C=(20,0), r=10, clockwise through (20,10):
        // the contour turns left, the rounding lies outside the arc
        let o = run("L X-5 Y+0 F100\nL X+10 Y+0\nRND R2\nCC X+20 Y+0\nC X+30 Y+0 DR-").unwrap();
        assert_eq!(o.len(), 4, "{o:?}");
        let (r, big, c): (f64, f64, [f64; 2]) = (2.0, 10.0, [20.0, 0.0]);
        // centre at height R above the line and R + r from C, on the corner side
        let m = [c[0] - ((big + r) * (big + r) - r * r).sqrt(), r];
        let (_, l_end) = line(&o[1]);
        let (f_from, f_to, f_c, f_sweep) = arc(&o[2]);
        let (a_from, a_to, a_c, _) = arc(&o[3]);
        close(f_c, m);
        // tangent to the line: the line ends below the centre, at distance R
        close(l_end, [m[0], 0.0]);
        assert!((dist(f_c, l_end) - r).abs() < 1e-9);
        // tangent to the arc: its new start lies on the circle and on the line C–M
        assert!((dist(a_from, c) - big).abs() < 1e-9);
        assert!((dist(f_c, c) - (big + r)).abs() < 1e-9);
        let along = [
            c[0] + (m[0] - c[0]) * big / (big + r),
            c[1] + (m[1] - c[1]) * big / (big + r),
        ];
        close(a_from, along);
        close(f_from, l_end);
        close(f_to, a_from);
        assert!(f_sweep > 0.0 && f_sweep < 90.0, "{f_sweep}");
        // the arc keeps its centre and end point
        close(a_c, c);
        close(a_to, [30.0, 0.0]);
    }

    #[test]
    fn rnd_between_arc_and_line() {
        // arc about the origin, r=10, counter-clockwise (10,0) -> (0,10); then a line +Y:
        // the contour turns right, the rounding lies outside the arc
        let o = run("L X+10 Y+0 F100\nCC X+0 Y+0\nC X+0 Y+10 DR+\nRND R2\nL X+0 Y+30").unwrap();
        assert_eq!(o.len(), 4, "{o:?}");
        let (r, big): (f64, f64) = (2.0, 10.0);
        let m = [r, ((big + r) * (big + r) - r * r).sqrt()];
        let (_, a_to, a_c, a_sweep) = arc(&o[1]);
        let (f_from, f_to, f_c, f_sweep) = arc(&o[2]);
        let (l_from, l_to) = line(&o[3]);
        close(f_c, m);
        assert!((dist(m, a_c) - (big + r)).abs() < 1e-9);
        close(a_to, [m[0] * big / (big + r), m[1] * big / (big + r)]);
        close(l_from, [0.0, m[1]]);
        close(l_to, [0.0, 30.0]);
        close(f_from, a_to);
        close(f_to, l_from);
        assert!(
            f_sweep < 0.0,
            "turning right: clockwise rounding, got {f_sweep}"
        );
        // the trimmed arc still turns counter-clockwise and ends at its new end point
        let end_angle = a_sweep.to_radians();
        close([big * end_angle.cos(), big * end_angle.sin()], a_to);
    }

    #[test]
    fn rnd_between_two_arcs() {
        // arc 1 about (0,0), r=10, ccw (10,0) -> (0,10); arc 2 about (10,10), r=10, cw from
        // (0,10): the contour turns right, outside arc 1 and inside arc 2
        let o = run(
            "L X+10 Y+0 F100\nCC X+0 Y+0\nC X+0 Y+10 DR+\nRND R2\nCC X+10 Y+10\nC X+10 Y+20 DR-",
        )
        .unwrap();
        assert_eq!(o.len(), 4, "{o:?}");
        let r = 2.0;
        let (_, a1_to, c1, _) = arc(&o[1]);
        let (f_from, f_to, m, _) = arc(&o[2]);
        let (a2_from, a2_to, c2, _) = arc(&o[3]);
        assert!((dist(m, c1) - (10.0 + r)).abs() < 1e-9);
        assert!((dist(m, c2) - (10.0 - r)).abs() < 1e-9);
        assert!((dist(a1_to, c1) - 10.0).abs() < 1e-9);
        assert!((dist(a2_from, c2) - 10.0).abs() < 1e-9);
        assert!((dist(f_from, m) - r).abs() < 1e-9);
        assert!((dist(f_to, m) - r).abs() < 1e-9);
        close(f_from, a1_to);
        close(f_to, a2_from);
        close(a2_to, [10.0, 20.0]);
        // the centre lies near the corner (0,10), not on the far intersection
        assert!(dist(m, [0.0, 10.0]) < 3.0 * r);
    }

    #[test]
    fn rnd_too_large_and_chamfer_next_to_an_arc_are_errors() {
        let e = run("L X+9 Y+0 F100\nL X+10 Y+0\nRND R5\nCC X+20 Y+0\nC X+30 Y+0 DR-").unwrap_err();
        assert!(
            e.starts_with("r.h:6:1:") && e.contains("does not fit"),
            "{e}"
        );
        let e = run("L X+0 Y+0 F100\nL X+10 Y+0\nCHF 1\nCC X+20 Y+0\nC X+30 Y+0 DR-").unwrap_err();
        assert!(
            e.starts_with("r.h:6:1:") && e.contains("CHF only between two straight lines"),
            "{e}"
        );
        let e =
            run("L X+10 Y+0 F100\nCC X+10 Y+10\nC X+20 Y+10 DR+\nRND R1\nL X+20 Y+30").unwrap_err();
        assert!(e.contains("meet tangentially"), "{e}");
    }
}
