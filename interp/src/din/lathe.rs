//! The modal state of a lathe running a DIN PLUS MACHINING section, and the motion it emits.
//!
//! Coordinates in ops: X is a **radius** (the program's diameter halved), Z the spindle axis,
//! C the main spindle as a rotary axis in degrees, Y the Y axis, B the tilt of the tool.
//! Turning arcs lie in the ZX plane ([`Plane::ZX`]); looking onto the drawing with Z to the
//! right and X up, G3/G13 (counter-clockwise) turn Z towards X, which is a positive sweep in
//! the op contract, and G2/G12 a negative one. G2/G3 take the centre I, K incrementally from
//! the start point, G12/G13 absolutely; I is a radius value (the manual's G13 example has its
//! start and end 20 mm from the centre only with I read as a radius). `R` gives the radius
//! instead (the shorter arc).

use std::collections::VecDeque;

use super::block::{DinValue, DinWord};
use crate::diag::ProgramError;
use crate::op::{
    AxisLetter, CompSide, Feed, Op, OpKind, Plane, Pose, SourceLoc, SpindleDir, SpindleId,
    SpindleSpeed,
};
use crate::tnc::exec::{C_RADIUS_TOLERANCE, ExecError};
use crate::tnc::geom;

/// The tool change point of the built-in lathe used by G14: X diameter 200 mm, Z 200 mm.
pub const TOOL_CHANGE_POINT: (f64, f64) = (200.0, 200.0);

/// What the feed word F means.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FeedUnit {
    /// G94: mm/min.
    PerMinute,
    /// G95: mm per revolution of the main spindle.
    PerRevolution,
    /// G195: mm per revolution of the driven tool.
    DrivenPerRevolution,
}

/// A word located in its line.
pub(crate) fn err_at(w: &DinWord, e: ProgramError) -> ExecError {
    (Some(w.pos as u32), e)
}

/// The number of a word, or an error at it (`?` and texts are not numbers here).
pub(crate) fn num(w: &DinWord) -> Result<f64, ExecError> {
    match &w.value {
        DinValue::Num(v) => Ok(*v),
        DinValue::Unknown => Err(err_at(
            w,
            ProgramError::NotSupported(format!("{}? outside a FINISHED PART contour", w.addr)),
        )),
        DinValue::Text(_) => Err(err_at(w, ProgramError::MissingValue(w.addr.clone()))),
        DinValue::Expr(_) => Err(err_at(
            w,
            ProgramError::Unexpected(format!("formula in {} where it is not evaluated", w.addr)),
        )),
    }
}

/// A group of words: a G code with the words that follow it up to the next G.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Group<'a> {
    /// The G number, None for the words before the first G.
    pub g: Option<u32>,
    /// The G word itself.
    pub g_word: Option<&'a DinWord>,
    /// The parameter words.
    pub words: &'a [DinWord],
}

impl<'a> Group<'a> {
    /// The word with this address.
    pub fn get(&self, addr: &str) -> Option<&'a DinWord> {
        self.words.iter().find(|w| w.addr == addr)
    }

    /// The number of the word with this address.
    pub fn value(&self, addr: &str) -> Result<Option<f64>, ExecError> {
        self.get(addr).map(num).transpose()
    }
}

/// Splits the words of a block at each G word.
pub(crate) fn groups(words: &[DinWord]) -> Result<Vec<Group<'_>>, ExecError> {
    let mut out = Vec::new();
    let mut start = 0;
    let mut g = None;
    let mut g_word = None;
    for (i, w) in words.iter().enumerate() {
        if w.addr == "G" {
            out.push(Group {
                g,
                g_word,
                words: words.get(start..i).unwrap_or(&[]),
            });
            let n = num(w)?;
            if !(n >= 0.0 && n.fract() == 0.0 && n < 10_000.0) {
                return Err(err_at(
                    w,
                    ProgramError::OutOfRange(format!("G{n} is not a G function number")),
                ));
            }
            g = Some(n as u32);
            g_word = Some(w);
            start = i + 1;
        }
    }
    out.push(Group {
        g,
        g_word,
        words: words.get(start..).unwrap_or(&[]),
    });
    Ok(out)
}

