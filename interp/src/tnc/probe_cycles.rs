//! The current-format touch-probe cycles: 400 (basic rotation from two points on a
//! straight edge), 410/411 (preset in the centre of a rectangular pocket / stud), 412/413
//! (preset in the centre of a bore / circular stud), the measuring cycles 420–424 and 427,
//! and 431 (measure a plane).
//!
//! Each cycle's rules, as klar applies them from the TNC 640 touch-probe manual:
//! - **400**: touch points 1 (Q263/Q264) and 2 (Q265/Q266) lie on one edge; Q272=1 means the
//!   edge runs along the reference axis (the probe moves along the minor axis), Q272=2 along
//!   the minor axis; Q267 (+1/−1) is the direction of the probing moves. The angle of the
//!   edge against its axis is Q150; the basic rotation becomes that angle minus the nominal
//!   angle Q307 (added to the basic rotation already active) and goes to preset row Q305
//!   (0: the active preset, which turns at once).
//! - **401**: the basic rotation from the line through the centres of two bores (Q268/Q269
//!   and Q270/Q271, each probed from its nominal centre outward at four points): Q150 the
//!   line's angle against the reference axis, the basic rotation grows by Q150 − Q307 as
//!   for 400. **404** writes Q307 as the basic rotation of row Q305.
//! - **410/411**: the centre Q321/Q322 and side lengths Q323 (reference axis) and Q324 (minor
//!   axis) are nominal values; the four touch points lie on the two lines through the centre
//!   parallel to the axes. 410 probes from inside outward, starting from the centre when the
//!   pocket is too small for the clearance; 411 probes from outside inward. Results: Q151 and
//!   Q152 the centre, Q154 and Q155 the side lengths.
//! - **412/413**: Q321/Q322 nominal centre, Q262 nominal diameter, Q325 angle of the first
//!   touch point, Q247 step between touch points (default: a full circle shared evenly by the
//!   Q423 points, 4 unless given), Q365 how the probe travels between points at measuring
//!   height (0: straight, 1: on an arc about the nominal centre). The circle through the
//!   touch points (least squares for four or more) gives Q151/Q152 the centre and Q153 the
//!   diameter. klar fits the circle to the ball centres at the triggers and then adds (bore)
//!   or takes off (boss) the ball radius: the ball centres lie on a concentric circle even
//!   when the part is off its nominal centre and the ball meets the wall at a slant.
//! - 410 … 413 with Q381=1 also probe the probe axis at Q382/Q383 (nominal height Q384) and
//!   set the datum of that axis to Q333. The measured centre becomes Q331/Q332.
//! - **420** (measure angle), **421/422** (measure bore / boss, nominal centre Q273/Q274),
//!   **423/424** (measure rectangle inside / outside, nominal sides Q282/Q283) probe like
//!   400, 412/413 and 410/411 but write no preset; they add the deviations from nominal:
//!   Q161/Q162 of the centre, Q163 of the diameter, Q164/Q165 of the sides. Their
//!   tolerance limits, workpiece status, measuring log and program stop (Q275 …, Q281,
//!   Q309) are in [`super::probe_measure`] and [`super::probe_report`].
//! - The cycles 402, 408, 409, 414 … 416, 418 are in [`super::probe_ref`], 425, 426 and 430
//!   in [`super::probe_measure`], 403 and 405 (turning a rotary table) in
//!   [`super::probe_rotary`].
//! - **417** (preset in the tool axis): the probe stands over Q263/Q264 at the clearance
//!   above the nominal surface height Q294 and probes downward; the height touched is Q160
//!   and becomes the tool-axis datum Q333.
//! - **419** (preset in one axis) and **427** (measure a coordinate): one touch point at
//!   Q263/Q264 (height Q261) along axis Q272 (1 reference, 2 minor, 3 tool axis) in
//!   direction Q267 (+1/−1), approached from the clearance before it; 419 makes the
//!   coordinate touched the datum Q333 of that axis (the other axes keep theirs), 427 writes
//!   it to Q160.
//! - **431**: three points (Q263/Q264/Q294, Q265/Q266/Q295, Q296/Q297/Q298) probed downward
//!   along the tool axis; Q173 … Q175 the heights measured, Q158/Q159 the projection angles
//!   about the reference and the minor axis, Q170 … Q172 the spatial angles A, B, C of the
//!   plane (C is 0: the plane is given by its normal alone).

