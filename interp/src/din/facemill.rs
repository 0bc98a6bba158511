//! G793: a free contour on the face, milled at depth with the C/Y kinematics.
//!
//! `G793 ZS… ZE… P… F…` opens the contour; the blocks after it describe it in the face's
//! Cartesian system, seen onto the face: `G0 XK… YK…` its start, `G1 XK… YK…` lines, `G2`
//! (clockwise) / `G3` (counter-clockwise) `XK… YK…` arcs with the radius `R` (the shorter
//! arc) or the absolute centre `I`, `J`; `G80` ends it and runs the cycle. (This is this
//! version's form of the manual's "contour in the following blocks".)
//!
//! After a G745/G743 pattern without ZE, the contour is milled at every pattern position,
//! its coordinates taken relative to the position (the position is the contour's origin),
//! with the spindle turned to the position's angle as for the other pattern cycles; ZS/ZE
//! of the pattern stand in for those G793 leaves out.
//!
//! The spindle stays at the angle C where it stands (set it with G110 before), and a face
//! point p is reached at (X, Y) = rot(−C)·p, as for the slot G791, so straight elements stay
//! straight lines in X/Y and arcs stay arcs in the XY plane with the same sweep. Milling:
//! rapid at the clearance Z (where the tool stood at G793) onto the contour start, rapid to
//! ZS (default: the clearance), then in infeeds of P (default: all at once) down to ZE:
//! feed down at the start, follow the contour at the feed; an open contour goes back to its
//! start at ZS between infeeds, a closed one is entered again where it ends. Last, rapid
//! up to the clearance Z.

use std::collections::VecDeque;

use super::cycles::{FacePattern, face_in_turned, face_pose};
use super::lathe::{Group, Lathe, err_at, groups, num};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, Feed, Op, OpKind, Plane, SourceLoc};
use crate::tnc::exec::{C_RADIUS_TOLERANCE, ExecError};
use crate::tnc::geom;

/// Most elements of one contour.
pub const MAX_ELEMENTS: usize = 10_000;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Element {
    Line {
        to: [f64; 2],
    },
    Arc {
        to: [f64; 2],
        centre: [f64; 2],
        sweep: f64,
    },
}

/// A G793 contour being collected.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct FaceContour {
    /// The positions of a G745/G743 pattern before G793 (the contour's origin at each).
    positions: Option<Vec<[f64; 2]>>,
    zs: Option<f64>,
    ze: f64,
    infeed: Option<f64>,
    feed: Feed,
    start: Option<[f64; 2]>,
    pen: [f64; 2],
    motion: Option<u32>,
    elements: Vec<Element>,
}

/// Reads the G793 group.
pub(crate) fn g793(
    lathe: &mut Lathe,
    g: &Group<'_>,
    pattern: Option<FacePattern>,
) -> Result<FaceContour, ExecError> {
    let here = g.g_word.map(|w| w.pos as u32);
    if let Some(f) = g.get("F") {
        lathe.set_feed(num(f)?, f)?;
    }
    let feed = lathe.need_feed().map_err(|(_, e)| (here, e))?;
    let ze = g
        .value("ZE")?
        .or(pattern.as_ref().and_then(|p| p.ze))
        .ok_or((
            here,
            ProgramError::Missing("G793 needs the milling depth ZE"),
        ))?;
    Ok(FaceContour {
        zs: g.value("ZS")?.or(pattern.as_ref().and_then(|p| p.zs)),
        positions: pattern.map(|p| p.points),
        ze,
        infeed: g.value("P")?.filter(|p| *p > 0.0),
        feed,
        start: None,
        pen: [0.0, 0.0],
        motion: None,
        elements: Vec::new(),
    })
}

impl FaceContour {
    /// Takes one contour block; returns true at G80 (the contour is complete).
    pub fn add(&mut self, words: &[super::block::DinWord]) -> Result<bool, ExecError> {
        for g in &groups(words)? {
            let code = match g.g {
                Some(80) => {
                    if self.elements.is_empty() {
                        return Err((
                            g.g_word.map(|w| w.pos as u32),
                            ProgramError::Missing("the G793 contour has no elements before G80"),
                        ));
                    }
                    return Ok(true);
                }
                Some(c @ 0..=3) => {
                    self.motion = Some(c);
                    c
                }
                None if g.words.is_empty() => continue,
                None => self.motion.ok_or((
                    None,
                    ProgramError::Missing("G793 contour element without G0, G1, G2 or G3"),
                ))?,
                Some(other) => {
                    return Err((
                        g.g_word.map(|w| w.pos as u32),
                        ProgramError::Unexpected(format!(
                            "G{other} in a G793 contour: only G0, G1, G2, G3 until G80"
                        )),
                    ));
                }
            };
            self.element(g, code)?;
        }
        Ok(false)
    }

