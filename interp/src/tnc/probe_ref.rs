//! Preset cycles on slots, ridges, corners and hole patterns: 408 (slot centre), 409 (ridge
//! centre), 414 (outside corner), 415 (inside corner), 416 (bolt-hole-circle centre), 418
//! (centre of four holes) and 402 (basic rotation from two studs), and where every preset
//! cycle writes its datum (preset table, or datum table with Q303=0).
//!
//! Each cycle's rules, as klar applies them from the TNC 640 touch-probe manual (where the
//! manual leaves a detail open, klar's reading is said so):
//! - **408/409**: Q321/Q322 the nominal centre, Q311 the nominal width, Q272 the measuring
//!   axis (1 reference, 2 minor). The two touch points lie on the line through the centre
//!   along the measuring axis: 408 probes the slot's walls from inside outward (starting from
//!   the centre when the slot is narrower than the clearance allows), 409 the ridge's sides
//!   from outside inward, moving over the clearance height between them (409 has no Q301).
//!   Results: Q166 the width measured, Q157 the centre line. The centre becomes the datum Q405
//!   of the measuring axis only (the other axis keeps its datum); Q381=1 also sets the tool
//!   axis (Q382 … Q384, Q333) as for 410.
//! - **414**: touch points 1 (Q263/Q264) and 2 (Q326 further along the reference axis) lie
//!   on the edge along the reference axis, 3 (Q296/Q297) and 4 (Q327 further along the minor
//!   axis) on the edge along the minor axis. The probing directions follow from where point 3
//!   lies against point 1: points 1 and 2 are probed along the minor axis toward point 3's
//!   side, points 3 and 4 along the reference axis toward point 1's side. With Q301=0 the
//!   probe goes round the outside of the corner between points 2 and 3.
//! - **415**: Q263/Q264 the nominal corner, Q308 which corner of the pocket it is (klar's
//!   reading: 1 at −/− of the pocket, 2 at +/−, 3 at +/+, 4 at −/+ in reference/minor axis, so
//!   the pocket lies toward + of corner 1). On each wall the first touch point lies the
//!   clearance (set-up clearance plus ball radius) from the corner and the second Q326
//!   (reference-axis wall) or Q327 (minor-axis wall) further on.
//! - 414/415: the corner is where the two edges meet; Q151/Q152 the corner measured, which
//!   becomes the datum Q331/Q332. Q304=1 also turns the basic rotation by the angle of the edge
//!   along the reference axis. klar fits each edge through the ball centres at the two
//!   triggers and moves it on by the ball radius, so a turned edge is found exactly.
//! - **416**: three holes on a circle about Q273/Q274 of diameter Q262 at the polar angles
//!   Q291, Q292, Q293, each probed from its nominal centre outward at four points; the circle
//!   through the three hole centres gives Q151/Q152 its centre (the datum Q331/Q332) and Q153
//!   its diameter. **430** measures the same way (see [`super::probe_measure`]).
//! - **418**: four holes Q268/Q269, Q270/Q271, Q316/Q317, Q318/Q319, each probed as for 416;
//!   the crossing of the lines from hole 1 to hole 3 and from hole 2 to hole 4 is Q151/Q152
//!   and becomes the datum Q331/Q332.
//! - **402**: two studs (Q268/Q269 diameter Q313 at height Q261, Q270/Q271 diameter Q314 at
//!   height Q315), each probed from outside at four points (0°, 90°, 180°, 270°), travelling on
//!   an arc about the stud at measuring height when Q301=0. The angle of the line from stud 1
//!   to stud 2 is Q150; the basic rotation grows by Q150 − Q307 as for 401 (Q402=1, turning
//!   a rotary table instead, is refused).
//! - Where the datum goes: Q303=1 (or no Q303) writes preset row Q305 (0: the active preset,
//!   which acts at once). Q303=0 with Q305 ≥ 1 writes row Q305 of the datum table instead:
//!   the measured point's coordinates in the active preset's system less the new datum, so
//!   that a datum shift (cycle 7) to that row makes the point read Q331/Q332 (Q405, Q333);
//!   the preset stays as it is. A machine without a datum table refuses it; a basic rotation
//!   (Q304=1) cannot go to a datum table and is refused as well.

