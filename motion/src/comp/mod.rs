//! Tool radius compensation: turns the programmed contour into the path of the tool centre.
//!
//! [`Compensator`] sits between the interpreter and the planner. It takes canonical ops (the
//! programmed contour, with [`OpKind::RadiusComp`] switching RL/RR/R0 and
//! [`OpKind::ToolChange`] giving the tool radius including DR) and gives back ops of the
//! tool-centre path: lines and arcs only, APPR/DEP resolved, every non-motion op passed
//! through in its place.
//!
//! The rules, in our words, after the HEIDENHAIN TNC user manuals:
//! - With RL the tool centre runs on the left of the contour seen in the direction of travel,
//!   with RR on the right, at the tool radius R (table radius plus DR). Lines, arcs and
//!   helices are offset in the working plane only (module `element`).
//! - Corners: transition arc around outside corners, intersection at inside corners, nothing
//!   at tangent transitions (module `corner`). An arc whose offset radius would be zero or
//!   negative, an inside corner whose offset paths never meet, and an element that would run
//!   backwards (a gap narrower than the tool) are contour violations: the stage refuses them
//!   with the blocks named.
//! - Compensation takes effect with the first straight move in the working plane after RL/RR
//!   (moves of the tool axis alone before it run as programmed; an arc there is refused).
//!   That move goes from the uncompensated tool position to the first contour point, where
//!   the tool arrives on the normal of the first contour element. The block with R0 after
//!   RL/RR leaves the same way: the last element ends on its own normal, and the R0 move goes
//!   from there to its end point. RL and RR cannot follow each other directly; R0 or DEP
//!   comes in between. The tool may not change while compensation is on.
//! - APPR/DEP are built on the compensated path (module `approach`).
//! - The working plane is the one normal to the tool axis of the last tool change (XY until
//!   then); arcs in other planes and spline blocks are refused while compensation is on.
//!   Moves of the tool axis alone inside a compensated contour are made where the tool
//!   stands at that corner.
//!
//! - [`OpKind::CornerRule`] (M97/M98 in a block) applies to the corner at the end of the
//!   next contour element (module `corner` has the rules); it is consumed here.
//!
//! - Tilted working plane: after [`OpKind::WorkingPlane`] the ops are in the tilted system;
//!   compensation works there, and the output is turned into the workpiece system by
//!   [`crate::tilt::TiltStage`] as it is popped (the interpreter refuses a plane change
//!   while compensation is on).
//!
//! Not handled here: paraxial R+/R−, which the interpreter resolves.
//!
//! Streaming: an element's tool path is known once the next element is in (its end corner
//! depends on it). Finished elements are then held back for [`DEFAULT_LOOKAHEAD`] further
//! elements (configurable, like M120 LA) so that a contour violation found a few blocks later
//! is reported before the motion leading into it has been released. Within that window the
//! tool path of every held element is also checked against every programmed element for
//! gouges (module `gouge`). Memory stays bounded by the window, whatever the program's length.

mod approach;
mod corner;
mod element;
mod error;
mod gouge;
mod plane;

pub use error::{Blocks, CompError};

use approach::{Approach, Depart};
use element::{Element, Motion, Pending, Shape, Trail, line};
use klar_interp::{AxisLetter, CompSide, CornerRule, Op, OpKind, Plane, Pose, SourceLoc};
use plane::{project, with_point};
use std::collections::VecDeque;

/// Finished elements held back before their motion is released (see the module docs).
pub const DEFAULT_LOOKAHEAD: usize = 6;

/// Largest in-plane gap (mm) between consecutive compensated blocks that is accepted.
pub const CONTINUITY_TOLERANCE: f64 = 1e-6;

/// Finished ops of one element, held back until the window moves past it.
#[derive(Debug)]
struct Group {
    ops: Vec<Op>,
    /// Its compensated path in the plane (empty for moves that are not checked for gouges:
    /// lead-in, APPR, DEP).
    path: Vec<gouge::PathPiece>,
    /// The block.
    loc: SourceLoc,
}

