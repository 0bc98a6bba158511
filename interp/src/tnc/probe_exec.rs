//! Touch-probe cycles (`TCH PROBE`) on the TNC machine: the probing move, the positioning
//! between touch points, and the writes of results and presets. The cycles themselves are in
//! [`super::probe_cycles`].
//!
//! Rules taken from the TNC 640 touch-probe manual, in klar's words:
//! - touch-probe cycles act when they are defined: no `CYCL CALL`;
//! - the controlled point of the probe is the centre of its stylus ball; a measuring height
//!   (Q261) is where that centre stands, and every measured value is the workpiece surface,
//!   i.e. the trigger position moved on by the ball radius in the probing direction;
//! - a probing move starts the set-up clearance (the probe's own plus the cycle's Q320) and
//!   the ball radius before the nominal touch point, and runs at most the probe's probing
//!   distance; a move that finds nothing ends the program with "touch point inaccessible",
//!   a ball that touches before it moves with "stylus already in contact";
//! - after each touch the probe returns to where its probing move started; between touch
//!   points it travels at the measuring height, or at the clearance height Q260 when Q301=1;
//!   the first touch point is always reached over the clearance height, and at the end the
//!   probe returns to the clearance height;
//! - the stylus ball's radius is the radius of the probe's row in the tool table when the
//!   probe is the active tool and has one there (the TNC keeps R and L of the probe in the
//!   tool table and feeds, overtravel and set-up clearance in the touch-probe table);
//!   klar's `[probe]` data give the rest, and the radius when the tool has none;
//! - the probe's length is its tool length L (with the table's DL and TOOL CALL's DL): like
//!   every tool length it is measured from the tool reference point on the spindle to the
//!   stylus tip, and the control uses it only to place the spindle so that the tip stands
//!   where the program says. klar's axes carry the tool tip (the length is part of the tool,
//!   not of the axis positions), so L moves no axis and changes no touch point: a surface
//!   height comes out the same whatever L the table gives;
//! - cycles 0 and 1 also leave the trigger position in Q115 … Q117: the spindle's position,
//!   the stylus length not taken off. klar gives the ball centre at the trigger (program
//!   coordinates) with the active tool length added along the tool axis, so the tool-axis
//!   value differs by exactly the difference of two probes' lengths;
//! - a preset found by a cycle goes to row Q305 of the preset table when Q303=1 (Q305=0: the
//!   active preset, which then acts at once; a row that is the active one acts at once as
//!   well). The preset is chosen so that the measured point reads Q331/Q332 (Q333 in the
//!   probe axis) afterwards.
//!
//! - a positioning move on which the stylus meets the part stops the program (a collision of
//!   the probe: on the machine the stylus deflects outside a probing move);
//!
//! - with a real probe ([`ProbeStop`]) the probing move runs past the touch point by the
//!   distance the axes need to stop (the trigger delay at the probing feed, then braking);
//!   the measured position is the one latched at the trigger. A stop distance larger than
//!   the stylus may deflect is refused before the move ("probing feed too high"), as is a
//!   touch that comes before the probe can have reached its probing feed;
//!
//! - measured probing ([`super::probe_wait`]): the machine runs each probing move, stops it at
//!   the trigger and answers with the latched position; the cycle waits for it.
//!
//! Not modelled: the tilted working plane (probing is refused in it). Without a
//! [`ProbeStop`] the axes stop on the trigger point, which the interpreter knows before the
//! move. Q303=0 (the datum table): see [`super::probe_ref`].

use std::collections::VecDeque;

use super::cycle_exec::CycleDef;
use super::cycle_words::OldItem;
use super::exec::{ExecError, Flow, Machine, here};
use super::expr::{ParamKind, ParamRef};
use super::probe_wait::Measured;
use super::stmt::Parsed;
use crate::cycles::{ParamKey, ParamSource};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, Op, OpKind, Pose, PresetWrite, ProbeResult, SourceLoc};
use crate::probe::{Probe, ProbeData, ProbeError, ProbeRequest, ProbeStop};

/// A point in the working plane's axes: first axis, second axis, tool axis (mm).
pub(super) type P3 = [f64; 3];

