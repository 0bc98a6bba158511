//! The tilted working plane: PLANE blocks, cycle 19, and tool centre point management
//! (M128/M129, FUNCTION TCPM / FUNCTION RESET TCPM) on a table-table machine.
//!
//! A PLANE block defines the rotation of the working plane (see [`super::plane_math`] for
//! every form), computes the rotary-axis angles that put the tool along the tilted tool axis
//! and writes them to Q120 (A), Q121 (B) and Q122 (C). What happens next is the block's
//! positioning word:
//! - MOVE: the rotary axes turn to the angles at the block's F (or FMAX) while the tool tip
//!   keeps its place on the workpiece; with DIST the point DIST above the tip along the tool
//!   axis stays put instead (the tip swings about it).
//! - TURN: only the rotary axes turn; the machine's linear axes stay where they are, so the
//!   tool tip ends on whatever point of the workpiece the table carries under it, and the
//!   program positions the linear axes afterwards. Where that point is depends on the
//!   machine's pivots: told them (`Interpreter::with_table_geometry`), the interpreter passes
//!   the turn on as pieces of the tip's path on the workpiece that keep the linear axes
//!   within a fraction of a micrometre of their place, between exact stops, and carries on
//!   from the tip's new point (see [`super::plane_turn`]). Not told them (no table-table
//!   machine, or a check without one), TURN holds the tool tip like MOVE. MB is accepted and
//!   ignored.
//! - STAY: nothing moves; the program positions the axes itself (`L A+Q120 C+Q122`).
//!
//! From the block on, the coordinates of the program are in the tilted system: every point
//! an op carries is turned by the plane's rotation into the untilted workpiece system after
//! the coordinate transforms of the cycles (datum shift, mirror, rotation, scaling), i.e. the
//! tilt is the last stage and turns about the workpiece datum. Arcs of a tilted plane leave
//! their principal plane, so they are passed on as chains of lines within 1 µm; splines keep
//! their form with turned coefficients.
//!
//! Radius compensation (RL/RR) and APPR/DEP must work in the tilted plane, before the turn.
//! So the interpreter can leave the turn to motion (working-plane ops, see
//! [`super::plane_output`]): the ops then stay in the tilted system, an
//! [`OpKind::WorkingPlane`] op marks where each new plane takes effect, and the compensation
//! stage offsets the contour in the tilted plane and turns its output. The rotary-axis moves
//! of PLANE … MOVE/TURN come after that op, expressed in the new plane. Without
//! working-plane ops, RL/RR and APPR/DEP are refused while a plane is tilted. Either way the
//! plane cannot change while compensation is on: the contour would run through two planes.
//!
//! The workpiece coordinates reach the machine through the kinematics' tool-tip
//! transformation, so any PLANE other than RESET switches it on ([`OpKind::Tcpm`]); PLANE
//! RESET with MOVE or TURN turns the axes back to zero and switches it off again unless M128
//! or FUNCTION TCPM is active. M128 / FUNCTION TCPM switch it on at the block start, M129 /
//! FUNCTION RESET TCPM off (when no tilted plane needs it). Each switch follows an exact
//! stop, and is meant to happen while the rotary axes stand at zero, where workpiece and
//! machine coordinates agree (PLANE RESET STAY with the axes still turned leaves it on).
//!
//! The interpreter learns the machine's rotary axes from its owner
//! (`Interpreter::with_rotary_axes`); one never told assumes an A/C table.
//!
//! Cycle 19 (`19.0 WORKING PLANE`, `19.1 A.. B.. C..`) tilts the plane by the same spatial
//! angles as PLANE SPATIAL with STAY; `19.1` without angles (or all zero) resets it.

use std::collections::VecDeque;

use super::exec::{ExecError, Flow, Machine, at, here};
use super::expr::{ParamKind, ParamRef, Value};
use super::plane_math::{self as pm, Choice, IDENTITY, M3, Tilt};
use super::plane_output::turn;
use super::stmt::{Parsed, text_of};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, CompSide, Feed, Op, OpKind, Pose, SourceLoc};