/// Where the compensation is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    /// R0: ops pass through.
    Off,
    /// RL/RR switched on (or APPR seen); no contour element yet.
    Starting(CompSide),
    /// Compensating; the last contour element is pending.
    Active(CompSide),
}

/// The streaming tool radius compensation stage. See the module docs.
#[derive(Debug)]
pub struct Compensator {
    plane: Plane,
    /// Tool radius including DR.
    tool: f64,
    state: State,
    /// Tool pose at the end of everything produced so far.
    pos: Pose,
    /// The last contour element, waiting for the next one.
    pending: Option<Pending>,
    /// An APPR block waiting for the first contour element, and the ops after it.
    approach: Option<(Approach, Vec<Trail>)>,
    /// Finished ops, one group per element, not yet released.
    held: VecDeque<Group>,
    /// The programmed contour elements of the window (lead-in blocks excluded).
    recent: VecDeque<(SourceLoc, Shape)>,
    /// Released ops.
    out: VecDeque<Op>,
    lookahead: usize,
    finished: bool,
    failed: bool,
    /// The corner rule for the end of the next contour element.
    rule: Option<CornerRule>,
    /// The working plane of the ops coming in (see [`crate::tilt`]).
    in_plane: crate::tilt::Rotation,
    /// Turns released ops into the workpiece system.
    tilt: crate::tilt::TiltStage,
    /// Released ops in the workpiece system, ready to pop.
    tilted: VecDeque<Op>,
}

impl Compensator {
    /// A compensator with the tool at `start`, compensation off, working plane XY, tool
    /// radius 0 and the default look-ahead.
    pub fn new(start: Pose) -> Self {
        Compensator::with_lookahead(start, DEFAULT_LOOKAHEAD)
    }

    /// As [`Compensator::new`], holding `elements` finished elements back before release
    /// (0 releases each element as soon as its end corner is known).
    pub fn with_lookahead(start: Pose, elements: usize) -> Self {
        Compensator {
            plane: Plane::XY,
            tool: 0.0,
            state: State::Off,
            pos: start,
            pending: None,
            approach: None,
            held: VecDeque::new(),
            recent: VecDeque::new(),
            out: VecDeque::new(),
            lookahead: elements,
            finished: false,
            failed: false,
            rule: None,
            in_plane: crate::tilt::IDENTITY,
            tilt: crate::tilt::TiltStage::new(),
            tilted: VecDeque::new(),
        }
    }

    /// Takes the next op of the programmed stream.
    ///
    /// After an error the stage is stopped: later pushes return [`CompError::Stopped`] and no
    /// further motion is released.
    pub fn push(&mut self, op: Op) -> Result<(), CompError> {
        if self.failed {
            return Err(CompError::Stopped { loc: op.loc });
        }
        if self.finished {
            return Err(CompError::AfterFinish { loc: op.loc });
        }
        let r = self.accept(op);
        if let Err(e) = &r {
            tracing::debug!(error = %e, "radius compensation stopped");
            self.failed = true;
        }
        r
    }

    /// Marks the end of input: ends an open compensation (the last element ends on its own
    /// normal) and releases everything held.
    ///
    /// Fails when an APPR block was never followed by a contour element, or when the last
    /// elements violate the contour. After an earlier error, or a second time, it does
    /// nothing.
    pub fn finish(&mut self) -> Result<(), CompError> {
        if self.failed || self.finished {
            self.finished = true;
            return Ok(());
        }
        self.finished = true;
        let r = self.end_section();
        if r.is_err() {
            self.failed = true;
            return r;
        }
        self.release_all();
        Ok(())
    }

    /// The next op of the tool-centre stream, in order, in workpiece coordinates.
    pub fn pop(&mut self) -> Option<Op> {
        if self.failed {
            return None;
        }
        loop {
            if let Some(op) = self.tilted.pop_front() {
                return Some(op);
            }
            let op = self.out.pop_front()?;
            self.tilt.push(op, &mut self.tilted);
        }
    }