/// The probe as the machine knows it.
#[derive(Debug, Default)]
pub(crate) struct ProbeState {
    /// Answers the probing moves; `None`: the machine has no probe.
    pub probe: Option<Box<dyn Probe>>,
    /// Ball radius, clearance, distance and feeds.
    pub data: ProbeData,
    /// The head block of an old-format cycle 0 or 1: cycle, result parameter, axis,
    /// direction sign.
    pub(super) old: Option<OldHead>,
    /// Height of the surface found by the probe-axis touch of a centre cycle (Q381=1).
    pub axis_hit: Option<f64>,
    /// The Q parameters the cycle under way has written (number, value).
    written: Vec<(u32, f64)>,
    /// The preset the cycle under way has written.
    preset: Option<PresetWrite>,
    /// Measured probing ([`super::probe_wait`]): the touch points come from the machine;
    /// `None`: from `probe`.
    pub measured: Option<Measured>,
}

/// What an old-format head block (`0.0`, `1.0`, `1.1`) said.
#[derive(Debug, Clone, Copy)]
pub(super) struct OldHead {
    cycle: u32,
    result: Option<ParamRef>,
    /// Probing direction in X, Y, Z (program coordinates), once known.
    dir: Option<P3>,
}

pub(super) fn perr(e: ProbeError) -> ExecError {
    here(ProgramError::Probe(e))
}

/// Where one touch-probe cycle is: its number and the touch point it works on.
#[derive(Debug, Clone, Copy)]
pub(super) struct Run {
    pub cycle: u32,
    pub point: u32,
    pub loc: SourceLoc,
}

impl Machine {
    /// Gives the machine a probe and its data.
    pub fn set_probe(&mut self, data: ProbeData, probe: Box<dyn Probe>) {
        self.probe.data = data;
        self.probe.probe = Some(probe);
    }