/// Modal lathe state.
#[derive(Debug)]
pub(crate) struct Lathe {
    /// Last programmed position (X radius, mm, degrees).
    pub pos: Pose,
    /// The active motion G (0, 1, 2, 3, 12, 13).
    pub motion: Option<u32>,
    /// What F means.
    pub feed_unit: FeedUnit,
    /// The active feed.
    pub feed: Option<Feed>,
    /// G195 feed per driven-tool revolution, mm (to recompute when the speed changes).
    pub driven_feed: Option<f64>,
    /// Main spindle speed.
    pub main_speed: SpindleSpeed,
    /// Main spindle direction.
    pub main_dir: SpindleDir,
    /// Driven tool speed, rpm.
    pub driven_speed: f64,
    /// Driven tool direction.
    pub driven_dir: SpindleDir,
    /// G26 speed limit, rpm.
    pub speed_limit: Option<f64>,
    /// M14: the main spindle is the C axis.
    pub c_axis: bool,
    /// Coolant.
    pub coolant: bool,
    /// Radius compensation.
    pub comp: CompSide,
}

impl Lathe {
    /// A lathe standing at `start`, spindles off, feed per revolution.
    pub fn new(start: Pose) -> Self {
        Lathe {
            pos: start,
            motion: None,
            feed_unit: FeedUnit::PerRevolution,
            feed: None,
            driven_feed: None,
            main_speed: SpindleSpeed::Rpm(0.0),
            main_dir: SpindleDir::Off,
            driven_speed: 0.0,
            driven_dir: SpindleDir::Off,
            speed_limit: None,
            c_axis: false,
            coolant: false,
            comp: CompSide::Off,
        }
    }

    /// Sets the feed from an F value in the active unit.
    pub fn set_feed(&mut self, f: f64, w: &DinWord) -> Result<(), ExecError> {
        if !(f > 0.0 && f.is_finite()) {
            return Err(err_at(
                w,
                ProgramError::OutOfRange(format!("feed F{f} must be positive")),
            ));
        }
        self.feed = Some(match self.feed_unit {
            FeedUnit::PerMinute => Feed::Rate(f / 60.0),
            FeedUnit::PerRevolution => Feed::PerRevolution(f),
            FeedUnit::DrivenPerRevolution => {
                self.driven_feed = Some(f);
                Feed::Rate(f * self.driven_speed / 60.0)
            }
        });
        Ok(())
    }

    /// The feed for a feed move, or the no-feed error.
    pub fn need_feed(&self) -> Result<Feed, ExecError> {
        match self.feed {
            Some(Feed::Rate(r)) if r <= 0.0 => Err((
                None,
                ProgramError::Missing("G195 feed needs a driven tool speed G197 S first"),
            )),
            Some(f) => Ok(f),
            None => Err((None, ProgramError::NoFeed)),
        }
    }

    /// The main spindle op for the current state.
    pub fn main_spindle_op(&self) -> OpKind {
        OpKind::Spindle {
            spindle: SpindleId::Main,
            dir: self.main_dir,
            speed: match (self.main_speed, self.speed_limit) {
                (SpindleSpeed::SurfaceSpeed(v), Some(n)) => SpindleSpeed::SurfaceSpeedCapped(v, n),
                (speed, _) => speed,
            },
        }
    }

    /// The driven tool op for the current state.
    pub fn driven_op(&self) -> OpKind {
        OpKind::Spindle {
            spindle: SpindleId::Driven,
            dir: self.driven_dir,
            speed: SpindleSpeed::Rpm(self.driven_speed),
        }
    }