    /// True while no op is ready to pop and input is still open: push more.
    pub fn needs_input(&self) -> bool {
        !self.finished && !self.failed && self.out.is_empty() && self.tilted.is_empty()
    }

    /// The working plane used for compensation (from the last tool change's tool axis).
    pub fn plane(&self) -> Plane {
        self.plane
    }

    /// The active tool radius including DR.
    pub fn tool_radius(&self) -> f64 {
        self.tool
    }

    /// The machine moved the tool itself to `to` (X, Y, Z; a probing move it stopped at the
    /// probe's trigger) with compensation off: the next op starts there. False (nothing
    /// changes) while compensation is on or an approach waits.
    pub fn moved_to(&mut self, to: [f64; 3]) -> bool {
        if !matches!(self.state, State::Off) || self.approach.is_some() {
            return false;
        }
        for (l, v) in [AxisLetter::X, AxisLetter::Y, AxisLetter::Z].iter().zip(to) {
            self.pos[*l] = v;
        }
        true
    }

    fn side_sign(side: CompSide) -> f64 {
        match side {
            CompSide::Right => -1.0,
            _ => 1.0,
        }
    }

    fn accept(&mut self, op: Op) -> Result<(), CompError> {
        let loc = op.loc;
        match &op.kind {
            OpKind::RadiusComp { side } => self.switch(*side, op),
            OpKind::CornerRule { rule } => {
                self.rule = Some(*rule);
                Ok(())
            }
            OpKind::ToolChange { axis, radius, .. } => {
                if matches!(self.state, State::Active(_)) || self.approach.is_some() {
                    return Err(CompError::ToolChangeWhileCompensating { loc });
                }
                if !radius.is_finite() {
                    return Err(CompError::NonFinite {
                        loc,
                        what: "tool radius",
                    });
                }
                self.tool = *radius;
                if let Some(p) = Plane::from_tool_axis(*axis) {
                    self.plane = p;
                }
                if let State::Starting(_) = self.state {
                    self.check_radius(loc)?;
                }
                self.pass(op);
                Ok(())
            }
            OpKind::Approach {
                to,
                shape,
                side,
                feed_to_aux,
                feed,
                plane,
                ..
            } => {
                match self.state {
                    State::Off => {}
                    State::Starting(s) if s == *side && self.approach.is_none() => {}
                    _ => return Err(CompError::ApproachWhileCompensating { loc }),
                }
                if *side == CompSide::Off {
                    return Err(CompError::BadApproach {
                        loc,
                        what: "needs RL or RR",
                    });
                }
                if !to.0.iter().all(|v| v.is_finite()) {
                    return Err(CompError::NonFinite {
                        loc,
                        what: "APPR contour point",
                    });
                }
                self.plane = *plane;
                self.check_radius(loc)?;
                self.state = State::Starting(*side);
                self.approach = Some((
                    Approach {
                        to: *to,
                        shape: *shape,
                        side: Self::side_sign(*side),
                        feed_to_aux: *feed_to_aux,
                        feed: *feed,
                        loc,
                    },
                    Vec::new(),
                ));
                Ok(())
            }
            OpKind::Depart {
                to,
                shape,
                feed,
                plane,
                ..
            } => {
                let State::Active(side) = self.state else {
                    return Err(CompError::DepartWithoutContour { loc });
                };
                if *plane != self.plane {
                    return Err(CompError::BadApproach {
                        loc,
                        what: "plane differs from the working plane of the contour",
                    });
                }
                let last = self.close_pending()?;
                let dep = Depart {
                    to: *to,
                    shape: *shape,
                    side: Self::side_sign(side),
                    feed: *feed,
                    loc,
                };
                let ops = approach::depart(&dep, &last, self.pos, self.plane)?;
                if let Some(end) = ops.last().and_then(end_of) {
                    self.pos = end;
                }
                self.emit_group(Group {
                    ops,
                    path: Vec::new(),
                    loc,
                });
                self.state = State::Off;
                self.release_all();
                Ok(())
            }
            OpKind::Spline { to, .. } => match self.state {
                State::Off => {
                    let to = *to;
                    let op = self.curve_after(op)?;
                    self.pos = to;
                    self.pass(op);
                    Ok(())
                }
                _ => Err(CompError::SplineCompensated { loc }),
            },
            OpKind::Line { .. } | OpKind::Arc { .. } => self.motion(op),
            OpKind::Tcpm {
                reframe: Some(p), ..
            } => {
                if !matches!(self.state, State::Off) || self.approach.is_some() {
                    return Err(CompError::TcpmWhileCompensating { loc });
                }
                // The machine stands still; its position in the new frame (workpiece
                // coordinates) in the terms of the plane in force.
                self.pos = crate::tilt::reexpress(&crate::tilt::IDENTITY, &self.in_plane, p);
                self.route(Trail::Pass(op));
                Ok(())
            }
            OpKind::WorkingPlane { rotation } => {
                // The tool stands where it stood; from here on in the new plane's terms.
                self.pos = crate::tilt::reexpress(&self.in_plane, rotation, &self.pos);
                self.in_plane = *rotation;
                self.route(Trail::Pass(op));
                Ok(())
            }
            OpKind::SpindleSync { .. } | OpKind::RigidTap { .. } => {
                // A thread pass or a rigid tap is the tool tip's own path: it moves
                // uncompensated, and the following moves start from its end.
                if let Some((_, to)) = op.kind.geared_ends() {
                    self.pos = to;
                }
                self.route(Trail::Pass(op));
                Ok(())
            }
            _ => {
                self.route(Trail::Pass(op));
                Ok(())
            }
        }
    }

