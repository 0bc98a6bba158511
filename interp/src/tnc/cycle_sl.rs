//! SL cycles (14 contour geometry, 20 contour data, 21–24 machining): collecting the
//! contours of the subprograms named in cycle 14 and running the cycle on them.
//!
//! `CYCL CALL` of an SL cycle asks the interpreter ([`Flow::Contours`]) to run each contour
//! subprogram from its `LBL n` to `LBL 0` while the machine collects instead of moving:
//! the first motion block gives the contour's start point, every following line and arc (in
//! the working plane, RND/CHF resolved) becomes an element, and the radius compensation the
//! subprogram programs (RL/RR) tells pockets from islands. Feeds and M functions in a contour
//! subprogram are ignored, Q parameter assignments act normally. A contour that does not end
//! at its start point is closed with a straight line. Arcs longer than a half circle are split
//! into halves, so that every element is unambiguous from its end point, centre and
//! direction. Afterwards the machine state (position, compensation, pole, feed) is what it was
//! at the call, and the cycle runs from there.

use std::collections::VecDeque;

use super::exec::{ExecError, Flow, LabelKey, Machine, Pole, here};
use super::mfunc::MWords;
use super::stmt::Words;
use crate::cycles::{self, Contour, ContourSeg};
use crate::diag::ProgramError;
use crate::op::{CompSide, Feed, Op, OpKind, Pose, SourceLoc};

/// In-plane distance below which two contour points are the same, mm.
const SAME_POINT: f64 = 1e-6;

/// The machine state an SL call puts aside while its contours run.
#[derive(Debug, Clone)]
pub(crate) struct Saved {
    pos: Pose,
    comp: CompSide,
    tangent: Option<[f64; 9]>,
    pole: Option<Pole>,
    feed: Option<f64>,
    last_feed: Option<Feed>,
    held_at: Option<usize>,
    modal_call: bool,
}

/// Collector state of an SL call.
#[derive(Debug, Default)]
pub(crate) struct SlState {
    /// The CYCL CALL block: where its ops go and its M words.
    pub pending: Option<(SourceLoc, Words)>,
    /// Contours collected so far.
    pub collected: Vec<Contour>,
    /// State at the call.
    pub saved: Option<Saved>,
}

impl Machine {
    /// `CYCL CALL` of an SL cycle: asks for the contours of the last cycle 14.
    pub(super) fn sl_call(&mut self, w: &Words, loc: SourceLoc) -> Result<Flow, ExecError> {
        if self.cyc.contours.is_empty() {
            return Err(here(ProgramError::Missing(
                "SL cycle without contour labels: program CYCL DEF 14 first",
            )));
        }
        if self.cyc.p20.is_none() {
            return Err(here(ProgramError::Missing(
                "SL cycle without contour data: program CYCL DEF 20 first",
            )));
        }
        self.cyc.sl.pending = Some((loc, *w));
        Ok(Flow::Contours(
            self.cyc
                .contours
                .iter()
                .map(|n| LabelKey::Num(*n))
                .collect(),
        ))
    }

    /// Puts the machine state aside before the contour subprograms run.
    pub fn begin_contours(&mut self) {
        self.cyc.sl.collected.clear();
        self.cyc.sl.saved = Some(Saved {
            pos: self.pos,
            comp: self.comp,
            tangent: self.tangent,
            pole: self.pole,
            feed: self.feed,
            last_feed: self.last_feed,
            held_at: self.held_at,
            modal_call: self.cyc.modal_call,
        });
        self.held_at = None;
        self.cyc.modal_call = false;
        self.comp = CompSide::Off;
    }

