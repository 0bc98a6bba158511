//! The cycle arms of the MACHINING dispatch: hole patterns with their drilling and milling
//! cycles (G743–G746, G71, G74, G36, G791, G793) and the contour-based cycles on the
//! FINISHED PART (G31 thread, G810/G820 roughing, G830 contour-parallel, G860/G866/G870
//! recessing, G869 recess turning, G890 finishing).

use std::collections::VecDeque;

use super::{DinExec, whole};
use crate::diag::ProgramError;
use crate::din::cycles;
use crate::din::facemill;
use crate::din::grooving;
use crate::din::lateral;
use crate::din::lathe::{Group, num};
use crate::din::roughing;
use crate::op::{AxisLetter, Op, SourceLoc};
use crate::tnc::exec::ExecError;

impl DinExec {
    /// A hole pattern (G743–G746), the face contour G793, or a drilling/milling cycle
    /// (G71, G74, G36, G791) on the pattern read before it or at the tool's position.
    pub(super) fn pattern_cycle(
        &mut self,
        g: &Group<'_>,
        code: u32,
        number: Option<u64>,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let l = &mut self.lathe;
        let gpos = g.g_word.map(|w| w.pos as u32);
        match code {
            744 | 746 => {
                if !l.c_axis {
                    return Err((
                        gpos,
                        ProgramError::Missing(
                            "a lateral pattern needs the C axis switched on (M14)",
                        ),
                    ));
                }
                if let Some(f) = g.get("F") {
                    l.set_feed(num(f)?, f)?;
                }
                let pattern = if code == 744 {
                    lateral::g744(g, number)?
                } else {
                    lateral::g746(g, number)?
                };
                if pattern.xe.is_some() {
                    let call = lateral::lateral_call(l, g, 71, &pattern)?;
                    let clearance = l.pos[AxisLetter::X];
                    for p in &pattern.points {
                        lateral::run_lateral(l, &call, *p, clearance, loc, out);
                    }
                } else {
                    self.pending_lateral = Some(pattern);
                }
            }
            743 | 745 => {
                if !l.c_axis {
                    return Err((
                        gpos,
                        ProgramError::Missing("a face pattern needs the C axis switched on (M14)"),
                    ));
                }
                let pattern = if code == 743 {
                    cycles::g743(g, number)?
                } else {
                    cycles::g745(g, number)?
                };
                if pattern.ze.is_some() {
                    let call = cycles::cycle_call(l, g, 71, Some(&pattern))?;
                    let clearance = l.pos[AxisLetter::Z];
                    for p in &pattern.points {
                        cycles::run_at(l, &call, Some(*p), clearance, loc, out);
                    }
                } else {
                    self.pending = Some(pattern);
                }
            }
            793 => {
                if !l.c_axis {
                    return Err((
                        gpos,
                        ProgramError::Missing("G793 needs the C axis switched on (M14)"),
                    ));
                }
                if self.pending_lateral.take().is_some() {
                    return Err((
                        gpos,
                        ProgramError::Unexpected(
                            "G793 mills on the face: it cannot follow a lateral pattern".into(),
                        ),
                    ));
                }
                let pattern = self.pending.take();
                self.face_contour = Some(facemill::g793(l, g, pattern)?);
            }
            71 | 74 | 36 | 791 if self.pending_lateral.is_some() => {
                if let Some(p) = self.pending_lateral.take() {
                    let call = lateral::lateral_call(l, g, code, &p)?;
                    let clearance = l.pos[AxisLetter::X];
                    for pt in &p.points {
                        lateral::run_lateral(l, &call, *pt, clearance, loc, out);
                    }
                }
            }
            71 | 74 | 36 | 791 => {
                let pattern = self.pending.take();
                let call = cycles::cycle_call(l, g, code, pattern.as_ref())?;
                let clearance = l.pos[AxisLetter::Z];
                match pattern {
                    Some(p) => {
                        for pt in &p.points {
                            cycles::run_at(l, &call, Some(*pt), clearance, loc, out);
                        }
                    }
                    None => cycles::run_at(l, &call, None, clearance, loc, out),
                }
            }
            // only called with the codes above
            _ => {}
        }
        Ok(())
    }