    /// `TCH PROBE n …`.
    pub(super) fn touch_probe(
        &mut self,
        number: u32,
        sub: Option<u8>,
        parsed: &Parsed,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Result<Flow, ExecError> {
        if self.probe.probe.is_none() && self.probe.measured.is_none() {
            return Err(perr(ProbeError::NoProbe(number)));
        }
        if !self.tilt.identity {
            return Err(perr(ProbeError::Bad {
                cycle: number,
                what: "probing in a tilted working plane is not supported yet".into(),
            }));
        }
        let run = Run {
            cycle: number,
            point: 1,
            loc,
        };
        self.probe.written.clear();
        self.probe.preset = None;
        self.probe_block_start();
        let base = out.len();
        let r = match sub {
            Some(s) => self.old_probe(number, s, &parsed.cycle.items, run, out),
            None => self
                .read_q_def(number, parsed)
                .and_then(|def| self.probe_cycle(&def, run, out)),
        };
        if let Some(flow) = self.probe_flow(r, out, base)? {
            return Ok(flow);
        }
        // What the cycle measured, for displays: after its moves, where the results hold.
        if !self.probe.written.is_empty() || self.probe.preset.is_some() {
            let result = ProbeResult {
                cycle: number,
                params: std::mem::take(&mut self.probe.written),
                preset: self.probe.preset.take(),
            };
            out.push_back(Op {
                kind: OpKind::ProbeResult { result },
                loc,
            });
        }
        Ok(Flow::Continue)
    }

    /// The working-plane coordinates of the position.
    pub(super) fn plane_pos(&self) -> P3 {
        let (a, b, n) = self.plane.axes();
        [self.pos[a], self.pos[b], self.pos[n]]
    }

    /// The position with its working-plane coordinates replaced by `p`.
    pub(super) fn pose_at(&self, p: P3) -> Pose {
        let (a, b, n) = self.plane.axes();
        let mut q = self.pos;
        (q[a], q[b], q[n]) = (p[0], p[1], p[2]);
        q
    }

    /// A straight move to `to` (working-plane coordinates).
    pub(super) fn probe_line(&mut self, to: P3, feed: Feed, run: Run, out: &mut VecDeque<Op>) {
        let from = self.pos;
        let to = self.pose_at(to);
        if from != to {
            out.push_back(Op {
                kind: OpKind::Line { from, to, feed },
                loc: run.loc,
            });
        }
        self.pos = to;
    }

    /// The radius of the stylus ball: the radius of the active tool's row in the tool table
    /// (R plus the table's DR; TOOL CALL's DR is a machining allowance and does not count)
    /// when the probe is called as a tool with a radius, else the probe's own (`[probe]`).
    pub(super) fn ball(&self) -> f64 {
        let table = self.tool_base.1;
        if self.tool_unknown.is_none() && table > 0.0 {
            table
        } else {
            self.probe.data.radius
        }
    }

    /// The machine position of the rotary table axis C, degrees (0 on a machine without one).
    pub(super) fn table_angle(&self) -> f64 {
        self.cyc.xf.map_point(&self.pos)[AxisLetter::C]
    }

    /// The feed of positioning moves.
    pub(super) fn positioning(&self) -> Feed {
        self.probe
            .data
            .positioning_feed
            .map_or(Feed::Rapid, |f| Feed::Rate(f / 60.0))
    }

    /// Goes to `start` (in-plane) at height `h`: over the clearance height `clear` when
    /// `high`, else at the height the probe stands at.
    pub(super) fn go_to_point(
        &mut self,
        start: [f64; 2],
        h: f64,
        clear: f64,
        high: bool,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let p = self.plane_pos();
        if high {
            let top = p[2].max(clear);
            self.position_to([p[0], p[1], top], run, out)?;
            self.position_to([start[0], start[1], top], run, out)?;
        } else {
            self.position_to([start[0], start[1], p[2]], run, out)?;
        }
        self.position_to([start[0], start[1], h], run, out)
    }

    /// A positioning move to `to` at the positioning feed. The stylus must not meet the part
    /// on the way (it may come to rest touching it: the probing move then reports that).
    pub(super) fn position_to(
        &mut self,
        to: P3,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let xyz = |p: &Pose| [p[AxisLetter::X], p[AxisLetter::Y], p[AxisLetter::Z]];
        let from = xyz(&self.cyc.xf.map_point(&self.pos));
        let end = xyz(&self.cyc.xf.map_point(&self.pose_at(to)));
        let radius = self.ball();
        let blank = self.blank;
        let table = self.table_angle();
        if from != end
            && self.probe.measured.is_none()
            && let Some(p) = self.probe.probe.as_mut()
            && let Some(hit) = {
                p.table_at(table);
                p.touch(from, end, radius, blank.as_ref())
            }
        {
            let short = (0..3)
                .map(|i| (end[i] - hit[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            if short > 1e-9 {
                return Err(perr(ProbeError::Collision {
                    cycle: run.cycle,
                    point: run.point,
                }));
            }
        }
        let f = self.positioning();
        self.probe_line(to, f, run, out);
        Ok(())
    }

    /// Raises the probe to the clearance height `clear` (when below it).
    pub(super) fn up_to(
        &mut self,
        clear: f64,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let p = self.plane_pos();
        if p[2] < clear {
            self.position_to([p[0], p[1], clear], run, out)?;
        }
        Ok(())
    }

    /// Probes from where the probe stands along the unit direction `dir` (working-plane
    /// coordinates) and returns to the start. Returns the trigger position of the ball centre.
    pub(super) fn probe_from_here(
        &mut self,
        dir: P3,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<P3, ExecError> {
        let start = self.plane_pos();
        let d = self.probe.data.distance;
        let end = [
            start[0] + dir[0] * d,
            start[1] + dir[1] * d,
            start[2] + dir[2] * d,
        ];
        let xyz = |p: &Pose| [p[AxisLetter::X], p[AxisLetter::Y], p[AxisLetter::Z]];
        let m_start = self.cyc.xf.map_point(&self.pose_at(start));
        let m_end = self.cyc.xf.map_point(&self.pose_at(end));
        let radius = self.ball();
        let blank = self.blank;
        let table = self.table_angle();
        let feed = Feed::Rate(self.probe.data.feed / 60.0);
        if self.probe.measured.is_some() {
            return self.measured_touch(start, (xyz(&m_start), xyz(&m_end)), run, out);
        }
        let hit = match self.probe.probe.as_mut() {
            Some(p) => {
                p.table_at(table);
                p.touch(xyz(&m_start), xyz(&m_end), radius, blank.as_ref())
            }
            None => return Err(perr(ProbeError::NoProbe(run.cycle))),
        };
        let Some(h) = hit else {
            // the probe runs its whole distance, then the program stops
            self.probe_line(end, feed, run, out);
            return Err(perr(ProbeError::NotReached {
                cycle: run.cycle,
                point: run.point,
                distance: d,
            }));
        };
        let moved = (0..3)
            .map(|i| (h[i] - xyz(&m_start)[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        if moved < 1e-9 {
            return Err(perr(ProbeError::AlreadyInContact {
                cycle: run.cycle,
                point: run.point,
            }));
        }
        let trigger = self.to_plane(&m_start, h);
        let stop = match self.probe.data.stop {
            Some(s) => {
                let o = self.overrun(&s, xyz(&m_start), xyz(&m_end), h, moved, run)?;
                self.to_plane(&m_start, o)
            }
            None => trigger,
        };
        self.probe_line(stop, feed, run, out);
        let back = self.positioning();
        self.probe_line(start, back, run, out);
        Ok(trigger)
    }

    /// The working-plane coordinates of the machine X, Y, Z point `p` (the other axes as in
    /// the machine pose `at`).
    fn to_plane(&self, at: &Pose, p: P3) -> P3 {
        let (a, b, n) = self.plane.axes();
        let mut q = *at;
        (q[AxisLetter::X], q[AxisLetter::Y], q[AxisLetter::Z]) = (p[0], p[1], p[2]);
        let q = self.cyc.xf.unmap_point(&q);
        [q[a], q[b], q[n]]
    }

    /// A probing move measured by the machine ([`super::probe_wait`]) from `start` (working
    /// plane coordinates; `m` the move's start and end in machine X, Y, Z): the machine's
    /// answer, or a wait for it. The machine runs the probing move itself (it is no op), so
    /// that it can stop it at the trigger. A stop distance the stylus cannot take is refused
    /// before the move. Returns the trigger position.
    fn measured_touch(
        &mut self,
        start: P3,
        m: (P3, P3),
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<P3, ExecError> {
        let (m_start, m_end) = m;
        let radius = self.ball();
        let stop = self.probe.data.stop;
        if let Some(s) = &stop {
            self.overrun(s, m_start, m_end, m_start, f64::INFINITY, run)?;
        }
        let feed = self.probe.data.feed;
        let answer = self.probe.measured.as_mut().and_then(Measured::next_answer);
        let Some(answer) = answer else {
            if let Some(w) = self.probe.measured.as_mut() {
                w.ask(ProbeRequest {
                    from: m_start,
                    to: m_end,
                    feed,
                    radius,
                });
            }
            return Err(perr(ProbeError::Pending(run.cycle)));
        };
        let at = self.cyc.xf.map_point(&self.pose_at(start));
        // the axes stand where they came to rest
        self.pos = self.pose_at(self.to_plane(&at, answer.stop));
        let Some(h) = answer.trigger else {
            return Err(perr(ProbeError::NotReached {
                cycle: run.cycle,
                point: run.point,
                distance: self.probe.data.distance,
            }));
        };
        let moved = (0..3)
            .map(|i| (h[i] - m_start[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        if moved < 1e-9 {
            return Err(perr(ProbeError::AlreadyInContact {
                cycle: run.cycle,
                point: run.point,
            }));
        }
        if let Some(s) = &stop {
            self.overrun(s, m_start, m_end, h, moved, run)?;
        }
        let back = self.positioning();
        self.probe_line(start, back, run, out);
        Ok(self.to_plane(&at, h))
    }

    /// Where the axes of a real probe come to rest (machine X, Y, Z) after touching at `hit`
    /// on the probing move from `from` toward `to`, `moved` mm after its start: past the
    /// touch point by the stop distance of [`ProbeStop`]. Refused when that exceeds the
    /// stylus's overtravel, or when the probe touches before it can have reached its probing
    /// feed (the stop distance assumes it probes at that feed).
    fn overrun(
        &self,
        stop: &ProbeStop,
        from: P3,
        to: P3,
        hit: P3,
        moved: f64,
        run: Run,
    ) -> Result<P3, ExecError> {
        let d = [to[0] - from[0], to[1] - from[1], to[2] - from[2]];
        let len = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        if len <= 0.0 {
            return Ok(hit);
        }
        let dir = d.map(|v| v / len);
        let feed = self.probe.data.feed;
        let (v, s) = stop.stop_distance(dir, feed / 60.0);
        if let Some(allowed) = stop.overtravel
            && s > allowed
        {
            return Err(perr(ProbeError::Overtravel {
                cycle: run.cycle,
                point: run.point,
                stop: s,
                allowed,
                feed,
            }));
        }
        let [_, acc, jerk] = stop.path_limits(dir, feed / 60.0);
        let run_up = ProbeStop::braking_distance(v, acc, jerk);
        if moved < run_up {
            return Err(perr(ProbeError::ShortRunUp {
                cycle: run.cycle,
                point: run.point,
                moved,
                run_up,
            }));
        }
        Ok([0, 1, 2].map(|i| hit[i] + dir[i] * s))
    }

    /// Probes along `dir` from where the probe stands; the surface point touched.
    pub(super) fn touch_surface(
        &mut self,
        dir: P3,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<P3, ExecError> {
        let t = self.probe_from_here(dir, run, out)?;
        let r = self.ball();
        Ok([t[0] + dir[0] * r, t[1] + dir[1] * r, t[2] + dir[2] * r])
    }

    /// Sets Q parameter `n`.
    pub(super) fn set_q(&mut self, n: u32, v: f64) {
        self.probe.written.push((n, v));
        self.params.set(
            ParamRef {
                kind: ParamKind::Q,
                index: n,
            },
            v,
        );
    }

    /// Writes a measured datum: the program point `measured` (working-plane coordinates;
    /// `None` for axes not measured) shall read `new` afterwards (preset or datum table: see
    /// [`Machine::put_datum`]).
    pub(super) fn set_datum(
        &mut self,
        def: &CycleDef,
        measured: [Option<f64>; 3],
        new: P3,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Result<(), ExecError> {
        self.put_datum(def, measured, new, None, out, loc)
    }

    /// Writes `xf`'s preset (`values`, basic rotation `rot`) into row Q305 and makes it act
    /// when that row is the active preset.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn write_preset(
        &mut self,
        cycle: u32,
        def: &CycleDef,
        xf: super::transform::Transform,
        values: &[Option<f64>; 9],
        rot: Option<f64>,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Result<(), ExecError> {
        let q305 = def.get(ParamKey::Q(305)).unwrap_or(0.0);
        if q305.fract() != 0.0 || !(0.0..=99_999.0).contains(&q305) {
            return Err(perr(ProbeError::Bad {
                cycle,
                what: format!("Q305={q305} is not a preset table row"),
            }));
        }
        let row = if q305 == 0.0 {
            self.cyc.active_preset
        } else {
            Some(q305 as i64)
        };
        let active = q305 == 0.0 || row == self.cyc.active_preset;
        self.probe.preset = Some(PresetWrite {
            row,
            active,
            values: AxisLetter::ALL
                .iter()
                .filter_map(|&a| Some((a, values.get(a.index()).copied().flatten()?)))
                .collect(),
            rotation: rot,
        });
        match (&mut self.cyc.presets, row) {
            (Some(t), Some(nr)) => t.write(nr, values, rot),
            (None, Some(nr)) => {
                return Err(here(ProgramError::NoTable {
                    table: "preset",
                    row: nr as f64,
                    key: "preset_table",
                }));
            }
            // no table: the active preset exists only in the run
            (_, None) => {}
        }
        if active {
            self.set_transform(xf, out, loc);
        }
        Ok(())
    }

    /// Cycles 0 and 1 in the old block format.
    fn old_probe(
        &mut self,
        number: u32,
        sub: u8,
        items: &[OldItem],
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let bad = |what: &str| {
            perr(ProbeError::Bad {
                cycle: number,
                what: what.into(),
            })
        };
        let axis_of = |it: &OldItem| match it.word() {
            [c] => AxisLetter::from_char(char::from(*c)).filter(|a| a.index() < 3),
            _ => None,
        };
        let unit = |a: AxisLetter| {
            let mut d = [0.0; 3];
            d[a.index()] = 1.0;
            d
        };
        match (number, sub) {
            (0, 0) => {
                let result = items.iter().find_map(|it| match (it.len, it.value) {
                    (0, Some(crate::tnc::expr::Value::Param { param, .. })) => Some(param),
                    _ => None,
                });
                let dir = items.iter().find_map(|it| {
                    let a = axis_of(it)?;
                    let neg = it.sign_only?;
                    let mut d = unit(a);
                    if neg {
                        d = d.map(|v| -v);
                    }
                    Some(d)
                });
                if result.is_none() || dir.is_none() {
                    return Err(bad(
                        "0.0 needs the result parameter and the probing direction (Q10 Z-)",
                    ));
                }
                self.probe.old = Some(OldHead {
                    cycle: 0,
                    result,
                    dir,
                });
                Ok(())
            }
            (1, 0) => {
                self.probe.old = Some(OldHead {
                    cycle: 1,
                    result: None,
                    dir: None,
                });
                Ok(())
            }
            (1, 1) => {
                let head = self
                    .probe
                    .old
                    .filter(|h| h.cycle == 1)
                    .ok_or_else(|| bad("1.1 without 1.0"))?;
                let axis = items
                    .iter()
                    .find_map(axis_of)
                    .ok_or_else(|| bad("1.1 needs the reference axis (X, Y or Z)"))?;
                let angle = items
                    .iter()
                    .find(|it| it.len > 1)
                    .and_then(|it| self.item_value(it))
                    .ok_or_else(|| bad("1.1 needs the probing angle (ANGLE:)"))?;
                // the angle turns the reference axis toward the next axis (X→Y, Y→Z, Z→X)
                let (s, c) = angle.to_radians().sin_cos();
                let i = axis.index();
                let mut d = [0.0; 3];
                d[i] = c;
                d[(i + 1) % 3] = s;
                self.probe.old = Some(OldHead {
                    dir: Some(d),
                    ..head
                });
                Ok(())
            }
            (0, 1) | (1, 2) => {
                let head = self
                    .probe
                    .old
                    .filter(|h| h.cycle == number && h.dir.is_some())
                    .ok_or_else(|| bad("the pre-position block needs its head block before it"))?;
                let Some(dir_xyz) = head.dir else {
                    return Err(bad("no probing direction"));
                };
                let mut target = self.pos;
                for it in items {
                    if let Some(a) = axis_of(it) {
                        let v = self
                            .item_value(it)
                            .ok_or_else(|| bad("an axis word of the pre-position needs a value"))?;
                        target[a] = v * self.unit;
                    }
                }
                // the probe moves to the pre-position in a straight line at rapid traverse
                let (a, b, n) = self.plane.axes();
                self.position_to([target[a], target[b], target[n]], run, out)?;
                self.pos = target;
                let dir = [dir_xyz[a.index()], dir_xyz[b.index()], dir_xyz[n.index()]];
                let t = self.probe_from_here(dir, run, out)?;
                let tp = self.pose_at(t);
                // Q115 … Q117: the spindle's position, the stylus length not compensated
                let mut spindle = tp;
                spindle[self.tool_axis] += self.tool_length;
                for (q, ax) in [
                    (115, AxisLetter::X),
                    (116, AxisLetter::Y),
                    (117, AxisLetter::Z),
                ] {
                    self.set_q(q, spindle[ax] / self.unit);
                }
                if let Some(res) = head.result {
                    let k = dir_xyz.iter().position(|v| v.abs() == 1.0).unwrap_or(2);
                    let ax = AxisLetter::ALL.get(k).copied().unwrap_or(AxisLetter::Z);
                    let surface = tp[ax] + dir_xyz[k] * self.ball();
                    self.params.set(res, surface / self.unit);
                }
                Ok(())
            }
            _ => Err(perr(ProbeError::Unknown(number))),
        }
    }
}
