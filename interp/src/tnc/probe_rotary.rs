//! Touch-probe cycles that take out a misalignment by turning a rotary axis instead of
//! writing a basic rotation: 403 (two points on an edge) and 405 (the centre of a bore).
//!
//! The rules, as klar applies them. The TNC 640 / iTNC 530 touch-probe manuals' pages for
//! 405 were found; the page for 403 was not, so its parameters follow the cycle's twin 400
//! and the usual meaning of their numbers, and klar's reading is said where it chooses:
//! - **403**: probes the two points of an edge exactly as 400 (Q263 … Q267, Q272, Q261, Q320,
//!   Q260, Q301); Q150 is the edge's angle against its axis. Q380 is the angle the edge
//!   shall have (0: along the axis). The axis named by Q312 (4 A, 5 B, 6 C; 0: the machine's
//!   axis about the tool axis) then turns by the measured angle less Q380, so that the edge
//!   lies at Q380 afterwards. klar turns only the axis about the tool axis (C with tool axis
//!   Z, B with Y, A with X): aligning with a tilting axis would need touch points along the
//!   tool axis (Q272=3), which klar refuses.
//! - **405**: probes a bore at four points as 412 (Q321/Q322 nominal centre, Q262 nominal
//!   diameter, Q325 starting angle, Q247 step, Q261, Q320, Q260, Q301). The angle of the
//!   measured centre about the datum is compared with the angle it shall have: that of the
//!   nominal centre, or +90° (the positive minor axis, Y) when Q322 is 0. The table axis
//!   about the tool axis (C for tool axis Z) turns by the difference, which is Q150. The
//!   datum must lie on the table axis for the turn to bring the centre where it belongs, as
//!   the manual presumes when it asks for the hole at a positive Y coordinate.
//! - Both cycles turn the axis at rapid traverse after the probe has returned to the
//!   clearance height. The axis is taken to be a rotary table turning in the primed sense:
//!   turning it by +a turns the workpiece by −a about the tool axis, so a part found turned
//!   by +1.5° is aligned by turning the axis by +1.5°.
//! - Q337=1 then makes that axis read 0 where it stands: its column of preset row Q305 (0:
//!   the active preset, which acts at once) takes its machine position. Q337=0 leaves the
//!   presets alone.

use std::collections::VecDeque;

use super::cycle_exec::CycleDef;
use super::exec::{ExecError, Machine};
use super::probe_exec::Run;
use super::probe_ref::bad;
use crate::cycles::{ParamKey, ParamSource};
use crate::op::{AxisLetter, Feed, Op, OpKind};

/// `deg` in (−180°, 180°].
fn half_turn(deg: f64) -> f64 {
    let a = deg.rem_euclid(360.0);
    if a > 180.0 { a - 360.0 } else { a }
}

impl Machine {
    /// The axis Q312 names (0, 4, 5 or 6), checked to be the rotary axis about the tool axis
    /// and one the machine has.
    fn compensation_axis(&self, def: &CycleDef) -> Result<AxisLetter, ExecError> {
        let cycle = def.number;
        let (_, _, n) = self.plane.axes();
        let about = match n {
            AxisLetter::X => AxisLetter::A,
            AxisLetter::Y => AxisLetter::B,
            _ => AxisLetter::C,
        };
        let q312 = self.opt(def, 312, 0.0);
        let named = match q312 {
            0.0 => about,
            4.0 => AxisLetter::A,
            5.0 => AxisLetter::B,
            6.0 => AxisLetter::C,
            v => {
                return Err(bad(
                    cycle,
                    format!("Q312={v}: the compensation axis is 4 (A), 5 (B), 6 (C) or 0"),
                ));
            }
        };
        if named != about {
            return Err(bad(
                cycle,
                format!(
                    "Q312={q312}: compensating with {} (a tilting axis) is not supported yet; the axis about the tool axis {} is {}",
                    named.as_char(),
                    n.as_char(),
                    about.as_char()
                ),
            ));
        }
        if let Some(rot) = self.tilt.rotary.as_deref()
            && !rot.contains(&named)
        {
            return Err(bad(
                cycle,
                format!("this machine has no rotary axis {}", named.as_char()),
            ));
        }
        Ok(named)
    }

    /// Turns `axis` by `turn` degrees at rapid traverse and, with Q337=1, makes it read 0.
    fn turn_table(
        &mut self,
        def: &CycleDef,
        axis: AxisLetter,
        turn: f64,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let zero = self.opt(def, 337, 0.0);
        if !(zero == 0.0 || zero == 1.0) {
            return Err(bad(def.number, format!("Q337={zero}: 0 or 1")));
        }
        let from = self.pos;
        let mut to = from;
        to[axis] += turn;
        if turn != 0.0 {
            out.push_back(Op {
                kind: OpKind::Line {
                    from,
                    to,
                    feed: Feed::Rapid,
                },
                loc: run.loc,
            });
        }
        self.pos = to;
        if zero == 0.0 {
            return Ok(());
        }
        let mut xf = self.cyc.xf;
        let i = axis.index();
        xf.preset[i] += to[axis];
        let mut values = [None; 9];
        values[i] = Some(xf.preset[i]);
        self.write_preset(def.number, def, xf, &values, None, out, run.loc)
    }

    /// 403: the misalignment of an edge taken out by turning a rotary axis.
    pub(super) fn cycle403(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let axis = self.compensation_axis(def)?;
        if self.opt(def, 272, 1.0) == 3.0 {
            return Err(bad(
                def.number,
                "Q272=3 (touch points along the tool axis) is not supported yet",
            ));
        }
        let measured = self.edge_angle(def, run, out)?;
        self.set_q(150, measured);
        let reference = self.opt(def, 380, 0.0);
        let turn = half_turn(measured - reference);
        self.turn_table(def, axis, turn, run, out)
    }

    /// 405: the angle of a bore's centre about the datum taken out by turning the table axis.
    pub(super) fn cycle405(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let axis = self.compensation_axis(def)?;
        let nominal = [self.need(def, 321)?, self.need(def, 322)?];
        let (centre, _) = self.probe_circle(def, true, false, run, out)?;
        if centre[0].hypot(centre[1]) < 1e-6 {
            return Err(bad(
                def.number,
                "the bore's centre lies on the datum: it has no angle to align",
            ));
        }
        let target = if def.get(ParamKey::Q(322)) == Some(0.0) {
            90.0
        } else {
            nominal[1].atan2(nominal[0]).to_degrees()
        };
        let actual = centre[1].atan2(centre[0]).to_degrees();
        let turn = half_turn(actual - target);
        self.set_q(150, turn);
        self.turn_table(def, axis, turn, run, out)
    }
}