/// The PLANE form.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum PlaneKind {
    /// PLANE RESET.
    #[default]
    Reset,
    /// PLANE SPATIAL.
    Spatial,
    /// PLANE PROJECTED.
    Projected,
    /// PLANE EULER.
    Euler,
    /// PLANE VECTOR.
    Vector,
    /// PLANE POINTS.
    Points,
    /// PLANE RELATIV.
    Relativ,
    /// PLANE AXIAL.
    Axial,
}

/// What the block does with the rotary axes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Positioning {
    /// MOVE.
    Move,
    /// TURN.
    Turn,
    /// STAY.
    Stay,
}

/// How a PLANE block's rotary move treats the tool.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Swing {
    /// MOVE: the tip stays (or, with DIST, the point that far up the tool axis).
    Move(Option<f64>),
    /// TURN: only the rotary axes move.
    Turn,
}

/// Words with a value, by slot.
pub(crate) const NAMES: [&[u8]; 30] = [
    b"SPA", b"SPB", b"SPC", b"PROPR", b"PROMIN", b"ROT", b"EULPR", b"EULNU", b"EULROT", b"BX",
    b"BY", b"BZ", b"NX", b"NY", b"NZ", b"P1X", b"P1Y", b"P1Z", b"P2X", b"P2Y", b"P2Z", b"P3X",
    b"P3Y", b"P3Z", b"A", b"B", b"C", b"DIST", b"F", b"MB",
];
pub(crate) const SPA: usize = 0;
pub(crate) const PROPR: usize = 3;
pub(crate) const EULPR: usize = 6;
pub(crate) const BX: usize = 9;
pub(crate) const NX: usize = 12;
pub(crate) const P1X: usize = 15;
pub(crate) const AXA: usize = 24;
pub(crate) const DIST: usize = 27;
pub(crate) const FEED: usize = 28;

/// The words of a PLANE block.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct PlaneWords {
    /// The form.
    pub kind: PlaneKind,
    /// Values by slot (see `NAMES`), with the word position.
    pub vals: [Option<(Value, u32)>; 30],
    /// MOVE, TURN or STAY.
    pub positioning: Option<Positioning>,
    /// FMAX (or F MAX) was programmed.
    pub rapid: bool,
    /// SEQ+ (true) or SEQ− (false).
    pub seq: Option<bool>,
    /// TABLE ROT (true) or COORD ROT (false).
    pub table_rot: Option<bool>,
}

/// State of the working plane and of TCPM.
#[derive(Debug)]
pub(crate) struct PlaneState {
    /// The machine's rotary axes (set by the interpreter's owner); `None`: not told (PLANE
    /// then assumes an A/C table).
    pub rotary: Option<Vec<AxisLetter>>,
    /// The active rotation (columns: tilted axes in the workpiece system).
    pub r: M3,
    /// `r` is the identity.
    pub identity: bool,
    /// M128 or FUNCTION TCPM is on.
    pub m128: bool,
    /// A tilted plane needs the tool-tip transformation.
    pub plane_tcpm: bool,
    /// The TCPM state last passed on.
    pub kin_on: bool,
    /// The feed of M128's compensating moves (mm/s), while M128 is on.
    pub m128_feed: Option<f64>,
    /// The compensating-move feed last passed on.
    pub kin_feed: Option<f64>,
    /// How FUNCTION TCPM reads the feed and the rotary coordinates.
    pub tcpm_mode: super::tcpm::TcpmMode,
    /// M116: F on rotary table axes is the tool point's speed (see [`super::rotary_feed`]).
    pub m116: bool,
    /// Ops at the front of the queue already tilted.
    pub pre: usize,
    /// Lines of a tilted arc still to hand out.
    pub pending: VecDeque<Op>,
    /// Working-plane ops on: ops stay in the tilted system, [`OpKind::WorkingPlane`] marks
    /// each change (see [`super::plane_output`]).
    pub deferred: bool,
    /// The table-table geometry (set by the interpreter's owner); `None`: TURN holds the tool
    /// tip like MOVE.
    pub geometry: Option<super::plane_turn::TableGeometry>,
}