    /// A motion op that is a line or an arc.
    fn motion(&mut self, op: Op) -> Result<(), CompError> {
        let loc = op.loc;
        let rule = self.rule.take();
        match self.state {
            State::Off => {
                if let OpKind::Line { to, feed, .. } = op.kind {
                    if !to.0.iter().all(|v| v.is_finite()) {
                        return Err(CompError::NonFinite {
                            loc,
                            what: "line end point",
                        });
                    }
                    let out = line(self.pos, to, feed, loc);
                    self.pos = to;
                    self.pass(out);
                } else if let OpKind::Arc { to, .. } = op.kind {
                    let op = self.curve_after(op)?;
                    self.pos = to;
                    self.pass(op);
                }
                Ok(())
            }
            State::Starting(side) => {
                let elem = match Element::classify(&op, self.plane)? {
                    Some(Motion::Contour(elem)) => elem,
                    Some(Motion::OffPlane { to, feed }) => {
                        // Compensation takes effect with the first move in the working plane;
                        // a tool-axis move before it (with APPR: after it) runs as programmed.
                        if self.approach.is_some() {
                            self.route(Trail::OffPlane { to, feed, loc });
                        } else {
                            let out = line(
                                self.pos,
                                with_point(&to, self.plane, project(&self.pos, self.plane)),
                                feed,
                                loc,
                            );
                            self.pos = end_of(&out).unwrap_or(self.pos);
                            self.pass(out);
                        }
                        return Ok(());
                    }
                    None => return Ok(()),
                };
                let d = Self::side_sign(side) * self.tool;
                if let Some((appr, trail)) = self.approach.take() {
                    let mut p = Pending::new(elem, d, self.tool, false)?;
                    p.end_rule = rule;
                    let pa = p.curve.point_from_start(0.0);
                    let mut ops = approach::approach(&appr, &p.elem, pa, self.pos, self.plane)?;
                    if let Some(end) = ops.last().and_then(end_of) {
                        self.pos = end;
                    }
                    for t in &trail {
                        self.pos = t.emit(self.pos, self.plane, &mut ops);
                    }
                    self.emit_group(Group {
                        ops,
                        path: Vec::new(),
                        loc: appr.loc,
                    });
                    self.remember(&p);
                    self.pending = Some(p);
                } else {
                    if matches!(elem.shape, element::Shape::Arc { .. }) {
                        return Err(CompError::StartOnArc { loc });
                    }
                    self.pending = Some(Pending::new(elem, d, self.tool, true)?);
                }
                self.state = State::Active(side);
                Ok(())
            }
            State::Active(side) => {
                let d = Self::side_sign(side) * self.tool;
                match Element::classify(&op, self.plane)? {
                    Some(Motion::Contour(elem)) => self.next_element(elem, d, rule),
                    Some(Motion::OffPlane { to, feed }) => {
                        self.route(Trail::OffPlane { to, feed, loc });
                        Ok(())
                    }
                    None => Ok(()),
                }
            }
        }
    }