use std::collections::VecDeque;

use super::cycle_exec::CycleDef;
use super::exec::{ExecError, Machine};
use super::probe_exec::{P3, Run, perr};
use crate::cycles::{ParamKey, ParamSource};
use crate::op::{Op, OpKind};
use crate::probe::ProbeError;

/// The circle through the points, least squares (algebraic fit): centre and radius, `None`
/// for fewer than three points or points on one line.
pub(crate) fn fit_circle(pts: &[[f64; 2]]) -> Option<([f64; 2], f64)> {
    if pts.len() < 3 {
        return None;
    }
    // centred on the mean for a well-conditioned system
    let n = pts.len() as f64;
    let mu = pts
        .iter()
        .fold([0.0, 0.0], |s, p| [s[0] + p[0] / n, s[1] + p[1] / n]);
    // minimise Σ (x² + y² + D x + E y + F)²: normal equations
    let mut m = [[0.0; 3]; 3];
    let mut r = [0.0; 3];
    for p in pts {
        let (x, y) = (p[0] - mu[0], p[1] - mu[1]);
        let row = [x, y, 1.0];
        let z = -(x * x + y * y);
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += row[i] * row[j];
            }
            r[i] += row[i] * z;
        }
    }
    let det3 = |a: &[[f64; 3]; 3]| {
        a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
    };
    let d = det3(&m);
    if d.abs() < 1e-12 {
        return None;
    }
    let solve = |k: usize| {
        let mut a = m;
        for i in 0..3 {
            a[i][k] = r[i];
        }
        det3(&a) / d
    };
    let (dd, ee, ff) = (solve(0), solve(1), solve(2));
    let c = [-dd / 2.0, -ee / 2.0];
    let rr = c[0] * c[0] + c[1] * c[1] - ff;
    (rr > 0.0).then(|| ([c[0] + mu[0], c[1] + mu[1]], rr.sqrt()))
}

/// `def` with parameters renamed `(from, to)`: a measuring cycle read as its preset twin.
fn renamed(def: &CycleDef, names: &[(u32, u32)]) -> CycleDef {
    let mut d = def.clone();
    for (key, _) in d.params.iter_mut() {
        if let Some((_, to)) = names.iter().find(|(from, _)| *key == ParamKey::Q(*from)) {
            *key = ParamKey::Q(*to);
        }
    }
    d
}

/// Degrees in (−90°, 90°]: the angle of an undirected line.
pub(super) fn line_angle(deg: f64) -> f64 {
    let a = deg.rem_euclid(180.0);
    if a > 90.0 { a - 180.0 } else { a }
}

impl Machine {
    /// A required parameter of `def`.
    pub(super) fn need(&self, def: &CycleDef, q: u32) -> Result<f64, ExecError> {
        def.get(ParamKey::Q(q))
            .map(|v| v * self.unit_of(q))
            .ok_or(perr(ProbeError::Missing {
                cycle: def.number,
                q,
            }))
    }

    /// An optional parameter of `def`.
    pub(super) fn opt(&self, def: &CycleDef, q: u32, default: f64) -> f64 {
        def.get(ParamKey::Q(q))
            .map_or(default, |v| v * self.unit_of(q))
    }

    /// The length factor of parameter `q` (angles, counts and switches are not lengths).
    fn unit_of(&self, q: u32) -> f64 {
        match q {
            247 | 267 | 272 | 281 | 291 | 292 | 293 | 301 | 303 | 304 | 305 | 307 | 308 | 309
            | 312 | 325 | 330 | 337 | 365 | 380 | 381 | 402 | 423 => 1.0,
            _ => self.unit,
        }
    }