impl Default for PlaneState {
    fn default() -> Self {
        PlaneState {
            rotary: None,
            r: IDENTITY,
            identity: true,
            m128: false,
            plane_tcpm: false,
            kin_on: false,
            m128_feed: None,
            kin_feed: None,
            tcpm_mode: Default::default(),
            m116: false,
            pre: 0,
            pending: VecDeque::new(),
            deferred: false,
            geometry: None,
        }
    }
}

/// `Q120`, `Q121`, `Q122`.
fn q(index: u32) -> ParamRef {
    ParamRef {
        kind: ParamKind::Q,
        index,
    }
}

impl Machine {
    /// Tells the interpreter which axes the machine has (only the rotary ones matter).
    pub fn set_rotary_axes(&mut self, axes: &[AxisLetter]) {
        let rot: Vec<AxisLetter> = axes.iter().copied().filter(|a| a.is_rotary()).collect();
        self.tilt.rotary = Some(rot);
    }

    /// The machine's tilt axis, or the error naming what it has.
    /// An interpreter not told the machine's axes (a check without a machine) assumes an A/C
    /// table.
    fn machine_tilt(&self) -> Result<Tilt, ExecError> {
        let Some(rot) = self.tilt.rotary.as_deref() else {
            return Ok(Tilt::A);
        };
        let has = |l| rot.contains(&l);
        if has(AxisLetter::C) && has(AxisLetter::A) && !has(AxisLetter::B) {
            return Ok(Tilt::A);
        }
        if has(AxisLetter::C) && has(AxisLetter::B) && !has(AxisLetter::A) {
            return Ok(Tilt::B);
        }
        let what = if rot.is_empty() {
            "no rotary axes".to_string()
        } else {
            let list: Vec<String> = rot.iter().map(ToString::to_string).collect();
            format!("rotary axes {}", list.join(", "))
        };
        Err(here(ProgramError::Plane(format!(
            "PLANE needs rotary axes A and C (or B and C); this machine has {what}"
        ))))
    }