use std::collections::VecDeque;

use super::cycle_exec::CycleDef;
use super::exec::{ExecError, Machine, here};
use super::probe_cycles::{fit_circle, line_angle};
use super::probe_exec::{P3, Run, perr};
use crate::cycles::{ParamKey, ParamSource};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Op, OpKind, SourceLoc};
use crate::probe::ProbeError;

/// A bad-parameter error of `cycle`.
pub(super) fn bad(cycle: u32, what: impl Into<String>) -> ExecError {
    perr(ProbeError::Bad {
        cycle,
        what: what.into(),
    })
}

/// The crossing of the lines `n1·x = e1` and `n2·x = e2`.
fn cross(n1: [f64; 2], e1: f64, n2: [f64; 2], e2: f64) -> Option<[f64; 2]> {
    let det = n1[0] * n2[1] - n1[1] * n2[0];
    (det.abs() > 1e-9).then(|| {
        [
            (e1 * n2[1] - e2 * n1[1]) / det,
            (n1[0] * e2 - n2[0] * e1) / det,
        ]
    })
}

/// The edge touched at ball centres `a` and `b` probing along `dir`: its unit normal (along
/// `dir`) and offset `e` (points `x` of the edge have `n·x = e`).
fn edge(a: [f64; 2], b: [f64; 2], dir: [f64; 2], ball: f64) -> Option<([f64; 2], f64)> {
    let d = [b[0] - a[0], b[1] - a[1]];
    let len = d[0].hypot(d[1]);
    if len < 1e-9 {
        return None;
    }
    let mut n = [-d[1] / len, d[0] / len];
    if n[0] * dir[0] + n[1] * dir[1] < 0.0 {
        n = [-n[0], -n[1]];
    }
    Some((n, n[0] * a[0] + n[1] * a[1] + ball))
}

impl Machine {
    /// The axis index of Q272 (1 reference → 0, 2 minor → 1).
    pub(super) fn plane_axis(&self, def: &CycleDef) -> Result<usize, ExecError> {
        match self.opt(def, 272, 1.0) {
            1.0 => Ok(0),
            2.0 => Ok(1),
            v => Err(bad(
                def.number,
                format!("Q272={v}: the measuring axis is 1 or 2"),
            )),
        }
    }

