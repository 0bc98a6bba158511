//! Path blocks: the motion ops of L, LP, C, CC, CR, CT, CP and CTP, and the R+/R- paraxial
//! correction.
//!
//! Arcs and polar paths work in the plane of the pole: CC with two axes of a plane selects that
//! plane (X/Y, Z/X or Y/Z), CC with one or no axis uses the working plane of the tool axis.
//! Polar angles run from the plane's first axis towards its second (X→Y, Z→X, Y→Z).

use super::exec::{
    C_RADIUS_TOLERANCE, ExecError, FULL_CIRCLE_EPS, MAX_IPA, Machine, Pole, at, here,
};
use super::geom;
use super::stmt::{Stmt, Words};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, OpKind, Plane, Pose};

impl Machine {
    pub(super) fn direction(w: &Words, block: &'static str) -> Result<bool, ExecError> {
        w.dr.map(|(ccw, _)| ccw).ok_or_else(|| {
            here(ProgramError::Missing(match block {
                "C" => "C needs the direction DR+ or DR-",
                "CR" => "CR needs the direction DR+ or DR-",
                _ => "CP needs the direction DR+ or DR-",
            }))
        })
    }

    /// A straight move to `to` (None when it goes nowhere).
    fn line_to(
        &self,
        from: Pose,
        to: Pose,
        feed: Option<Feed>,
    ) -> Result<Option<OpKind>, ExecError> {
        if to == from {
            return Ok(None);
        }
        Ok(Some(OpKind::Line {
            from,
            to,
            feed: self.need_feed(feed)?,
        }))
    }

    /// The end of an `L` block with M91 or M92: its absolute coordinates are machine
    /// coordinates, measured from the machine datum (M91) or the machine builder's fixed
    /// position (M92; klar's machines put it at the machine datum), so neither the active
    /// preset nor a datum shift, mirror, rotation or scaling acts on them; incremental words
    /// move by their amount along the machine axis. Axes the block does not name stay where
    /// they are on the machine. The result is in program coordinates, like every position.
    fn machine_datum_target(&self, w: &Words) -> Result<Pose, ExecError> {
        if !self.tilt.identity {
            return Err(here(ProgramError::NotSupported(
                "M91/M92 in a tilted working plane".into(),
            )));
        }
        let mut machine = self.cyc.xf.map_point(&self.pos);
        for a in AxisLetter::ALL {
            if let Some(c) = &w.axes[a.index()] {
                let v = self.length(a, self.params.value(c.value));
                machine[a] = if c.incremental { machine[a] + v } else { v };
            }
        }
        Ok(self.cyc.xf.unmap_point(&machine))
    }