    /// Emits a straight move to `to` (nothing when it does not move) and updates the position.
    pub fn line(&mut self, to: Pose, feed: Feed, loc: SourceLoc, out: &mut VecDeque<Op>) {
        if to != self.pos {
            out.push_back(Op {
                kind: OpKind::Line {
                    from: self.pos,
                    to,
                    feed,
                },
                loc,
            });
            self.pos = to;
        }
    }

    /// The end point of a G0/G1/G2/G3 group: X, Xi (diameters), Z, Zi, C, Ci, Y, Yi, B.
    pub fn target(&self, g: &Group<'_>) -> Result<Pose, ExecError> {
        let mut p = self.pos;
        let axes = [
            ("X", "Xi", AxisLetter::X, 0.5),
            ("Z", "Zi", AxisLetter::Z, 1.0),
            ("C", "Ci", AxisLetter::C, 1.0),
            ("Y", "Yi", AxisLetter::Y, 1.0),
            ("B", "Bi", AxisLetter::B, 1.0),
        ];
        for (abs, inc, axis, scale) in axes {
            match (g.get(abs), g.get(inc)) {
                (Some(a), Some(_)) => {
                    return Err(err_at(
                        a,
                        ProgramError::Unexpected(format!("{abs} and {inc} in one block")),
                    ));
                }
                (Some(a), None) => p[axis] = num(a)? * scale,
                (None, Some(i)) => p[axis] += num(i)? * scale,
                (None, None) => {}
            }
        }
        Ok(p)
    }

    /// G2/G3/G12/G13: an arc in the ZX plane.
    pub fn arc(
        &mut self,
        g: &Group<'_>,
        code: u32,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let to = self.target(g)?;
        let ccw = matches!(code, 3 | 13);
        let s = [self.pos[AxisLetter::Z], self.pos[AxisLetter::X]];
        let e = [to[AxisLetter::Z], to[AxisLetter::X]];
        let feed = self.need_feed()?;
        let (centre, sweep) = match g.get("R") {
            Some(rw) => {
                let r = num(rw)?;
                if r == 0.0 || !r.is_finite() {
                    return Err(err_at(
                        rw,
                        ProgramError::Geometry("arc radius R must not be 0".into()),
                    ));
                }
                if geom::norm(geom::sub(e, s)) < 1e-9 {
                    return Err(err_at(
                        rw,
                        ProgramError::Geometry("arc end point equals its start point".into()),
                    ));
                }
                geom::cr_arc(s, e, r, ccw).map_err(|chord| {
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
                let i = g.value("I")?;
                let k = g.value("K")?;
                if i.is_none() && k.is_none() {
                    return Err((
                        None,
                        ProgramError::Missing("arc needs the radius R or the centre I, K"),
                    ));
                }
                let c = if code == 2 || code == 3 {
                    [s[0] + k.unwrap_or(0.0), s[1] + i.unwrap_or(0.0)]
                } else {
                    [
                        k.unwrap_or(self.pos[AxisLetter::Z]),
                        i.unwrap_or(self.pos[AxisLetter::X]),
                    ]
                };
                let rs = geom::norm(geom::sub(s, c));
                let re = geom::norm(geom::sub(e, c));
                if (rs - re).abs() > C_RADIUS_TOLERANCE {
                    return Err((
                        None,
                        ProgramError::RadiusMismatch {
                            start: rs,
                            end: re,
                            tol: C_RADIUS_TOLERANCE,
                        },
                    ));
                }
                if rs < 1e-9 {
                    return Err((
                        None,
                        ProgramError::Geometry("arc start point lies on the centre".into()),
                    ));
                }
                let sweep = geom::directed_sweep(
                    geom::angle(geom::sub(s, c)),
                    geom::angle(geom::sub(e, c)),
                    ccw,
                );
                (c, sweep)
            }
        };
        out.push_back(Op {
            kind: OpKind::Arc {
                from: self.pos,
                to,
                center: centre,
                plane: Plane::ZX,
                sweep,
                feed,
            },
            loc,
        });
        self.pos = to;
        Ok(())
    }
}