    /// Turns the ops one contour subprogram produced into a contour.
    pub fn end_contour(
        &mut self,
        label: &str,
        scratch: &mut VecDeque<Op>,
    ) -> Result<(), ProgramError> {
        if self.corner.is_some() {
            return Err(ProgramError::Geometry(
                "RND/CHF at the end of a contour subprogram".into(),
            ));
        }
        self.held_at = None;
        let (a, b, _) = self.plane.axes();
        let mut start: Option<[f64; 2]> = None;
        let mut segs = Vec::new();
        let mut left = None;
        let mut last = [0.0; 2];
        for op in scratch.drain(..) {
            match op.kind {
                OpKind::RadiusComp { side } => {
                    left = match side {
                        CompSide::Left => Some(true),
                        CompSide::Right => Some(false),
                        CompSide::Off => None,
                    };
                }
                OpKind::Line { to, .. } => {
                    let p = [to[a], to[b]];
                    if start.is_none() {
                        start = Some(p);
                    } else if (p[0] - last[0]).hypot(p[1] - last[1]) > SAME_POINT {
                        segs.push(ContourSeg::Line { to: p });
                    }
                    last = p;
                }
                OpKind::Arc {
                    from,
                    to,
                    center,
                    plane,
                    sweep,
                    ..
                } => {
                    if plane != self.plane {
                        return Err(ProgramError::Geometry(format!(
                            "contour arc in the {plane:?} plane, the working plane is {:?}",
                            self.plane
                        )));
                    }
                    let s = [from[a], from[b]];
                    if start.is_none() {
                        start = Some(s);
                    }
                    split_arc(s, [to[a], to[b]], center, sweep, &mut segs);
                    last = [to[a], to[b]];
                }
                OpKind::Spline { .. } | OpKind::Approach { .. } | OpKind::Depart { .. } => {
                    return Err(ProgramError::Geometry(
                        "a contour subprogram may only hold lines and arcs (no SPL, APPR, DEP)"
                            .into(),
                    ));
                }
                _ => {}
            }
        }
        let Some(start) = start else {
            return Err(ProgramError::Geometry(format!(
                "contour {label} has no motion"
            )));
        };
        if (start[0] - last[0]).hypot(start[1] - last[1]) > SAME_POINT {
            segs.push(ContourSeg::Line { to: start });
        }
        if segs.is_empty() {
            return Err(ProgramError::Geometry(format!(
                "contour {label} has no elements"
            )));
        }
        self.cyc.sl.collected.push(Contour { start, segs, left });
        self.comp = CompSide::Off;
        Ok(())
    }