    /// Computes the motion op of a path block (None when nothing moves).
    pub(super) fn motion(&mut self, stmt: &Stmt, w: &Words) -> Result<Option<OpKind>, ExecError> {
        let feed = self.feed(w.feed)?;
        let from = self.pos;
        match stmt {
            Stmt::Line => {
                let mut to = self.target(w);
                if w.m_words().any(|(n, _)| n == 91 || n == 92) {
                    to = self.machine_datum_target(w)?;
                }
                if let Some((longer, pos)) = w.paraxial {
                    to = self.paraxial(from, to, longer, pos)?;
                }
                self.line_to(from, to, feed)
            }
            Stmt::LinePolar => {
                let to = self.polar_end(w, "LP")?;
                self.line_to(from, to, feed)
            }
            Stmt::Circle => {
                let pole = self.pole_for("C")?;
                let ccw = Self::direction(w, "C")?;
                let plane = pole.plane;
                let (a, b, _) = plane.axes();
                let mut to = self.target(w);
                let s = [from[a], from[b]];
                let mut e = [to[a], to[b]];
                let rs = geom::norm(geom::sub(s, pole.centre));
                let re = geom::norm(geom::sub(e, pole.centre));
                if (rs - re).abs() > C_RADIUS_TOLERANCE {
                    return Err(here(ProgramError::RadiusMismatch {
                        start: rs,
                        end: re,
                        tol: C_RADIUS_TOLERANCE,
                    }));
                }
                if rs < 1e-9 {
                    return Err(here(ProgramError::Geometry(
                        "C start point lies on CC: radius 0".into(),
                    )));
                }
                let full = geom::norm(geom::sub(e, s)) < FULL_CIRCLE_EPS;
                if full {
                    e = s;
                    to[a] = s[0];
                    to[b] = s[1];
                }
                let sweep = geom::directed_sweep(
                    geom::angle(geom::sub(s, pole.centre)),
                    geom::angle(geom::sub(e, pole.centre)),
                    ccw,
                );
                let sweep = if full {
                    if ccw { 360.0 } else { -360.0 }
                } else {
                    sweep
                };
                Ok(Some(OpKind::Arc {
                    from,
                    to,
                    center: pole.centre,
                    plane,
                    sweep,
                    feed: self.need_feed(feed)?,
                }))
            }
            Stmt::CircleRadius => {
                let ccw = Self::direction(w, "CR")?;
                let Some((rv, rpos)) = w.radius else {
                    return Err(here(ProgramError::Missing("CR needs the radius R+ or R-")));
                };
                let r = self.params.value(rv) * self.scale;
                if r == 0.0 || !r.is_finite() {
                    return Err(at(
                        rpos,
                        ProgramError::Geometry("CR radius must not be 0".into()),
                    ));
                }
                let plane = self.plane;
                let (a, b, _) = plane.axes();
                let to = self.target(w);
                let s = [from[a], from[b]];
                let e = [to[a], to[b]];
                if geom::norm(geom::sub(e, s)) < FULL_CIRCLE_EPS {
                    return Err(here(ProgramError::Geometry(
                        "CR end point equals its start point: use C for a full circle".into(),
                    )));
                }
                let (center, sweep) = geom::cr_arc(s, e, r, ccw).map_err(|chord| {
                    here(ProgramError::ChordTooLong {
                        chord,
                        two_r: 2.0 * r.abs(),
                    })
                })?;
                Ok(Some(OpKind::Arc {
                    from,
                    to,
                    center,
                    plane,
                    sweep,
                    feed: self.need_feed(feed)?,
                }))
            }
            Stmt::CircleTangent | Stmt::CircleTangentPolar => {
                let (plane, to) = if matches!(stmt, Stmt::CircleTangentPolar) {
                    let to = self.polar_end(w, "CTP")?;
                    (self.pole_for("CTP")?.plane, to)
                } else {
                    (self.plane, self.target(w))
                };
                let (a, b, _) = plane.axes();
                let t = self
                    .tangent
                    .map(|d| [d[a.index()], d[b.index()]])
                    .filter(|t| geom::norm(*t) > 0.0)
                    .ok_or_else(|| {
                        here(ProgramError::Geometry(
                            "CT needs a preceding contour element in the working plane".into(),
                        ))
                    })?;
                let n = geom::norm(t);
                let t = [t[0] / n, t[1] / n];
                let s = [from[a], from[b]];
                let e = [to[a], to[b]];
                if geom::norm(geom::sub(e, s)) < FULL_CIRCLE_EPS {
                    return Err(here(ProgramError::Geometry(
                        "CT end point equals its start point".into(),
                    )));
                }
                let (center, sweep) = geom::ct_arc(s, t, e).ok_or_else(|| {
                    here(ProgramError::Geometry(
                        "CT end point lies on the tangent: that is a straight line, not an arc"
                            .into(),
                    ))
                })?;
                Ok(Some(OpKind::Arc {
                    from,
                    to,
                    center,
                    plane,
                    sweep,
                    feed: self.need_feed(feed)?,
                }))
            }
            Stmt::CirclePolar => {
                let pole = self.pole_for("CP")?;
                let ccw = Self::direction(w, "CP")?;
                Self::no_plane_axes(w, pole.plane, "CP")?;
                let plane = pole.plane;
                let (a, b, _) = plane.axes();
                let s = [from[a], from[b]];
                let rel = geom::sub(s, pole.centre);
                let r = geom::norm(rel);
                if r < 1e-9 {
                    return Err(here(ProgramError::Geometry(
                        "CP start point lies on the pole CC: radius 0".into(),
                    )));
                }
                let a0 = geom::angle(rel);
                let Some(pa) = w.pa else {
                    return Err(here(ProgramError::Missing("CP needs PA or IPA")));
                };
                let v = self.params.value(pa.value);
                let sweep = if pa.incremental {
                    if v.abs() > MAX_IPA {
                        return Err(at(
                            pa.pos,
                            ProgramError::OutOfRange(format!("IPA{v:+} beyond ±{MAX_IPA} degrees")),
                        ));
                    }
                    if v == 0.0 || (v > 0.0) != ccw {
                        return Err(at(
                            pa.pos,
                            ProgramError::IpaSign {
                                ipa: v,
                                dr: if ccw { '+' } else { '-' },
                            },
                        ));
                    }
                    v
                } else {
                    geom::directed_sweep(a0, v, ccw)
                };
                let mut to = self.target(w);
                let e = geom::polar(pole.centre, r, a0 + sweep);
                to[a] = e[0];
                to[b] = e[1];
                Ok(Some(OpKind::Arc {
                    from,
                    to,
                    center: pole.centre,
                    plane,
                    sweep,
                    feed: self.need_feed(feed)?,
                }))
            }
            _ => Ok(None),
        }
    }