    /// A cycle on the FINISHED PART contour: G31, G810/G820, G830, G860/G866/G870, G869, G890.
    pub(super) fn contour_cycle(
        &mut self,
        g: &Group<'_>,
        code: u32,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let l = &mut self.lathe;
        let gpos = g.g_word.map(|w| w.pos as u32);
        match code {
            31 => {
                let segs = match g.get("NS") {
                    None => None,
                    Some(w) => {
                        let ne = g.get("NE").map(|w| whole(w, "NE")).transpose()?;
                        let ns = Some(u64::from(whole(w, "NS")?));
                        // without NE: the element NS alone
                        let ne = ne.map(u64::from).or(ns);
                        Some(self.contour.segments(ns, ne).map_err(|e| (gpos, e))?)
                    }
                };
                crate::din::thread_cycle::g31(&mut self.lathe, g, segs, loc, out)?;
            }
            810 | 820 => {
                let allowed: &[&str] = if code == 810 {
                    &["NS", "NE", "P", "I", "K", "Z", "F"]
                } else {
                    &["NS", "NE", "P", "I", "K", "X", "F"]
                };
                Self::check_words(g, allowed, "G810/G820")?;
                let block_of = |addr: &str| -> Result<Option<u64>, ExecError> {
                    match g.get(addr) {
                        None => Ok(None),
                        Some(w) => whole(w, addr).map(|n| Some(u64::from(n))),
                    }
                };
                let (ns, ne) = (block_of("NS")?, block_of("NE")?);
                let p = roughing::params(l, g, code)?;
                let segs = self.contour.segments(ns, ne).map_err(|e| (gpos, e))?;
                roughing::rough(l, &segs, self.blank, &p, loc, out).map_err(|e| (gpos, e))?;
            }
            830 => {
                Self::check_words(g, &crate::din::parallel::G830_WORDS[..], "G830")?;
                let ns = g.get("NS").map(|w| whole(w, "NS")).transpose()?;
                let ne = g.get("NE").map(|w| whole(w, "NE")).transpose()?;
                let (ns, ne) = (ns.map(u64::from), ne.map(u64::from).or(ns.map(u64::from)));
                let p = crate::din::parallel::params(l, g)?;
                let segs = self.contour.segments(ns, ne).map_err(|e| (gpos, e))?;
                crate::din::parallel::rough(l, &segs, self.blank, &p, loc, out)
                    .map_err(|e| (gpos, e))?;
            }
            869 => {
                Self::check_words(g, &crate::din::recess_turn::G869_WORDS[..], "G869")?;
                let ns = g.get("NS").map(|w| whole(w, "NS")).transpose()?;
                let ne = g.get("NE").map(|w| whole(w, "NE")).transpose()?;
                // NS = NE: the one element against its programmed direction
                let against = ns.is_some() && ne == ns;
                let (ns, ne) = (ns.map(u64::from), ne.map(u64::from).or(ns.map(u64::from)));
                let p = crate::din::recess_turn::params(l, g)?;
                let mut segs = self.contour.segments(ns, ne).map_err(|e| (gpos, e))?;
                if against {
                    segs = crate::din::recess_turn::reversed(&segs);
                }
                crate::din::recess_turn::run(l, &segs, &p, loc, out).map_err(|e| (gpos, e))?;
            }
            860 | 866 | 870 => {
                self.recessing(g, code, loc, out)?;
            }
            890 => {
                let block_of = |addr: &str| -> Result<Option<u64>, ExecError> {
                    match g.get(addr) {
                        None => Ok(None),
                        Some(w) => whole(w, addr).map(|n| Some(u64::from(n))),
                    }
                };
                let (ns, ne) = (block_of("NS")?, block_of("NE")?);
                Self::check_words(g, &["NS", "NE", "F"], "G890")?;
                if let Some(f) = g.get("F") {
                    l.set_feed(num(f)?, f)?;
                }
                let feed = l.need_feed().map_err(|(_, e)| (gpos, e))?;
                self.contour
                    .finish(l, ns, ne, feed, loc, out)
                    .map_err(|e| (gpos, e))?;
            }
            // only called with the codes above
            _ => {}
        }
        Ok(())
    }

    /// G860 (contour area), G866/G870 (G22 recess): see `grooving`.
    fn recessing(
        &mut self,
        g: &Group<'_>,
        code: u32,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let gpos = g.g_word.map(|w| w.pos as u32);
        let block_of = |addr: &str| -> Result<Option<u64>, ExecError> {
            match g.get(addr) {
                None => Ok(None),
                Some(w) => whole(w, addr).map(|n| Some(u64::from(n))),
            }
        };
        let l = &mut self.lathe;
        if code == 860 {
            Self::check_words(g, &["NS", "NE", "P", "I", "K", "Q", "E", "F"], "G860")?;
            let (ns, ne) = (block_of("NS")?, block_of("NE")?);
            let a = grooving::area_params(l, g)?;
            let segs = self.contour.segments(ns, ne).map_err(|e| (gpos, e))?;
            grooving::cut_area(l, &segs, &a, loc, out).map_err(|e| (gpos, e))
        } else {
            Self::check_words(g, &["NS", "P", "I", "E", "F"], "G866/G870")?;
            let ns = block_of("NS")?;
            let p = grooving::plunge_params(l, g)?;
            let r = self.contour.recess_of(ns).map_err(|e| (gpos, e))?;
            grooving::cut_recess(l, &r, &p, loc, out).map_err(|e| (gpos, e))
        }
    }
}