    /// Runs a current-format touch-probe cycle.
    pub(super) fn probe_cycle(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        // the measuring cycles probe as their preset twins, under their own parameter numbers
        let centre = [(273, 321), (274, 322)];
        match def.number {
            400 => self.cycle400(def, true, run, out),
            401 => self.cycle401(def, run, out),
            404 => {
                let rot = self.opt(def, 307, 0.0);
                let xf = self.cyc.xf;
                self.write_preset(def.number, def, xf, &[None; 9], Some(rot), out, run.loc)
            }
            420 => {
                self.cycle400(def, false, run, out)?;
                self.measured(def, run)
            }
            410 | 411 => self.cycle41x_rect(def, def.number == 410, true, run, out),
            412 | 413 => self.cycle41x_circle(def, def.number == 412, true, run, out),
            421 | 422 => {
                let d = renamed(def, &centre);
                self.cycle41x_circle(&d, def.number == 421, false, run, out)?;
                self.measured(def, run)
            }
            423 | 424 => {
                let d = renamed(def, &[centre[0], centre[1], (282, 323), (283, 324)]);
                self.cycle41x_rect(&d, def.number == 423, false, run, out)?;
                self.measured(def, run)
            }
            417 => self.cycle417(def, run, out),
            419 => self.cycle419(def, run, out),
            427 => {
                self.cycle427(def, run, out)?;
                self.measured(def, run)
            }
            431 => self.cycle431(def, run, out),
            408 | 409 => self.cycle408_409(def, def.number == 408, run, out),
            414 => self.cycle414(def, run, out),
            415 => self.cycle415(def, run, out),
            416 | 430 => self.cycle416_430(def, def.number == 416, run, out),
            418 => self.cycle418(def, run, out),
            402 => self.cycle402(def, run, out),
            403 => self.cycle403(def, run, out),
            405 => self.cycle405(def, run, out),
            425 => self.cycle425(def, run, out),
            426 => self.cycle426(def, run, out),
            n => Err(perr(ProbeError::Unknown(n))),
        }
    }

    /// The clearance before a touch point: the probe's, the cycle's Q320 and the ball.
    pub(super) fn lead(&self, def: &CycleDef) -> f64 {
        self.probe.data.set_up + self.opt(def, 320, 0.0) + self.ball()
    }

    fn cycle400(
        &mut self,
        def: &CycleDef,
        datum: bool,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let cycle = def.number;
        let measured = self.edge_angle(def, run, out)?;
        self.set_q(150, measured);
        if !datum {
            return Ok(());
        }
        let nominal = self.opt(def, 307, 0.0);
        let mut xf = self.cyc.xf;
        xf.basic_rot += measured - nominal;
        let rot = xf.basic_rot;
        self.write_preset(cycle, def, xf, &[None; 9], Some(rot), out, run.loc)
    }