    /// Writes the datum of a preset cycle that found the working-plane point `point`: it
    /// shall read Q331/Q332 afterwards, and the tool-axis touch (Q381=1), when there was one,
    /// Q333; with the basic rotation `rot` when given.
    pub(super) fn point_datum(
        &mut self,
        def: &CycleDef,
        point: [f64; 2],
        rot: Option<f64>,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Result<(), ExecError> {
        let w = self.probe.axis_hit.take();
        let new = [
            self.opt(def, 331, 0.0),
            self.opt(def, 332, 0.0),
            self.opt(def, 333, 0.0),
        ];
        self.put_datum(def, [Some(point[0]), Some(point[1]), w], new, rot, out, loc)
    }

    /// Writes the datum found by a preset cycle: the program point `measured` (working-plane
    /// axes; `None` for axes not measured) shall read `new` afterwards, with the basic rotation
    /// `rot` when given (see the module doc for Q303/Q305).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn put_datum(
        &mut self,
        def: &CycleDef,
        measured: [Option<f64>; 3],
        new: P3,
        rot: Option<f64>,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Result<(), ExecError> {
        let cycle = def.number;
        let transfer = def.get(ParamKey::Q(303)).unwrap_or(1.0);
        if !(transfer == 0.0 || transfer == 1.0 || transfer == -1.0) {
            return Err(bad(
                cycle,
                format!("Q303={transfer}: 0 (datum table) or 1 (preset table)"),
            ));
        }
        let (a, b, n) = self.plane.axes();
        let axes = [a, b, n];
        let here_p = self.pose_at(measured.map(|m| m.unwrap_or(0.0)));
        let m_here = self.cyc.xf.map_point(&here_p);
        let row = def.get(ParamKey::Q(305)).unwrap_or(0.0);
        if transfer == 0.0 && row != 0.0 {
            if rot.is_some() {
                return Err(bad(
                    cycle,
                    "Q304=1 with Q303=0: a datum table has no basic rotation (write the preset table, Q303=1)",
                ));
            }
            if row.fract() != 0.0 || !(1.0..=99_999.0).contains(&row) {
                return Err(bad(cycle, format!("Q305={row} is not a datum table row")));
            }
            let xf = self.cyc.xf;
            // the point in the active preset's system: machine point less the preset, turned
            // back by the basic rotation
            let (s, c) = (-xf.basic_rot).to_radians().sin_cos();
            let d = [
                m_here[AxisLetter::X] - xf.preset[0],
                m_here[AxisLetter::Y] - xf.preset[1],
                m_here[AxisLetter::Z] - xf.preset[2],
            ];
            let pc = [d[0] * c - d[1] * s, d[0] * s + d[1] * c, d[2]];
            let mut values = [None; 9];
            for (k, ax) in axes.iter().enumerate() {
                let i = ax.index();
                if measured[k].is_some() && i < 3 {
                    values[i] = Some(pc[i] - new[k]);
                }
            }
            return match self.cyc.datums.as_mut() {
                Some(t) => {
                    t.write(row as i64, &values, None);
                    Ok(())
                }
                None => Err(here(ProgramError::NoTable {
                    table: "datum",
                    row,
                    key: "datum_table",
                })),
            };
        }
        let mut xf = self.cyc.xf;
        if let Some(r) = rot {
            xf.basic_rot = r;
        }
        let m_there = xf.map_point(&self.pose_at(new));
        let mut written = [None; 9];
        for (k, ax) in axes.iter().enumerate() {
            if measured[k].is_some() {
                let i = ax.index();
                xf.preset[i] += m_here[*ax] - m_there[*ax];
                written[i] = Some(xf.preset[i]);
            }
        }
        self.write_preset(cycle, def, xf, &written, rot, out, loc)
    }

    /// 408 (slot, `slot`) and 409 (ridge).
    pub(super) fn cycle408_409(
        &mut self,
        def: &CycleDef,
        slot: bool,
        mut run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let c = [self.need(def, 321)?, self.need(def, 322)?];
        let half = self.need(def, 311)? / 2.0;
        let k = self.plane_axis(def)?;
        let h = self.need(def, 261)?;
        let clear = self.need(def, 260)?;
        let high = !slot || self.opt(def, 301, 1.0) == 1.0;
        let lead = self.lead(def);
        let mut hits = [0.0; 2];
        for (j, sign) in [-1.0, 1.0].iter().enumerate() {
            run.point = j as u32 + 1;
            let mut start = c;
            let mut dir = [0.0; 3];
            if slot {
                start[k] += sign * (half - lead).max(0.0);
                dir[k] = *sign;
            } else {
                start[k] += sign * (half + lead);
                dir[k] = -sign;
            }
            self.go_to_point(start, h, clear, j == 0 || high, run, out)?;
            hits[j] = self.touch_surface(dir, run, out)?[k];
        }
        self.tool_axis_datum(def, run, out)?;
        self.up_to(clear, run, out)?;
        let centre = (hits[0] + hits[1]) / 2.0;
        self.set_q(166, (hits[1] - hits[0]).abs() / self.unit);
        self.set_q(157, centre / self.unit);
        let mut measured = [None; 3];
        measured[k] = Some(centre);
        measured[2] = self.probe.axis_hit.take();
        let mut new = [0.0; 3];
        new[k] = self.opt(def, 405, 0.0);
        new[2] = self.opt(def, 333, 0.0);
        self.put_datum(def, measured, new, None, out, run.loc)
    }

    /// Probes four edge points (`pts` nominal, `dirs` unit probing directions) and returns the
    /// corner where the edge through points 1–2 meets the edge through points 3–4, and the
    /// angle of the first edge against the reference axis. `around`: go round the outside of
    /// the corner between points 2 and 3 at measuring height.
    #[allow(clippy::too_many_arguments)]
    fn corner(
        &mut self,
        def: &CycleDef,
        pts: [[f64; 2]; 4],
        dirs: [[f64; 2]; 4],
        around: bool,
        mut run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<([f64; 2], f64), ExecError> {
        let h = self.need(def, 261)?;
        let clear = self.need(def, 260)?;
        let high = self.opt(def, 301, 1.0) == 1.0;
        let lead = self.lead(def);
        let mut ball = [[0.0; 2]; 4];
        for k in 0..4 {
            run.point = k as u32 + 1;
            let d = dirs[k];
            let start = [pts[k][0] - d[0] * lead, pts[k][1] - d[1] * lead];
            if k == 2 && around && !high {
                // along the first edge's outside to the second edge's line, then to point 3
                let p = self.plane_pos();
                let via = if d[0] != 0.0 {
                    [start[0], p[1], p[2]]
                } else {
                    [p[0], start[1], p[2]]
                };
                self.position_to(via, run, out)?;
            }
            self.go_to_point(start, h, clear, k == 0 || high, run, out)?;
            let t = self.probe_from_here([d[0], d[1], 0.0], run, out)?;
            ball[k] = [t[0], t[1]];
        }
        let r = self.ball();
        let flat = || bad(def.number, "the touch points of an edge coincide");
        let (n1, e1) = edge(ball[0], ball[1], dirs[0], r).ok_or_else(flat)?;
        let (n2, e2) = edge(ball[2], ball[3], dirs[2], r).ok_or_else(flat)?;
        let corner = cross(n1, e1, n2, e2)
            .ok_or_else(|| bad(def.number, "the two edges are parallel: no corner"))?;
        let angle = (ball[1][1] - ball[0][1])
            .atan2(ball[1][0] - ball[0][0])
            .to_degrees();
        Ok((corner, line_angle(angle)))
    }

    /// Finishes 414/415: results, tool-axis touch, datum and (Q304=1) basic rotation.
    fn corner_datum(
        &mut self,
        def: &CycleDef,
        corner: [f64; 2],
        angle: f64,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        self.tool_axis_datum(def, Run { point: 5, ..run }, out)?;
        let clear = self.need(def, 260)?;
        self.up_to(clear, run, out)?;
        self.set_q(151, corner[0] / self.unit);
        self.set_q(152, corner[1] / self.unit);
        let rot = match self.opt(def, 304, 0.0) {
            0.0 => None,
            1.0 => Some(self.cyc.xf.basic_rot + angle),
            v => return Err(bad(def.number, format!("Q304={v}: 0 or 1"))),
        };
        self.point_datum(def, corner, rot, out, run.loc)
    }

    /// 414: preset in an outside corner.
    pub(super) fn cycle414(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let cycle = def.number;
        let p1 = [self.need(def, 263)?, self.need(def, 264)?];
        let s1 = self.need(def, 326)?;
        let p3 = [self.need(def, 296)?, self.need(def, 297)?];
        let s3 = self.need(def, 327)?;
        if s1 == 0.0 || s3 == 0.0 {
            return Err(bad(cycle, "the spacings Q326 and Q327 must not be 0"));
        }
        let sy = p3[1] - p1[1];
        let sx = p1[0] - p3[0];
        if sx == 0.0 || sy == 0.0 {
            return Err(bad(
                cycle,
                "point 3 (Q296/Q297) must lie off point 1 in both axes: it gives the probing directions",
            ));
        }
        let (sx, sy) = (sx.signum(), sy.signum());
        let pts = [p1, [p1[0] + s1, p1[1]], p3, [p3[0], p3[1] + s3]];
        let dirs = [[0.0, sy], [0.0, sy], [sx, 0.0], [sx, 0.0]];
        let (corner, angle) = self.corner(def, pts, dirs, true, run, out)?;
        self.corner_datum(def, corner, angle, run, out)
    }

    /// 415: preset in an inside corner.
    pub(super) fn cycle415(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let cycle = def.number;
        let c = [self.need(def, 263)?, self.need(def, 264)?];
        let s1 = self.need(def, 326)?;
        let s3 = self.need(def, 327)?;
        if s1 <= 0.0 || s3 <= 0.0 {
            return Err(bad(cycle, "the spacings Q326 and Q327 must be positive"));
        }
        let (sx, sy) = match self.opt(def, 308, 1.0) {
            1.0 => (1.0, 1.0),
            2.0 => (-1.0, 1.0),
            3.0 => (-1.0, -1.0),
            4.0 => (1.0, -1.0),
            v => return Err(bad(cycle, format!("Q308={v}: the corner is 1, 2, 3 or 4"))),
        };
        let lead = self.lead(def);
        let pts = [
            [c[0] + sx * lead, c[1]],
            [c[0] + sx * (lead + s1), c[1]],
            [c[0], c[1] + sy * lead],
            [c[0], c[1] + sy * (lead + s3)],
        ];
        let dirs = [[0.0, -sy], [0.0, -sy], [-sx, 0.0], [-sx, 0.0]];
        let (corner, angle) = self.corner(def, pts, dirs, false, run, out)?;
        self.corner_datum(def, corner, angle, run, out)
    }

    /// The centres of the three holes of 416/430, probed in turn.
    pub(super) fn hole_circle(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<([f64; 2], f64), ExecError> {
        let c = [self.need(def, 273)?, self.need(def, 274)?];
        let r = self.need(def, 262)? / 2.0;
        let h = self.need(def, 261)?;
        let clear = self.need(def, 260)?;
        let mut centres = Vec::with_capacity(3);
        for (j, q) in [291, 292, 293].iter().enumerate() {
            let (s, co) = self.need(def, *q)?.to_radians().sin_cos();
            let nominal = [c[0] + r * co, c[1] + r * s];
            let point = 4 * j as u32 + 1;
            centres.push(self.hole_centre(nominal, h, clear, Run { point, ..run }, out)?);
        }
        let (centre, radius) = fit_circle(&centres).ok_or_else(|| {
            bad(
                def.number,
                "the three hole centres lie on one line: no circle",
            )
        })?;
        Ok((centre, 2.0 * radius))
    }

    /// 416 (preset) and 430 (measure, see [`super::probe_measure`]).
    pub(super) fn cycle416_430(
        &mut self,
        def: &CycleDef,
        datum: bool,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let (centre, dia) = self.hole_circle(def, run, out)?;
        if datum {
            self.tool_axis_datum(def, Run { point: 13, ..run }, out)?;
        }
        let clear = self.need(def, 260)?;
        self.up_to(clear, run, out)?;
        self.set_q(151, centre[0] / self.unit);
        self.set_q(152, centre[1] / self.unit);
        self.set_q(153, dia / self.unit);
        if !datum {
            return self.report430(def, centre, dia, run);
        }
        self.point_datum(def, centre, None, out, run.loc)
    }

    /// 418: preset in the crossing of the diagonals of four holes.
    pub(super) fn cycle418(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let h = self.need(def, 261)?;
        let clear = self.need(def, 260)?;
        let mut c = [[0.0; 2]; 4];
        for (j, (qa, qb)) in [(268, 269), (270, 271), (316, 317), (318, 319)]
            .iter()
            .enumerate()
        {
            let nominal = [self.need(def, *qa)?, self.need(def, *qb)?];
            let point = 4 * j as u32 + 1;
            c[j] = self.hole_centre(nominal, h, clear, Run { point, ..run }, out)?;
        }
        self.tool_axis_datum(def, Run { point: 17, ..run }, out)?;
        self.up_to(clear, run, out)?;
        // lines 1→3 and 2→4 as n·x = e
        let line = |a: [f64; 2], b: [f64; 2]| {
            let n = [a[1] - b[1], b[0] - a[0]];
            (n, n[0] * a[0] + n[1] * a[1])
        };
        let (n1, e1) = line(c[0], c[2]);
        let (n2, e2) = line(c[1], c[3]);
        let x = cross(n1, e1, n2, e2).ok_or_else(|| {
            bad(
                def.number,
                "the lines from hole 1 to 3 and from hole 2 to 4 do not cross",
            )
        })?;
        self.set_q(151, x[0] / self.unit);
        self.set_q(152, x[1] / self.unit);
        self.point_datum(def, x, None, out, run.loc)
    }

    /// The centre of a stud of diameter `d` about nominal `c`, probed from outside at four
    /// points at height `h`.
    #[allow(clippy::too_many_arguments)]
    fn stud_centre(
        &mut self,
        def: &CycleDef,
        c: [f64; 2],
        d: f64,
        h: f64,
        high: bool,
        mut run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<[f64; 2], ExecError> {
        let clear = self.need(def, 260)?;
        let ring = d / 2.0 + self.lead(def);
        let first = run.point;
        let mut pts = Vec::with_capacity(4);
        for k in 0..4u32 {
            run.point = first + k;
            let (s, co) = (90.0 * f64::from(k)).to_radians().sin_cos();
            let start = [c[0] + co * ring, c[1] + s * ring];
            if k > 0 && !high {
                // on an arc about the stud to the next start point
                let from = self.pos;
                let to = self.pose_at([start[0], start[1], self.plane_pos()[2]]);
                out.push_back(Op {
                    kind: OpKind::Arc {
                        from,
                        to,
                        center: c,
                        plane: self.plane,
                        sweep: 90.0,
                        feed: self.positioning(),
                    },
                    loc: run.loc,
                });
                self.pos = to;
            }
            self.go_to_point(start, h, clear, k == 0 || high, run, out)?;
            let t = self.probe_from_here([-co, -s, 0.0], run, out)?;
            pts.push([t[0], t[1]]);
        }
        self.up_to(clear, run, out)?;
        fit_circle(&pts)
            .map(|(c, _)| c)
            .ok_or_else(|| bad(run.cycle, "the touch points do not make a circle"))
    }

    /// 402: the basic rotation from the line through the centres of two studs.
    pub(super) fn cycle402(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        if self.opt(def, 402, 0.0) != 0.0 {
            return Err(bad(
                def.number,
                "Q402=1 (align with the rotary table) is not supported yet",
            ));
        }
        let s1 = [self.need(def, 268)?, self.need(def, 269)?];
        let d1 = self.need(def, 313)?;
        let h1 = self.need(def, 261)?;
        let s2 = [self.need(def, 270)?, self.need(def, 271)?];
        let d2 = self.need(def, 314)?;
        let h2 = self.need(def, 315)?;
        let high = self.opt(def, 301, 1.0) == 1.0;
        let c1 = self.stud_centre(def, s1, d1, h1, high, run, out)?;
        let c2 = self.stud_centre(def, s2, d2, h2, high, Run { point: 5, ..run }, out)?;
        let measured = (c2[1] - c1[1]).atan2(c2[0] - c1[0]).to_degrees();
        self.set_q(150, measured);
        let nominal = self.opt(def, 307, 0.0);
        let mut xf = self.cyc.xf;
        xf.basic_rot += measured - nominal;
        let rot = xf.basic_rot;
        self.write_preset(def.number, def, xf, &[None; 9], Some(rot), out, run.loc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_edge_lies_the_ball_radius_beyond_the_ball_centres() {
        // ball centres on y = -2 probing +y with a ball of 2: the edge is y = 0
        let (n, e) = edge([0.0, -2.0], [10.0, -2.0], [0.0, 1.0], 2.0).expect("edge");
        assert!((n[1] - 1.0).abs() < 1e-12 && e.abs() < 1e-12);
        let x = cross(n, e, [1.0, 0.0], 5.0).expect("crossing");
        assert!((x[0] - 5.0).abs() < 1e-12 && x[1].abs() < 1e-12);
        assert!(cross([1.0, 0.0], 1.0, [2.0, 0.0], 3.0).is_none());
    }
}