    fn element(&mut self, g: &Group<'_>, code: u32) -> Result<(), ExecError> {
        for w in g.words {
            if !matches!(w.addr.as_str(), "XK" | "YK" | "R" | "I" | "J") {
                return Err(err_at(
                    w,
                    ProgramError::UnknownWord {
                        word: w.addr.clone(),
                        block: "G793 contour",
                    },
                ));
            }
        }
        let to = [
            g.value("XK")?.unwrap_or(self.pen[0]),
            g.value("YK")?.unwrap_or(self.pen[1]),
        ];
        if code == 0 {
            if self.start.is_some() {
                return Err((
                    g.g_word.map(|w| w.pos as u32),
                    ProgramError::Unexpected("a second G0 start point in a G793 contour".into()),
                ));
            }
            self.start = Some(to);
            self.pen = to;
            return Ok(());
        }
        if self.start.is_none() {
            return Err((
                None,
                ProgramError::Missing("the G793 contour starts with G0 XK… YK…"),
            ));
        }
        if self.elements.len() >= MAX_ELEMENTS {
            return Err((
                None,
                ProgramError::OutOfRange(format!("more than {MAX_ELEMENTS} contour elements")),
            ));
        }
        let s = self.pen;
        let e = if code == 1 {
            Element::Line { to }
        } else {
            let ccw = code == 3;
            let (centre, sweep) = match g.get("R") {
                Some(rw) => {
                    let r = num(rw)?;
                    if r == 0.0 || geom::norm(geom::sub(to, s)) < 1e-9 {
                        return Err(err_at(
                            rw,
                            ProgramError::Geometry("arc with R0 or without length".into()),
                        ));
                    }
                    geom::cr_arc(s, to, r, ccw).map_err(|chord| {
                        err_at(
                            rw,
                            ProgramError::ChordTooLong {
                                chord,
                                two_r: 2.0 * r.abs(),
                            },
                        )
                    })?
                }
                None => {
                    let (Some(i), Some(j)) = (g.value("I")?, g.value("J")?) else {
                        return Err((
                            g.g_word.map(|w| w.pos as u32),
                            ProgramError::Missing("arc needs the radius R or the centre I, J"),
                        ));
                    };
                    let c = [i, j];
                    let (rs, re) = (geom::norm(geom::sub(s, c)), geom::norm(geom::sub(to, c)));
                    if (rs - re).abs() > C_RADIUS_TOLERANCE || rs < 1e-9 {
                        return Err((
                            None,
                            ProgramError::RadiusMismatch {
                                start: rs,
                                end: re,
                                tol: C_RADIUS_TOLERANCE,
                            },
                        ));
                    }
                    let sweep = geom::directed_sweep(
                        geom::angle(geom::sub(s, c)),
                        geom::angle(geom::sub(to, c)),
                        ccw,
                    );
                    (c, sweep)
                }
            };
            Element::Arc { to, centre, sweep }
        };
        self.elements.push(e);
        self.pen = to;
        Ok(())
    }

    /// Mills the contour (see the module documentation), once or at every pattern position.
    pub fn run(&self, lathe: &mut Lathe, loc: SourceLoc, out: &mut VecDeque<Op>) {
        let clearance = lathe.pos[AxisLetter::Z];
        match &self.positions {
            None => {
                let c = lathe.pos[AxisLetter::C];
                self.mill(lathe, [0.0, 0.0], c, clearance, loc, out);
            }
            Some(points) => {
                for p in points {
                    let at = face_pose(lathe.pos, *p, clearance);
                    lathe.line(at, Feed::Rapid, loc, out);
                    self.mill(lathe, *p, at[AxisLetter::C], clearance, loc, out);
                }
            }
        }
    }

    /// Mills the contour shifted by `origin`, the spindle at `c`.
    fn mill(
        &self,
        lathe: &mut Lathe,
        origin: [f64; 2],
        c: f64,
        clearance: f64,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) {
        let Some(start) = self.start else {
            return;
        };
        let zs = self.zs.unwrap_or(clearance);
        let place = |lathe: &Lathe, p: [f64; 2], z: f64| {
            let t = face_in_turned([p[0] + origin[0], p[1] + origin[1]], c);
            let mut q = lathe.pos;
            q[AxisLetter::X] = t[0];
            q[AxisLetter::Y] = t[1];
            q[AxisLetter::Z] = z;
            q
        };
        let to = place(lathe, start, clearance);
        lathe.line(to, Feed::Rapid, loc, out);
        let to = place(lathe, start, zs);
        lathe.line(to, Feed::Rapid, loc, out);
        let closed = geom::norm(geom::sub(self.pen, start)) < 1e-9;
        let total = (self.ze - zs).abs();
        let down = if self.ze < zs { -1.0 } else { 1.0 };
        let step = self.infeed.unwrap_or(total).max(1e-3);
        let mut done = 0.0;
        loop {
            done = (done + step).min(total);
            let z = zs + down * done;
            let mut q = lathe.pos;
            q[AxisLetter::Z] = z;
            lathe.line(q, self.feed, loc, out);
            for e in &self.elements {
                match *e {
                    Element::Line { to } => {
                        let q = place(lathe, to, z);
                        lathe.line(q, self.feed, loc, out);
                    }
                    Element::Arc { to, centre, sweep } => {
                        let q = place(lathe, to, z);
                        out.push_back(Op {
                            kind: OpKind::Arc {
                                from: lathe.pos,
                                to: q,
                                center: face_in_turned(
                                    [centre[0] + origin[0], centre[1] + origin[1]],
                                    c,
                                ),
                                plane: Plane::XY,
                                sweep,
                                feed: self.feed,
                            },
                            loc,
                        });
                        lathe.pos = q;
                    }
                }
            }
            if done >= total - 1e-9 {
                break;
            }
            if !closed {
                let mut q = lathe.pos;
                q[AxisLetter::Z] = zs;
                lathe.line(q, Feed::Rapid, loc, out);
                let q = place(lathe, start, zs);
                lathe.line(q, Feed::Rapid, loc, out);
            }
        }
        let mut up = lathe.pos;
        up[AxisLetter::Z] = clearance;
        lathe.line(up, Feed::Rapid, loc, out);
    }
}