    /// Joins a new contour element to the pending one; the pending one is then complete.
    fn next_element(
        &mut self,
        elem: Element,
        d: f64,
        rule: Option<CornerRule>,
    ) -> Result<(), CompError> {
        let mut b = Pending::new(elem, d, self.tool, false)?;
        b.end_rule = rule;
        let a = self.pending.take();
        if let Some(mut a) = a {
            let gap = project(&a.elem.to, self.plane).dist(b.elem.start());
            if gap > CONTINUITY_TOLERANCE {
                return Err(CompError::Discontinuity {
                    loc: b.elem.loc,
                    gap,
                });
            }
            corner::join(&mut a, &mut b, d, self.tool)?;
            // The specific diagnostics (corners, elements running backwards) come first.
            corner::check_forward(&a, Some(b.elem.loc), self.tool)?;
            self.check_held(&b)?;
            self.remember(&b);
            self.emit_pending(&a)?;
        } else {
            self.check_held(&b)?;
            self.remember(&b);
        }
        self.pending = Some(b);
        Ok(())
    }

    /// Checks the tool paths held back against a new programmed element.
    fn check_held(&self, b: &Pending) -> Result<(), CompError> {
        for g in &self.held {
            if let Some(distance) = gouge::intrusion(&g.path, &b.elem.shape, self.tool) {
                return Err(CompError::Gouge {
                    blocks: vec![g.loc, b.elem.loc],
                    distance,
                    tool: self.tool,
                });
            }
        }
        Ok(())
    }

    /// Ends the pending element on its own normal and emits it; returns its element.
    fn close_pending(&mut self) -> Result<Element, CompError> {
        let Some(a) = self.pending.take() else {
            return Err(CompError::DepartWithoutContour {
                loc: SourceLoc::default(),
            });
        };
        corner::check_forward(&a, None, self.tool)?;
        self.emit_pending(&a)?;
        Ok(a.elem)
    }

    /// Ends an open compensation section (R0, end of input).
    fn end_section(&mut self) -> Result<(), CompError> {
        if let Some((appr, _)) = &self.approach {
            return Err(CompError::ApproachWithoutContour { loc: appr.loc });
        }
        if self.pending.is_some() {
            self.close_pending()?;
        }
        self.state = State::Off;
        Ok(())
    }

    fn switch(&mut self, side: CompSide, op: Op) -> Result<(), CompError> {
        let loc = op.loc;
        match (self.state, side) {
            (State::Off, CompSide::Off) => {}
            (State::Off, s) => {
                self.state = State::Starting(s);
                self.check_radius(loc)?;
                tracing::debug!(
                    ?s,
                    radius = self.tool,
                    line = loc.line,
                    "radius compensation on"
                );
            }
            (State::Starting(_) | State::Active(_), CompSide::Off) => {
                self.end_section()?;
                self.release_all();
                tracing::debug!(line = loc.line, "radius compensation off");
            }
            (State::Starting(cur) | State::Active(cur), s) if cur == s => {}
            _ => return Err(CompError::SideSwitch { loc }),
        }
        self.route(Trail::Pass(op));
        Ok(())
    }