    /// End point of a polar block (LP, CTP, polar APPR/DEP): PR/IPR and PA/IPA about the pole;
    /// a missing PR or PA keeps the current polar radius or angle. The axis normal to the
    /// pole's plane may be programmed too.
    pub(super) fn polar_end(&self, w: &Words, block: &'static str) -> Result<Pose, ExecError> {
        let from = self.pos;
        let pole = self.pole_for(block)?;
        Self::no_plane_axes(w, pole.plane, block)?;
        let (a, b, _) = pole.plane.axes();
        let rel = geom::sub([from[a], from[b]], pole.centre);
        let (r0, a0) = (geom::norm(rel), geom::angle(rel));
        let r = match &w.pr {
            Some(c) => {
                let v = self.params.value(c.value) * self.scale;
                if c.incremental { r0 + v } else { v }
            }
            None => r0,
        };
        if r < 0.0 {
            return Err(at(
                w.pr.map_or(0, |c| c.pos),
                ProgramError::Geometry(format!("polar radius PR {r:.4} mm is negative")),
            ));
        }
        let ang = match &w.pa {
            Some(c) => {
                let v = self.params.value(c.value);
                if c.incremental { a0 + v } else { v }
            }
            None => a0,
        };
        let mut to = self.target(w);
        let e = geom::polar(pole.centre, r, ang);
        to[a] = e[0];
        to[b] = e[1];
        Ok(to)
    }

    /// R+ / R-: a move in one axis, lengthened (R+) or shortened (R-) by the tool radius.
    pub(super) fn paraxial(
        &self,
        from: Pose,
        to: Pose,
        longer: bool,
        pos: u32,
    ) -> Result<Pose, ExecError> {
        let moving: Vec<AxisLetter> = AxisLetter::ALL
            .into_iter()
            .filter(|a| to[*a] != from[*a])
            .collect();
        let [axis] = moving.as_slice() else {
            return Err(at(
                pos,
                ProgramError::Geometry(
                    "R+/R- (paraxial compensation) needs a move in exactly one axis".into(),
                ),
            ));
        };
        if axis.is_rotary() {
            return Err(at(
                pos,
                ProgramError::Geometry("R+/R- cannot compensate a rotary axis move".into()),
            ));
        }
        let d = to[*axis] - from[*axis];
        let change = if longer {
            self.tool_radius
        } else {
            -self.tool_radius
        };
        if !longer && d.abs() < self.tool_radius {
            return Err(at(
                pos,
                ProgramError::Geometry(format!(
                    "R-: the move of {:.4} mm is shorter than the tool radius {:.4} mm",
                    d.abs(),
                    self.tool_radius
                )),
            ));
        }
        let mut out = to;
        out[*axis] += d.signum() * change;
        Ok(out)
    }

    /// CC: sets the pole. The plane follows the two axes programmed (X/Y → XY, Z/X → ZX,
    /// Y/Z → YZ); with one axis or none it is the working plane, and missing coordinates come
    /// from the previous pole in that plane, else from the current position. `I` words are
    /// relative to the last programmed position.
    pub(super) fn centre(&mut self, w: &Words) -> Result<(), ExecError> {
        let has = |ax: AxisLetter| w.axes[ax.index()].is_some();
        let (x, y, z) = (has(AxisLetter::X), has(AxisLetter::Y), has(AxisLetter::Z));
        let plane = match (x, y, z) {
            (true, true, false) => Plane::XY,
            (true, false, true) => Plane::ZX,
            (false, true, true) => Plane::YZ,
            (true, true, true) => {
                let pos = w.axes[AxisLetter::Z.index()].map_or(0, |c| c.pos);
                return Err(at(
                    pos,
                    ProgramError::Geometry("CC takes two coordinates of one plane".into()),
                ));
            }
            _ => self.plane,
        };
        let (a, b, _) = plane.axes();
        for ax in AxisLetter::ALL {
            if ax != a
                && ax != b
                && let Some(c) = &w.axes[ax.index()]
            {
                return Err(at(
                    c.pos,
                    ProgramError::MisplacedWord {
                        word: ax.to_string(),
                        block: "CC",
                    },
                ));
            }
        }
        // CC without coordinates: the last programmed position becomes the pole
        let prev = if w.axes_set == 0 {
            None
        } else {
            self.pole.filter(|p| p.plane == plane)
        };
        let mut centre = [0.0; 2];
        for (i, ax) in [a, b].into_iter().enumerate() {
            centre[i] = match &w.axes[ax.index()] {
                Some(c) => self.resolve(ax, c),
                None => prev.map_or(self.pos[ax], |p| p.centre[i]),
            };
        }
        self.pole = Some(Pole { plane, centre });
        Ok(())
    }
}