    /// Restores the state of the call and, when the contours were collected, runs the SL
    /// cycle on them; ops go to `out`.
    pub fn finish_contours(
        &mut self,
        collected: Result<(), ProgramError>,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ProgramError> {
        if let Some(s) = self.cyc.sl.saved.take() {
            self.pos = s.pos;
            self.comp = s.comp;
            self.tangent = s.tangent;
            self.pole = s.pole;
            self.feed = s.feed;
            self.last_feed = s.last_feed;
            self.held_at = s.held_at;
            self.cyc.modal_call = s.modal_call;
        }
        self.corner = None;
        let pending = self.cyc.sl.pending.take();
        collected?;
        let Some((loc, w)) = pending else {
            return Ok(());
        };
        let contours = std::mem::take(&mut self.cyc.sl.collected);
        let (Some(def), Some(p20)) = (self.cyc.machining.clone(), self.cyc.p20.clone()) else {
            return Ok(());
        };
        let mut ctx = self.cycle_ctx();
        if def.number == 21 {
            // pilot drilling works out where the rough-out tool Q13 will plunge
            use cycles::ParamSource;
            ctx.rough_out_radius = def
                .get(cycles::ParamKey::Q(13))
                .filter(|n| *n >= 0.0 && n.fract() == 0.0 && *n <= f64::from(u32::MAX))
                .and_then(|n| self.tools.get(n as u32))
                .map(|t| t.radius + t.dr);
        }
        let mut moves = Vec::new();
        cycles::generate_sl(def.number, &contours, &p20, &def, &ctx, &mut moves)
            .map_err(|e| self.cycle_error(e))?;
        let mark = out.len();
        let mut emit = |kind: OpKind| out.push_back(Op { kind, loc });
        self.emit_moves(&moves, &mut emit);
        let ms = MWords::classify(&w).map_err(|e| e.1)?;
        ms.motion(self, &w, &mut emit).map_err(|e| e.1)?;
        let _ = ms.after(self, false, &mut emit);
        if let Err(e) = self.check_mapping(out) {
            out.truncate(mark);
            return Err(e.1);
        }
        Ok(())
    }
}

/// Appends an arc as contour elements, split into pieces of at most a half circle.
fn split_arc(s: [f64; 2], e: [f64; 2], c: [f64; 2], sweep: f64, segs: &mut Vec<ContourSeg>) {
    let pieces = (sweep.abs() / 180.0).ceil().max(1.0) as u32;
    let step = (sweep / f64::from(pieces)).to_radians();
    let (r0x, r0y) = (s[0] - c[0], s[1] - c[1]);
    for k in 1..=pieces {
        let to = if k == pieces {
            e
        } else {
            let (sn, cs) = (step * f64::from(k)).sin_cos();
            [c[0] + r0x * cs - r0y * sn, c[1] + r0x * sn + r0y * cs]
        };
        segs.push(ContourSeg::Arc {
            to,
            centre: c,
            ccw: sweep > 0.0,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::klartext::parser::Parser;

    /// Runs contour blocks into a scratch queue and collects them.
    fn contour(blocks: &[&str]) -> Result<Contour, ProgramError> {
        let mut m = Machine::new(Pose::xyz(0.0, 0.0, 50.0));
        let mut p = Parser::default();
        let mut q = VecDeque::new();
        m.begin_contours();
        for b in blocks {
            let block = p.parse(b.as_bytes()).map_err(|e| e.error)?;
            m.exec(&block.stmt, &p, b.as_bytes(), SourceLoc::default(), &mut q)
                .map_err(|e| e.1)?;
        }
        m.end_contour("LBL 1", &mut q)?;
        let c = m.cyc.sl.collected.pop().expect("one contour");
        m.finish_contours(Ok(()), &mut VecDeque::new())?;
        assert_eq!(m.pos, Pose::xyz(0.0, 0.0, 50.0), "state restored");
        Ok(c)
    }

    #[test]
    fn contour_subprogram_becomes_start_segments_and_side() {
        let c = contour(&[
            "L X+10 Y+10 RR F100",
            "L X+10 Y+70",
            "L X+80 Y+70",
            "RND R5",
            "L X+80 Y+10",
        ])
        .expect("collects");
        assert_eq!(c.start, [10.0, 10.0]);
        assert_eq!(c.left, Some(false));
        // line up, line right (shortened by the rounding), the rounding arc (clockwise),
        // line down, and the closing line back to the start
        assert_eq!(c.segs.len(), 5);
        assert_eq!(c.segs[0], ContourSeg::Line { to: [10.0, 70.0] });
        assert_eq!(c.segs[1], ContourSeg::Line { to: [75.0, 70.0] });
        let ContourSeg::Arc { to, centre, ccw } = c.segs[2] else {
            panic!("rounding arc");
        };
        assert!(!ccw);
        assert!((to[0] - 80.0).abs() < 1e-9 && (to[1] - 65.0).abs() < 1e-9);
        assert!((centre[0] - 75.0).abs() < 1e-9 && (centre[1] - 65.0).abs() < 1e-9);
        assert_eq!(c.segs[4], ContourSeg::Line { to: [10.0, 10.0] });
        let circle =
            contour(&["CC X+45 Y+40", "L X+55 Y+40 RL F100", "C X+55 Y+40 DR+"]).expect("collects");
        assert_eq!(circle.start, [55.0, 40.0]);
        assert_eq!(circle.left, Some(true));
        assert_eq!(circle.segs.len(), 2);
        assert!(contour(&["CC X+0 Y+0"]).is_err());
    }

    #[test]
    fn full_circles_split_into_half_arcs() {
        let mut segs = Vec::new();
        split_arc([10.0, 0.0], [10.0, 0.0], [0.0, 0.0], 360.0, &mut segs);
        assert_eq!(segs.len(), 2);
        let ContourSeg::Arc { to, ccw, .. } = segs[0] else {
            panic!("arc");
        };
        assert!(ccw);
        assert!((to[0] + 10.0).abs() < 1e-9 && to[1].abs() < 1e-9);
        segs.clear();
        split_arc([10.0, 0.0], [0.0, 10.0], [0.0, 0.0], -270.0, &mut segs);
        assert_eq!(segs.len(), 2);
        let ContourSeg::Arc { to, ccw, .. } = segs[0] else {
            panic!("arc");
        };
        // half of −270° from (10, 0): −135° → (−7.07, −7.07)
        assert!(!ccw);
        let h = 10.0 / 2f64.sqrt();
        assert!((to[0] + h).abs() < 1e-9 && (to[1] + h).abs() < 1e-9);
    }
}