    fn check_radius(&self, loc: SourceLoc) -> Result<(), CompError> {
        if self.tool < 0.0 {
            return Err(CompError::NegativeRadius {
                loc,
                radius: self.tool,
            });
        }
        Ok(())
    }

    /// An arc or spline with compensation off must start where the tool is (after R0 or DEP
    /// the tool is off the programmed point); it is then made to start exactly there.
    fn curve_after(&self, mut op: Op) -> Result<Op, CompError> {
        let loc = op.loc;
        if let OpKind::Arc { from, .. } | OpKind::Spline { from, .. } = &mut op.kind {
            let off = from
                .0
                .iter()
                .zip(&self.pos.0)
                .map(|(a, b)| (a - b).abs())
                .any(|d| d.is_nan() || d > CONTINUITY_TOLERANCE);
            if off {
                return Err(CompError::CurveAfterCompensation { loc });
            }
            *from = self.pos;
        }
        Ok(op)
    }

    /// Puts a non-motion op (or off-plane move) in its place in the stream.
    fn route(&mut self, t: Trail) {
        if let Some(p) = self.pending.as_mut() {
            p.trail.push(t);
        } else if let Some((_, trail)) = self.approach.as_mut() {
            trail.push(t);
        } else if let Trail::Pass(op) = t {
            self.pass(op);
        }
    }

    /// Remembers a programmed contour element for the gouge check of the window.
    fn remember(&mut self, p: &Pending) {
        if p.lead_in {
            return;
        }
        self.recent.push_back((p.elem.loc, p.elem.shape));
        while self.recent.len() > self.lookahead + 2 {
            self.recent.pop_front();
        }
    }

    /// Emits a complete element after checking its tool path against the window.
    fn emit_pending(&mut self, p: &Pending) -> Result<(), CompError> {
        let mut ops = Vec::new();
        let pos = p.emit(self.pos, self.plane, &mut ops);
        let path = if p.lead_in {
            Vec::new()
        } else {
            gouge::pieces(&ops, self.plane)
        };
        // The offset of its own element lies at the tool radius from it by construction, but
        // the transition arc after it is checked against it too (an arc of more than half a
        // turn can wrap around into the tool's way).
        let corner_path = match (p.corner, ops.last()) {
            (Some(_), Some(last)) => gouge::pieces(std::slice::from_ref(last), self.plane),
            _ => Vec::new(),
        };
        for (loc, shape) in &self.recent {
            if p.open_to.contains(loc) {
                continue;
            }
            let own = *shape == p.elem.shape && *loc == p.elem.loc;
            let checked = if own { &corner_path } else { &path };
            if let Some(distance) = gouge::intrusion(checked, shape, self.tool) {
                let blocks = if own {
                    vec![*loc]
                } else {
                    vec![p.elem.loc, *loc]
                };
                return Err(CompError::Gouge {
                    blocks,
                    distance,
                    tool: self.tool,
                });
            }
        }
        self.pos = pos;
        self.emit_group(Group {
            ops,
            path,
            loc: p.elem.loc,
        });
        Ok(())
    }

    fn emit_group(&mut self, g: Group) {
        self.held.push_back(g);
        while self.held.len() > self.lookahead {
            if let Some(g) = self.held.pop_front() {
                self.out.extend(g.ops);
            }
        }
    }

    fn release_all(&mut self) {
        while let Some(g) = self.held.pop_front() {
            self.out.extend(g.ops);
        }
        self.recent.clear();
    }

    /// Passes an op straight to the output (nothing is held in front of it).
    fn pass(&mut self, op: Op) {
        self.release_all();
        self.out.push_back(op);
    }
}

/// End pose of a line or arc op.
fn end_of(op: &Op) -> Option<Pose> {
    match &op.kind {
        OpKind::Line { to, .. } | OpKind::Arc { to, .. } => Some(*to),
        _ => None,
    }
}