    /// Probes the two points of an edge as 400 does (Q263 … Q267, Q272, Q261, Q260, Q301)
    /// and returns the edge's angle against its axis, degrees in (−90°, 90°].
    pub(super) fn edge_angle(
        &mut self,
        def: &CycleDef,
        mut run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<f64, ExecError> {
        let cycle = def.number;
        let p1 = [self.need(def, 263)?, self.need(def, 264)?];
        let p2 = [self.need(def, 265)?, self.need(def, 266)?];
        let axis = self.opt(def, 272, 1.0);
        let sign = self.opt(def, 267, 1.0);
        if !(axis == 1.0 || axis == 2.0) || !(sign == 1.0 || sign == -1.0) {
            return Err(perr(ProbeError::Bad {
                cycle,
                what: "Q272 must be 1 or 2 and Q267 +1 or -1".into(),
            }));
        }
        let h = self.need(def, 261)?;
        let clear = self.need(def, 260)?;
        let high = self.opt(def, 301, 1.0) == 1.0;
        let dir = if axis == 1.0 {
            [0.0, sign, 0.0]
        } else {
            [sign, 0.0, 0.0]
        };
        let lead = self.lead(def);
        let mut s = [[0.0; 2]; 2];
        for (k, p) in [p1, p2].iter().enumerate() {
            run.point = k as u32 + 1;
            let start = [p[0] - dir[0] * lead, p[1] - dir[1] * lead];
            self.go_to_point(start, h, clear, k == 0 || high, run, out)?;
            let t = self.touch_surface(dir, run, out)?;
            s[k] = [t[0], t[1]];
        }
        self.up_to(clear, run, out)?;
        let raw = (s[1][1] - s[0][1]).atan2(s[1][0] - s[0][0]).to_degrees();
        Ok(line_angle(if axis == 1.0 { raw } else { raw - 90.0 }))
    }

    /// The centre of a bore probed from `c` outward at four points (0°, 90°, 180°, 270°).
    pub(super) fn hole_centre(
        &mut self,
        c: [f64; 2],
        h: f64,
        clear: f64,
        mut run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<[f64; 2], ExecError> {
        self.go_to_point(c, h, clear, true, run, out)?;
        let mut pts = Vec::with_capacity(4);
        for (k, d) in [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]]
            .iter()
            .enumerate()
        {
            run.point += u32::from(k > 0);
            let t = self.probe_from_here([d[0], d[1], 0.0], run, out)?;
            pts.push([t[0], t[1]]);
        }
        self.up_to(clear, run, out)?;
        fit_circle(&pts)
            .map(|(c, _)| c)
            .ok_or(perr(ProbeError::Bad {
                cycle: run.cycle,
                what: "the touch points do not make a circle".into(),
            }))
    }

    /// 401: the basic rotation from the centres of two bores.
    fn cycle401(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        if self.opt(def, 402, 0.0) != 0.0 {
            return Err(perr(ProbeError::Bad {
                cycle: def.number,
                what: "Q402=1 (align with the rotary table) is not supported yet".into(),
            }));
        }
        let h1 = [self.need(def, 268)?, self.need(def, 269)?];
        let h2 = [self.need(def, 270)?, self.need(def, 271)?];
        let h = self.need(def, 261)?;
        let clear = self.need(def, 260)?;
        let c1 = self.hole_centre(h1, h, clear, run, out)?;
        let c2 = self.hole_centre(h2, h, clear, Run { point: 5, ..run }, out)?;
        let measured = (c2[1] - c1[1]).atan2(c2[0] - c1[0]).to_degrees();
        self.set_q(150, measured);
        let nominal = self.opt(def, 307, 0.0);
        let mut xf = self.cyc.xf;
        xf.basic_rot += measured - nominal;
        let rot = xf.basic_rot;
        self.write_preset(def.number, def, xf, &[None; 9], Some(rot), out, run.loc)
    }

    fn cycle41x_rect(
        &mut self,
        def: &CycleDef,
        inside: bool,
        datum: bool,
        mut run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let c = [self.need(def, 321)?, self.need(def, 322)?];
        let half = [self.need(def, 323)? / 2.0, self.need(def, 324)? / 2.0];
        let h = self.need(def, 261)?;
        let clear = self.need(def, 260)?;
        let high = self.opt(def, 301, 1.0) == 1.0;
        let lead = self.lead(def);
        // touch points: −ref, −minor, +ref, +minor (outward normals of the sides)
        let normals = [[-1.0, 0.0], [0.0, -1.0], [1.0, 0.0], [0.0, 1.0]];
        let mut hits = [0.0; 4];
        for (k, nrm) in normals.iter().enumerate() {
            run.point = k as u32 + 1;
            let i = k % 2;
            let side = [c[0] + nrm[0] * half[0], c[1] + nrm[1] * half[1]];
            let (start, dir) = if inside {
                let back = (half[i] - lead).max(0.0);
                (
                    [c[0] + nrm[0] * back, c[1] + nrm[1] * back],
                    [nrm[0], nrm[1], 0.0],
                )
            } else {
                (
                    [side[0] + nrm[0] * lead, side[1] + nrm[1] * lead],
                    [-nrm[0], -nrm[1], 0.0],
                )
            };
            if !inside && !high && k > 0 {
                // around the corner between the previous side and this one
                let prev = normals[k - 1];
                let corner = [
                    c[0] + (prev[0] + nrm[0]) * (half[0] + lead),
                    c[1] + (prev[1] + nrm[1]) * (half[1] + lead),
                ];
                let p = self.plane_pos();
                self.position_to([corner[0], corner[1], p[2]], run, out)?;
            }
            self.go_to_point(start, h, clear, k == 0 || high, run, out)?;
            let t = self.touch_surface(dir, run, out)?;
            hits[k] = t[i];
        }
        if datum {
            self.tool_axis_datum(def, run, out)?;
        }
        self.up_to(clear, run, out)?;
        let centre = [(hits[0] + hits[2]) / 2.0, (hits[1] + hits[3]) / 2.0];
        let sides = [hits[2] - hits[0], hits[3] - hits[1]];
        let u = self.unit;
        self.set_q(151, centre[0] / u);
        self.set_q(152, centre[1] / u);
        self.set_q(154, sides[0] / u);
        self.set_q(155, sides[1] / u);
        if !datum {
            self.set_q(161, (centre[0] - c[0]) / u);
            self.set_q(162, (centre[1] - c[1]) / u);
            self.set_q(164, (sides[0] - 2.0 * half[0]) / u);
            self.set_q(165, (sides[1] - 2.0 * half[1]) / u);
            return Ok(());
        }
        self.centre_datum(def, centre, run, out)
    }

    fn cycle41x_circle(
        &mut self,
        def: &CycleDef,
        inside: bool,
        datum: bool,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let c = [self.need(def, 321)?, self.need(def, 322)?];
        let r = self.need(def, 262)? / 2.0;
        let (centre, radius) = self.probe_circle(def, inside, datum, run, out)?;
        self.set_q(151, centre[0] / self.unit);
        self.set_q(152, centre[1] / self.unit);
        self.set_q(153, 2.0 * radius / self.unit);
        if !datum {
            self.set_q(161, (centre[0] - c[0]) / self.unit);
            self.set_q(162, (centre[1] - c[1]) / self.unit);
            self.set_q(163, 2.0 * (radius - r) / self.unit);
            return Ok(());
        }
        self.centre_datum(def, centre, run, out)
    }

    /// Probes a bore (`inside`) or boss as 412/413 do (Q321, Q322, Q262, Q325, Q247, Q423,
    /// Q261, Q260, Q301, Q365; with `axis` also the tool axis of Q381) and returns its centre
    /// and radius.
    pub(super) fn probe_circle(
        &mut self,
        def: &CycleDef,
        inside: bool,
        axis: bool,
        mut run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<([f64; 2], f64), ExecError> {
        let cycle = def.number;
        let c = [self.need(def, 321)?, self.need(def, 322)?];
        let r = self.need(def, 262)? / 2.0;
        let start_angle = self.opt(def, 325, 0.0);
        let count = self.opt(def, 423, 4.0);
        if !(count == 3.0 || count == 4.0) {
            return Err(perr(ProbeError::Bad {
                cycle,
                what: format!("Q423={count}: 3 or 4 touch points"),
            }));
        }
        let step = self.opt(def, 247, 360.0 / count);
        if step == 0.0 || step.abs() > 120.0 {
            return Err(perr(ProbeError::Bad {
                cycle,
                what: format!("Q247={step}: the step angle is 0 < |Q247| ≤ 120°"),
            }));
        }
        let h = self.need(def, 261)?;
        let clear = self.need(def, 260)?;
        let high = self.opt(def, 301, 1.0) == 1.0;
        let on_arc = self.opt(def, 365, 1.0) == 1.0;
        let lead = self.lead(def);
        let ring = if inside {
            (r - lead).max(0.0)
        } else {
            r + lead
        };
        let mut pts = Vec::with_capacity(4);
        for k in 0..count as usize {
            run.point = k as u32 + 1;
            let ang = (start_angle + step * k as f64).to_radians();
            let u = [ang.cos(), ang.sin()];
            let start = [c[0] + u[0] * ring, c[1] + u[1] * ring];
            if k > 0 && !high && on_arc && ring > 0.0 {
                // along the circle about the nominal centre to the next start point
                let from = self.pos;
                let to = self.pose_at([start[0], start[1], self.plane_pos()[2]]);
                out.push_back(Op {
                    kind: OpKind::Arc {
                        from,
                        to,
                        center: c,
                        plane: self.plane,
                        sweep: step,
                        feed: self.positioning(),
                    },
                    loc: run.loc,
                });
                self.pos = to;
            }
            self.go_to_point(start, h, clear, k == 0 || high, run, out)?;
            let dir = if inside {
                [u[0], u[1], 0.0]
            } else {
                [-u[0], -u[1], 0.0]
            };
            // the ball centres of all touches lie on a circle concentric with the bore or
            // boss whatever way the ball was moved: fitted before the ball radius is added
            let t = self.probe_from_here(dir, run, out)?;
            pts.push([t[0], t[1]]);
        }
        if axis {
            self.tool_axis_datum(def, run, out)?;
        }
        self.up_to(clear, run, out)?;
        let (centre, ball_path) = fit_circle(&pts).ok_or(perr(ProbeError::Bad {
            cycle,
            what: "the touch points do not make a circle".into(),
        }))?;
        let ball = self.ball();
        let radius = if inside {
            ball_path + ball
        } else {
            ball_path - ball
        };
        Ok((centre, radius))
    }

    /// Q381=1: probes the tool axis at Q382/Q383 downward from above Q384 and keeps the
    /// surface height for the datum (Q333).
    pub(super) fn tool_axis_datum(
        &mut self,
        def: &CycleDef,
        mut run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        self.probe.axis_hit = None;
        if self.opt(def, 381, 0.0) != 1.0 {
            return Ok(());
        }
        let p = [self.need(def, 382)?, self.need(def, 383)?];
        let nominal = self.need(def, 384)?;
        let clear = self.need(def, 260)?;
        run.point += 1;
        let lead = self.lead(def);
        self.go_to_point(p, nominal + lead, clear, true, run, out)?;
        let t = self.touch_surface([0.0, 0.0, -1.0], run, out)?;
        self.probe.axis_hit = Some(t[2]);
        Ok(())
    }

    /// Writes the datum of a centre cycle (Q331/Q332, and Q333 after Q381=1).
    fn centre_datum(
        &mut self,
        def: &CycleDef,
        centre: [f64; 2],
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        self.point_datum(def, centre, None, out, run.loc)
    }

    /// 427: one coordinate (see [`Self::one_coordinate`]); Q160 the coordinate measured.
    fn cycle427(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let (k, t) = self.one_coordinate(def, run, out)?;
        self.set_q(160, t[k] / self.unit);
        Ok(())
    }

    /// 419: one coordinate (see [`Self::one_coordinate`]) becomes the datum Q333 of its axis;
    /// the other axes keep theirs.
    fn cycle419(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let (k, t) = self.one_coordinate(def, run, out)?;
        let mut measured = [None; 3];
        measured[k] = Some(t[k]);
        let mut new = [0.0; 3];
        new[k] = self.opt(def, 333, 0.0);
        self.set_datum(def, measured, new, out, run.loc)
    }

    /// 417: the surface under Q263/Q264 (nominal height Q294), probed downward along the tool
    /// axis from the clearance above it, becomes the tool-axis datum Q333; Q160 the height
    /// measured.
    fn cycle417(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let p = [self.need(def, 263)?, self.need(def, 264)?];
        let nominal = self.need(def, 294)?;
        let clear = self.need(def, 260)?;
        let lead = self.lead(def);
        self.go_to_point(p, nominal + lead, clear, true, run, out)?;
        let t = self.touch_surface([0.0, 0.0, -1.0], run, out)?;
        self.up_to(clear, run, out)?;
        self.set_q(160, t[2] / self.unit);
        let new = [0.0, 0.0, self.opt(def, 333, 0.0)];
        self.set_datum(def, [None, None, Some(t[2])], new, out, run.loc)
    }

    /// The single touch point of 419 and 427: at Q263/Q264 (measuring height Q261) along
    /// axis Q272 (1 reference, 2 minor, 3 tool axis) in direction Q267 (+1/−1), started the
    /// clearance before the point and ended at the clearance height Q260. Returns the axis
    /// index and the surface point touched.
    fn one_coordinate(
        &mut self,
        def: &CycleDef,
        run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(usize, P3), ExecError> {
        let p = [self.need(def, 263)?, self.need(def, 264)?];
        let h = self.need(def, 261)?;
        let clear = self.need(def, 260)?;
        let axis = self.opt(def, 272, 1.0);
        let sign = self.opt(def, 267, 1.0);
        let k = match axis {
            1.0 => 0,
            2.0 => 1,
            3.0 => 2,
            _ => {
                return Err(perr(ProbeError::Bad {
                    cycle: def.number,
                    what: "Q272 must be 1, 2 or 3".into(),
                }));
            }
        };
        if !(sign == 1.0 || sign == -1.0) {
            return Err(perr(ProbeError::Bad {
                cycle: def.number,
                what: "Q267 must be +1 or -1".into(),
            }));
        }
        let mut dir = [0.0; 3];
        dir[k] = sign;
        let lead = self.lead(def);
        // the start lies the clearance before the point along the probing axis
        let mut start = [p[0], p[1], h];
        start[k] -= sign * lead;
        self.go_to_point([start[0], start[1]], start[2], clear, true, run, out)?;
        let t = self.touch_surface(dir, run, out)?;
        self.up_to(clear, run, out)?;
        Ok((k, t))
    }

    fn cycle431(
        &mut self,
        def: &CycleDef,
        mut run: Run,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let pts = [
            [
                self.need(def, 263)?,
                self.need(def, 264)?,
                self.need(def, 294)?,
            ],
            [
                self.need(def, 265)?,
                self.need(def, 266)?,
                self.need(def, 295)?,
            ],
            [
                self.need(def, 296)?,
                self.need(def, 297)?,
                self.need(def, 298)?,
            ],
        ];
        let clear = self.need(def, 260)?;
        let lead = self.lead(def);
        let mut s = [[0.0; 3]; 3];
        for (k, p) in pts.iter().enumerate() {
            run.point = k as u32 + 1;
            self.go_to_point([p[0], p[1]], p[2] + lead, clear, true, run, out)?;
            s[k] = self.touch_surface([0.0, 0.0, -1.0], run, out)?;
        }
        self.up_to(clear, run, out)?;
        let d1 = [s[1][0] - s[0][0], s[1][1] - s[0][1], s[1][2] - s[0][2]];
        let d2 = [s[2][0] - s[0][0], s[2][1] - s[0][1], s[2][2] - s[0][2]];
        let mut n = [
            d1[1] * d2[2] - d1[2] * d2[1],
            d1[2] * d2[0] - d1[0] * d2[2],
            d1[0] * d2[1] - d1[1] * d2[0],
        ];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if len < 1e-12 || n[2].abs() < 1e-12 {
            return Err(perr(ProbeError::Bad {
                cycle: def.number,
                what: "the three touch points do not span a plane across the tool axis".into(),
            }));
        }
        if n[2] < 0.0 {
            n = n.map(|v| -v);
        }
        let n = n.map(|v| v / len);
        // plane w = w0 + gu·u + gv·v with normal (−gu, −gv, 1)
        let (gu, gv) = (-n[0] / n[2], -n[1] / n[2]);
        self.set_q(158, gv.atan().to_degrees());
        self.set_q(159, (-gu).atan().to_degrees());
        // A about the reference axis then B about the minor axis turn the tool axis onto n
        self.set_q(170, (-n[1]).asin().to_degrees());
        self.set_q(171, n[0].atan2(n[2]).to_degrees());
        self.set_q(172, 0.0);
        for (k, q) in [173, 174, 175].iter().enumerate() {
            self.set_q(*q, s[k][2] / self.unit);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_fit_is_exact_for_points_on_a_circle() {
        let (c, r) = ([3.2_f64, -1.7_f64], 12.5_f64);
        for start in [0.0_f64, 17.0, 200.0] {
            let pts: Vec<[f64; 2]> = (0..4)
                .map(|k| {
                    let a = (start + 90.0 * k as f64).to_radians();
                    [c[0] + r * a.cos(), c[1] + r * a.sin()]
                })
                .collect();
            let (fc, fr) = fit_circle(&pts).expect("a circle");
            assert!((fc[0] - c[0]).abs() < 1e-9 && (fc[1] - c[1]).abs() < 1e-9);
            assert!((fr - r).abs() < 1e-9);
            let three = fit_circle(&pts[..3]).expect("three points");
            assert!((three.1 - r).abs() < 1e-9);
        }
        assert!(fit_circle(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]).is_none());
    }

    #[test]
    fn line_angles_fold_into_a_half_turn() {
        assert!((line_angle(181.5) - 1.5).abs() < 1e-12);
        assert!((line_angle(-178.5) - 1.5).abs() < 1e-12);
        assert!((line_angle(90.0) - 90.0).abs() < 1e-12);
    }
}