    /// A PLANE block.
    pub(super) fn plane_block(
        &mut self,
        parsed: &Parsed,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Result<Flow, ExecError> {
        let w = parsed.plane;
        let val = |m: &Machine, slot: usize| {
            w.vals
                .get(slot)
                .copied()
                .flatten()
                .map_or(0.0, |(v, _)| m.params.value(v))
        };
        let vec3 = |m: &Machine, s: usize| [val(m, s), val(m, s + 1), val(m, s + 2)];
        let reset = w.kind == PlaneKind::Reset;
        let tilt = match self.machine_tilt() {
            Ok(t) => Some(t),
            Err(_) if reset => None,
            Err(e) => return Err(e),
        };
        let now = self.rotary_now(tilt);
        let geo = |e: &str| here(ProgramError::Plane(e.to_string()));
        let mut axial_angles = now;
        let r: M3 = match w.kind {
            PlaneKind::Reset => IDENTITY,
            PlaneKind::Spatial => {
                pm::spatial(val(self, SPA), val(self, SPA + 1), val(self, SPA + 2))
            }
            PlaneKind::Projected => {
                pm::projected(val(self, PROPR), val(self, PROPR + 1), val(self, PROPR + 2))
                    .map_err(geo)?
            }
            PlaneKind::Euler => {
                pm::euler(val(self, EULPR), val(self, EULPR + 1), val(self, EULPR + 2))
            }
            PlaneKind::Vector => pm::vector(vec3(self, BX), vec3(self, NX)).map_err(geo)?,
            PlaneKind::Points => {
                pm::points(vec3(self, P1X), vec3(self, P1X + 3), vec3(self, P1X + 6))
                    .map_err(geo)?
            }
            PlaneKind::Relativ => {
                let turn = match (0..3).find(|i| w.vals[SPA + i].is_some()) {
                    Some(0) => pm::rx(val(self, SPA)),
                    Some(1) => pm::ry(val(self, SPA + 1)),
                    _ => pm::rz(val(self, SPA + 2)),
                };
                pm::mul(&self.tilt.r, &turn)
            }
            PlaneKind::Axial => {
                let t = tilt.unwrap_or(Tilt::A);
                let (own, other) = match t {
                    Tilt::A => (AXA, AXA + 1),
                    Tilt::B => (AXA + 1, AXA),
                };
                if let Some((_, pos)) = w.vals[other]
                    && val(self, other) != 0.0
                {
                    return Err(at(
                        pos,
                        ProgramError::Plane(
                            "PLANE AXIAL names a rotary axis this machine lacks".into(),
                        ),
                    ));
                }
                let pick = |m: &Machine, slot: usize, keep: f64| {
                    if w.vals[slot].is_some() {
                        val(m, slot)
                    } else {
                        keep
                    }
                };
                axial_angles = (pick(self, own, now.0), pick(self, AXA + 2, now.1));
                pm::axial(t, axial_angles.0, axial_angles.1)
            }
        };
        let angles = match (w.kind, tilt) {
            (PlaneKind::Reset, _) | (_, None) => (0.0, 0.0),
            (PlaneKind::Axial, Some(_)) => axial_angles,
            (_, Some(t)) => {
                let choice = Choice {
                    seq: w.seq,
                    table_rot: w.table_rot == Some(true),
                };
                pm::solve(&r, t, choice, now)
            }
        };
        let feed = if w.rapid {
            Feed::Rapid
        } else if w.vals[FEED].is_some() {
            Feed::Rate(val(self, FEED) * self.feed_scale() / 60.0)
        } else {
            self.feed.map_or(Feed::Rapid, Feed::Rate)
        };
        self.plane_change_allowed(&r)?;
        let moves = w.positioning != Some(Positioning::Stay) && tilt.is_some();
        let dist = w.vals[DIST].map(|_| val(self, DIST) * self.unit);
        let how = if w.positioning == Some(Positioning::Turn) {
            Swing::Turn
        } else {
            Swing::Move(dist)
        };
        self.apply_plane(r, tilt, angles, moves.then_some((feed, how)), out, loc);
        Ok(Flow::Continue)
    }

    /// Present angles of the tilt axis and C in program values.
    fn rotary_now(&self, tilt: Option<Tilt>) -> (f64, f64) {
        let t = match tilt {
            Some(Tilt::B) => AxisLetter::B,
            _ => AxisLetter::A,
        };
        (self.pos[t], self.pos[AxisLetter::C])
    }

    /// Makes `r` the working plane with the rotary axes at `angles`: writes Q120–Q122, turns
    /// the axes when `motion` is given (feed, MOVE with its DIST or TURN), and re-expresses
    /// the position.
    pub(super) fn apply_plane(
        &mut self,
        r: M3,
        tilt: Option<Tilt>,
        angles: (f64, f64),
        motion: Option<(Feed, Swing)>,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) {
        let tilt_letter = match tilt {
            Some(Tilt::B) => AxisLetter::B,
            _ => AxisLetter::A,
        };
        let (qa, qb) = if tilt_letter == AxisLetter::B {
            (0.0, angles.0)
        } else {
            (angles.0, 0.0)
        };
        self.params.set(q(120), qa);
        self.params.set(q(121), qb);
        self.params.set(q(122), angles.1);
        // Everything queued so far keeps the old plane: tilt it now.
        self.premap_queue(out);
        let reset = pm::is_identity(&r, 0.0);
        let mut emitted = Vec::new();
        let mut emit = |kind: OpKind| emitted.push(kind);
        if !reset {
            // TCPM on first: the position is re-expressed as the tool tip on the workpiece.
            self.tilt.plane_tcpm = true;
            self.sync_tcpm(&mut emit);
        }
        // Where the tool is, in workpiece coordinates (machine values of the other axes).
        let here_w = self.workpiece_pos();
        let mut end_w = here_w;
        if let (Some((feed, how)), Some(t)) = (motion, tilt) {
            end_w[tilt_letter] = angles.0;
            end_w[AxisLetter::C] = angles.1;
            let geometry = self.tilt.geometry.filter(|g| g.tilt == t);
            match (how, geometry) {
                // The tool tip follows the table only while the tip transformation is on;
                // without it the linear axes stand still whatever the interpreter does.
                (Swing::Turn, Some(g)) if self.tilt.kin_on => {
                    self.turn_move(&g, tilt_letter, here_w, &mut end_w, feed, &mut emit);
                }
                (Swing::Turn, _) => {
                    self.rotary_move(t, tilt_letter, here_w, &mut end_w, feed, None, &mut emit);
                }
                (Swing::Move(dist), _) => {
                    self.rotary_move(t, tilt_letter, here_w, &mut end_w, feed, dist, &mut emit);
                }
            }
        }
        let at_zero = end_w[tilt_letter] == 0.0 && end_w[AxisLetter::C] == 0.0;
        if reset && (motion.is_some() || at_zero) {
            self.tilt.plane_tcpm = false;
            // TCPM off where the rotary move left the tool: the position becomes the
            // machine's own X Y Z there.
            self.set_workpiece_pos(end_w);
            self.sync_tcpm(&mut emit);
            end_w = self.workpiece_pos();
        }
        if self.tilt.deferred {
            // The new plane holds from here on; the rotary moves above are workpiece
            // coordinates, expressed in it.
            if r != self.tilt.r {
                out.push_back(Op {
                    kind: OpKind::WorkingPlane { rotation: r },
                    loc,
                });
            }
            let back = pm::transpose(&r);
            for kind in emitted {
                let kind = match kind {
                    OpKind::Line { from, to, feed } => OpKind::Line {
                        from: turn(&back, &from),
                        to: turn(&back, &to),
                        feed,
                    },
                    other => other,
                };
                out.push_back(Op { kind, loc });
            }
        } else {
            for kind in emitted {
                out.push_back(Op { kind, loc });
            }
        }
        self.cyc.pre_mapped = out.len();
        self.tilt.pre = out.len();
        self.tilt.r = r;
        self.tilt.identity = reset;
        // Back into program coordinates of the new plane.
        let back = pm::apply(
            &pm::transpose(&r),
            [
                end_w[AxisLetter::X],
                end_w[AxisLetter::Y],
                end_w[AxisLetter::Z],
            ],
        );
        let mut machine = end_w;
        machine[AxisLetter::X] = back[0];
        machine[AxisLetter::Y] = back[1];
        machine[AxisLetter::Z] = back[2];
        self.pos = self.cyc.xf.unmap_point(&machine);
    }

    /// Refuses to change the working plane to `r` while radius compensation is on: the
    /// compensated contour would run through two planes.
    fn plane_change_allowed(&self, r: &M3) -> Result<(), ExecError> {
        if self.comp != CompSide::Off && *r != self.tilt.r {
            return Err(here(ProgramError::Plane(
                "the working plane cannot change while radius compensation is on; \
                 cancel it with R0 or DEP first"
                    .into(),
            )));
        }
        Ok(())
    }

    /// The present position in untilted workpiece coordinates (after the cycle transforms).
    pub(super) fn workpiece_pos(&self) -> Pose {
        let mut m = self.cyc.xf.map_point(&self.pos);
        let p = pm::apply(
            &self.tilt.r,
            [m[AxisLetter::X], m[AxisLetter::Y], m[AxisLetter::Z]],
        );
        m[AxisLetter::X] = p[0];
        m[AxisLetter::Y] = p[1];
        m[AxisLetter::Z] = p[2];
        m
    }

    /// Turns the rotary axes from `from` to the angles in `to`. The tool tip stays where it
    /// is on the workpiece, or with `dist` the point `dist` up the tool axis stays and the tip
    /// swings about it (in steps of at most 2°). Sets the tip's end in `to`.
    #[allow(clippy::too_many_arguments)]
    fn rotary_move(
        &mut self,
        tilt: Tilt,
        tilt_letter: AxisLetter,
        from: Pose,
        to: &mut Pose,
        feed: Feed,
        dist: Option<f64>,
        emit: &mut impl FnMut(OpKind),
    ) {
        let (t0, c0) = (from[tilt_letter], from[AxisLetter::C]);
        let (t1, c1) = (to[tilt_letter], to[AxisLetter::C]);
        if t0 == t1 && c0 == c1 {
            return;
        }
        let d = dist.unwrap_or(0.0);
        let n0 = pm::tool_axis(tilt, t0, c0);
        let tip = [
            from[AxisLetter::X],
            from[AxisLetter::Y],
            from[AxisLetter::Z],
        ];
        let pivot = [tip[0] + d * n0[0], tip[1] + d * n0[1], tip[2] + d * n0[2]];
        let span = (t1 - t0).abs().max((c1 - c0).abs());
        let steps = if d == 0.0 {
            1
        } else {
            (span / 2.0).ceil().clamp(1.0, 10_000.0) as usize
        };
        let mut prev = from;
        for k in 1..=steps {
            let f = k as f64 / steps as f64;
            let (t, c) = (t0 + (t1 - t0) * f, c0 + (c1 - c0) * f);
            let n = pm::tool_axis(tilt, t, c);
            let mut p = prev;
            p[tilt_letter] = t;
            p[AxisLetter::C] = c;
            p[AxisLetter::X] = pivot[0] - d * n[0];
            p[AxisLetter::Y] = pivot[1] - d * n[1];
            p[AxisLetter::Z] = pivot[2] - d * n[2];
            emit(OpKind::Line {
                from: prev,
                to: p,
                feed,
            });
            prev = p;
        }
        self.last_feed = Some(feed);
        *to = prev;
    }

    /// `CYCL DEF 19.0` / `19.1 A.. B.. C..` (old format) blocks: spatial angles, no motion.
    pub(super) fn cycle19(
        &mut self,
        sub: Option<u8>,
        parsed: &Parsed,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Result<Flow, ExecError> {
        if sub == Some(0) {
            return Ok(Flow::Continue);
        }
        let mut abc = [0.0; 3];
        for it in &parsed.cycle.items {
            let slot = match it.word() {
                b"A" => 0,
                b"B" => 1,
                b"C" => 2,
                // F and MB of newer controls position the axes: klar leaves that to the
                // program (as with PLANE … STAY).
                b"F" | b"MB" | b"FMAX" => continue,
                _ => {
                    return Err(at(
                        it.pos,
                        ProgramError::Unexpected(format!(
                            "word {} in cycle 19",
                            text_of(it.word())
                        )),
                    ));
                }
            };
            abc[slot] = it.value.map_or(0.0, |v| self.params.value(v));
        }
        let r = pm::spatial(abc[0], abc[1], abc[2]);
        self.plane_change_allowed(&r)?;
        let reset = pm::is_identity(&r, 0.0);
        let tilt = match self.machine_tilt() {
            Ok(t) => Some(t),
            Err(_) if reset => None,
            Err(e) => return Err(e),
        };
        let now = self.rotary_now(tilt);
        let angles = match tilt {
            Some(t) if !reset => pm::solve(
                &r,
                t,
                Choice {
                    seq: None,
                    table_rot: false,
                },
                now,
            ),
            _ => (0.0, 0.0),
        };
        self.apply_plane(r, tilt, angles, None, out, loc);
        Ok(Flow::Continue)
    }
}
