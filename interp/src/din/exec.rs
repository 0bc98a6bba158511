//! Executes the blocks of a MACHINING section: technology words, tool calls, M functions,
//! motion and cycles.
//!
//! A block's words are grouped by G code: each G takes the words that follow it up to the
//! next G (`T7 G197 S1200 G195 F0.2 M104`: S belongs to G197, F to G195); words before the
//! first G are the modal ones (axis words of the modal motion G, F, S). T and M words act
//! wherever they stand. M functions: M3/M4 main spindle, M103/M104 driven tool clockwise /
//! counter-clockwise, M8 coolant, M14 C axis on act at block start; M5, M105, M9, M15 (C
//! axis off) at block end; M0/M1 stop, M30/M2 end after the motion. The speed words of a
//! block (G96/G97 S, G197 S, a bare S) take effect before its M functions wherever they
//! stand, so a spindle switched on and given a speed in one block gets one spindle op with
//! the final speed (`M3 G96 S200` and `G96 S200 M3` are the same), at block start.
//!
//! Technology: G94 F mm/min, G95 F mm/rev (default), G96 S m/min, G97 S rpm, G26 S speed
//! limit (recorded), G197 S driven tool rpm, G195 F mm per driven-tool revolution (turned
//! into mm/s with the G197 speed), G14 Q0–Q4 moves to the tool change point (0 both axes
//! together, 1 X then Z, 2 Z then X, 3 X only, 4 Z only), G110 C turns the C axis at rapid,
//! G4 F dwells F seconds, G40/G41/G42 radius compensation, G890 finishes the FINISHED PART
//! contour (NS/NE: first and last contour block).
//!
//! Patterns and cycles live in their own files: G745 and G743 face patterns with G71, G74,
//! G36 and G791 (`cycles`), G744 and G746 lateral patterns drilling radially (`lateral`),
//! G793 face contour milling (`facemill`), G810/G820 roughing (`roughing`), G860/G866/G870
//! recessing (`grooving`), G869 recess turning (`recess_turn`); their arms of the block
//! dispatch are in `exec/dispatch`.

use std::collections::{HashMap, VecDeque};

use super::block::DinWord;
use super::contour::Contour;
use super::cycles::{self, FacePattern};
use super::facemill::FaceContour;
use super::lateral::LateralPattern;
use super::lathe::{FeedUnit, Group, Lathe, TOOL_CHANGE_POINT, err_at, groups, num};
use super::roughing::Bar;
use crate::diag::ProgramError;
use crate::op::{
    AxisLetter, CompSide, Feed, Op, OpKind, Pose, SourceLoc, SpindleDir, SpindleSpeed,
};
use crate::tnc::exec::ExecError;

mod dispatch;

/// What happens after a block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum DinFlow {
    /// Next block.
    Continue,
    /// M30/M2: the program ends.
    End,
}

/// The lathe with its tool list and the pattern waiting for its cycle.
#[derive(Debug)]
pub(crate) struct DinExec {
    /// Modal lathe state.
    pub lathe: Lathe,
    /// Tool IDs from the TURRET section.
    pub tools: HashMap<u32, String>,
    /// A G743/G745 pattern waiting for the cycle of the next block.
    pub pending: Option<FacePattern>,
    /// A G744/G746 pattern waiting for the cycle of the next block.
    pub pending_lateral: Option<LateralPattern>,
    /// A G793 contour being read, up to its G80.
    pub face_contour: Option<FaceContour>,
    /// The bar blank of the BLANK section (G20).
    pub blank: Option<Bar>,
    /// The FINISHED PART contour.
    pub contour: Contour,
    /// What thread passes remember of the one before.
    pub thread: super::thread::ThreadState,
}

const CYCLES: [u32; 5] = [71, 74, 36, 791, 793];

fn whole(w: &DinWord, what: &str) -> Result<u32, ExecError> {
    let v = num(w)?;
    if v >= 0.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX) {
        Ok(v as u32)
    } else {
        Err(err_at(
            w,
            ProgramError::OutOfRange(format!("{what} needs a whole number")),
        ))
    }
}

/// M functions of one block sorted by when they act.
#[derive(Debug, Default)]
struct MSet {
    main: Option<SpindleDir>,
    driven: Option<SpindleDir>,
    coolant_on: bool,
    c_on: bool,
    main_off: bool,
    driven_off: bool,
    coolant_off: bool,
    c_off: bool,
    stop: bool,
    optional: bool,
    end: bool,
}

impl MSet {
    fn read(words: &[DinWord]) -> Result<MSet, ExecError> {
        let mut m = MSet::default();
        for w in words.iter().filter(|w| w.addr == "M") {
            match whole(w, "M")? {
                0 => m.stop = true,
                1 => m.optional = true,
                2 | 30 => m.end = true,
                3 => m.main = Some(SpindleDir::Cw),
                4 => m.main = Some(SpindleDir::Ccw),
                5 => m.main_off = true,
                8 => m.coolant_on = true,
                9 => m.coolant_off = true,
                14 => m.c_on = true,
                15 => m.c_off = true,
                103 => m.driven = Some(SpindleDir::Cw),
                104 => m.driven = Some(SpindleDir::Ccw),
                105 => m.driven_off = true,
                other => return Err(err_at(w, ProgramError::UnsupportedM(other))),
            }
        }
        Ok(m)
    }
}

impl DinExec {
    /// A lathe at `start`.
    pub fn new(start: Pose) -> Self {
        DinExec {
            lathe: Lathe::new(start),
            tools: HashMap::new(),
            pending: None,
            pending_lateral: None,
            face_contour: None,
            blank: None,
            contour: Contour::new(),
            thread: Default::default(),
        }
    }

    /// Ops that end the program: spindles and coolant off, then End.
    pub fn end_ops(&mut self, loc: SourceLoc, out: &mut VecDeque<Op>) {
        let l = &mut self.lathe;
        if l.main_dir != SpindleDir::Off {
            l.main_dir = SpindleDir::Off;
            out.push_back(Op {
                kind: l.main_spindle_op(),
                loc,
            });
        }
        if l.driven_dir != SpindleDir::Off {
            l.driven_dir = SpindleDir::Off;
            out.push_back(Op {
                kind: l.driven_op(),
                loc,
            });
        }
        if l.coolant {
            l.coolant = false;
            out.push_back(Op {
                kind: OpKind::Coolant { on: false },
                loc,
            });
        }
        out.push_back(Op {
            kind: OpKind::End,
            loc,
        });
    }

    /// Runs one MACHINING block; on error the block's ops are dropped.
    pub fn block(
        &mut self,
        words: &[DinWord],
        number: Option<u64>,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<DinFlow, ExecError> {
        let mark = out.len();
        let r = self.block_inner(words, number, loc, out);
        if r.is_err() {
            out.truncate(mark);
        }
        r
    }

    fn block_inner(
        &mut self,
        words: &[DinWord],
        number: Option<u64>,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<DinFlow, ExecError> {
        if let Some(fc) = self.face_contour.as_mut() {
            if let Some(w) = words.iter().find(|w| w.addr == "T" || w.addr == "M") {
                return Err(err_at(
                    w,
                    ProgramError::Unexpected(
                        "tool call or M function inside a G793 contour (end it with G80)".into(),
                    ),
                ));
            }
            if fc.add(words)?
                && let Some(fc) = self.face_contour.take()
            {
                fc.run(&mut self.lathe, loc, out);
            }
            return Ok(DinFlow::Continue);
        }
        let gs = groups(words)?;
        let has_cycle = gs.iter().any(|g| g.g.is_some_and(|n| CYCLES.contains(&n)));
        if let Some(p) = self.pending.take_if(|_| !has_cycle) {
            let msg = format!(
                "{} has no ZE, so the next block must be a drilling or milling cycle \
                 (G71, G74, G36, G791, G793)",
                cycles::pattern_block(&p)
            );
            return Err((None, ProgramError::Geometry(msg)));
        }
        if let Some(p) = self.pending_lateral.take_if(|_| !has_cycle) {
            let at = p.block.map_or("the pattern".to_string(), |n| {
                format!("the pattern in block {n}")
            });
            let msg = format!(
                "{at} has no XE, so the next block must be a drilling cycle (G71, G74, G36)"
            );
            return Err((None, ProgramError::Geometry(msg)));
        }
        let ms = MSet::read(words)?;
        let emit = |out: &mut VecDeque<Op>, kind: OpKind| out.push_back(Op { kind, loc });
        // the block's speeds first, wherever they stand, so that the spindle starts once
        // with its final speed: `M3 G96 S200` and `G96 S200 M3` give the same single op
        let (main_changed, driven_changed) = self.technology(&gs)?;
        // block start: spindles, coolant, C axis
        if let Some(d) = ms.main {
            self.lathe.main_dir = d;
        }
        if (ms.main.is_some() || main_changed) && self.lathe.main_dir != SpindleDir::Off {
            emit(out, self.lathe.main_spindle_op());
        }
        if ms.c_on {
            self.lathe.c_axis = true;
            emit(out, OpKind::CAxis { on: true });
        }
        if ms.coolant_on {
            self.lathe.coolant = true;
            emit(out, OpKind::Coolant { on: true });
        }
        for w in words.iter().filter(|w| w.addr == "T") {
            let t = whole(w, "T")?;
            emit(
                out,
                OpKind::ToolChange {
                    tool: t,
                    name: self.tools.get(&t).cloned(),
                    axis: AxisLetter::Y,
                    length: 0.0,
                    radius: 0.0,
                },
            );
        }
        if let Some(d) = ms.driven {
            self.lathe.driven_dir = d;
        }
        if (ms.driven.is_some() || driven_changed) && self.lathe.driven_dir != SpindleDir::Off {
            emit(out, self.lathe.driven_op());
        }
        for g in &gs {
            self.group(g, number, loc, out)?;
        }
        if ms.main_off {
            self.lathe.main_dir = SpindleDir::Off;
            emit(out, self.lathe.main_spindle_op());
        }
        if ms.driven_off {
            self.lathe.driven_dir = SpindleDir::Off;
            emit(out, self.lathe.driven_op());
        }
        if ms.coolant_off {
            self.lathe.coolant = false;
            emit(out, OpKind::Coolant { on: false });
        }
        if ms.c_off {
            self.lathe.c_axis = false;
            emit(out, OpKind::CAxis { on: false });
        }
        if ms.end {
            self.end_ops(loc, out);
            return Ok(DinFlow::End);
        }
        if ms.stop {
            emit(out, OpKind::Stop { optional: false });
        } else if ms.optional {
            emit(out, OpKind::Stop { optional: true });
        }
        Ok(DinFlow::Continue)
    }

    /// Applies the speed words of a block (G96/G97 S, G197 S, S of the modal group) before
    /// anything else runs; returns whether the main and the driven spindle speed changed.
    fn technology(&mut self, gs: &[Group<'_>]) -> Result<(bool, bool), ExecError> {
        let l = &mut self.lathe;
        let (mut main, mut driven) = (false, false);
        for g in gs {
            let gpos = g.g_word.map(|w| w.pos as u32);
            match g.g {
                None => {
                    if let Some(s) = g.get("S") {
                        let v = num(s)?;
                        l.main_speed = match l.main_speed {
                            SpindleSpeed::SurfaceSpeed(_)
                            | SpindleSpeed::SurfaceSpeedCapped(..) => SpindleSpeed::SurfaceSpeed(v),
                            SpindleSpeed::Rpm(_) => SpindleSpeed::Rpm(v),
                        };
                        main = true;
                    }
                }
                Some(mode @ (96 | 97)) => {
                    let s = g
                        .value("S")?
                        .ok_or((gpos, ProgramError::Missing("G96/G97 need the speed S")))?;
                    l.main_speed = if mode == 96 {
                        SpindleSpeed::SurfaceSpeed(s)
                    } else {
                        SpindleSpeed::Rpm(s)
                    };
                    main = true;
                }
                Some(197) => {
                    let s = g
                        .value("S")?
                        .ok_or((gpos, ProgramError::Missing("G197 needs the speed S")))?;
                    l.driven_speed = s;
                    if let Some(f) = l.driven_feed
                        && l.feed_unit == FeedUnit::DrivenPerRevolution
                    {
                        l.feed = Some(Feed::Rate(f * s / 60.0));
                    }
                    driven = true;
                }
                _ => {}
            }
        }
        Ok((main, driven))
    }

    fn check_words(g: &Group<'_>, allowed: &[&str], name: &'static str) -> Result<(), ExecError> {
        for w in g.words {
            if w.addr == "M" || w.addr == "T" || allowed.contains(&w.addr.as_str()) {
                continue;
            }
            return Err(err_at(
                w,
                ProgramError::UnknownWord {
                    word: w.addr.clone(),
                    block: name,
                },
            ));
        }
        Ok(())
    }

    fn group(
        &mut self,
        g: &Group<'_>,
        number: Option<u64>,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        const AXES: [&str; 9] = ["X", "Xi", "Z", "Zi", "C", "Ci", "Y", "Yi", "B"];
        let params: Option<(&[&str], &'static str)> = match g.g {
            Some(4) => Some((&["F"], "G4")),
            Some(14) => Some((&["Q"], "G14")),
            Some(26 | 96 | 97 | 197) => Some((&["S"], "speed")),
            Some(94 | 95 | 195) => Some((&["F"], "feed")),
            Some(18 | 40..=42) => Some((&[], "G18/G40/G41/G42")),
            Some(110) => Some((&["C"], "G110")),
            Some(745) => Some((
                &[
                    "XK", "YK", "X", "C", "K", "A", "W", "Wi", "Q", "V", "ZS", "ZE", "F",
                ],
                "G745",
            )),
            Some(743) => Some((
                &[
                    "XK", "YK", "X", "C", "Q", "I", "J", "Ii", "Ji", "A", "R", "Ri", "ZS", "ZE",
                    "F",
                ],
                "G743",
            )),
            Some(744) => Some((
                &["Z", "C", "Q", "K", "Ki", "W", "Wi", "XS", "XE", "F"],
                "G744",
            )),
            Some(746) => Some((
                &[
                    "X", "Z", "C", "K", "A", "W", "Wi", "Q", "V", "XS", "XE", "F",
                ],
                "G746",
            )),
            Some(793) => Some((&["ZS", "ZE", "P", "F"], "G793")),
            Some(33) => Some((&super::thread::G33_WORDS[..], "G33")),
            Some(31) => Some((&super::thread_cycle::G31_WORDS[..], "G31")),
            Some(71 | 36) => Some((&["Z", "ZS", "ZE", "X", "XS", "XE", "F"], "G71/G36")),
            Some(74) => Some((
                &["Z", "ZS", "ZE", "X", "XS", "XE", "P", "I", "B", "J", "F"],
                "G74",
            )),
            Some(791) => Some((&["K", "A", "Z", "ZS", "ZE", "P", "F"], "G791")),
            _ => None,
        };
        if let Some((allowed, name)) = params {
            Self::check_words(g, allowed, name)?;
        }
        let l = &mut self.lathe;
        let gpos = g.g_word.map(|w| w.pos as u32);
        match g.g {
            None => {
                Self::check_words(g, &[&AXES[..], &["F", "S"]].concat(), "DIN")?;
                if let Some(f) = g.get("F") {
                    l.set_feed(num(f)?, f)?;
                }
                if g.words.iter().any(|w| AXES.contains(&w.addr.as_str())) {
                    let motion = l.motion.ok_or((
                        None,
                        ProgramError::Missing("no motion G code (G0, G1, G2, …) programmed yet"),
                    ))?;
                    self.motion(g, motion, loc, out)?;
                }
            }
            Some(code @ (0 | 1 | 2 | 3 | 12 | 13)) => {
                Self::check_words(
                    g,
                    &[&AXES[..], &["F", "S", "I", "K", "R"]].concat(),
                    "G0/G1/G2/G3/G12/G13",
                )?;
                if let Some(f) = g.get("F") {
                    l.set_feed(num(f)?, f)?;
                }
                l.motion = Some(code);
                self.motion(g, code, loc, out)?;
            }
            Some(4) => {
                let f = g
                    .value("F")?
                    .ok_or((gpos, ProgramError::Missing("G4 needs the dwell time F")))?;
                if !(f >= 0.0 && f.is_finite()) {
                    return Err((gpos, ProgramError::OutOfRange(format!("dwell F{f}"))));
                }
                out.push_back(Op {
                    kind: OpKind::Dwell { seconds: f },
                    loc,
                });
            }
            Some(14) => {
                let q = g.value("Q")?.unwrap_or(0.0);
                let (xd, z) = TOOL_CHANGE_POINT;
                let mut x_first = l.pos;
                x_first[AxisLetter::X] = xd / 2.0;
                let mut z_first = l.pos;
                z_first[AxisLetter::Z] = z;
                let mut both = x_first;
                both[AxisLetter::Z] = z;
                if q.fract() != 0.0 {
                    return Err((
                        gpos,
                        ProgramError::OutOfRange(format!("G14 Q{q}: expected 0 to 4")),
                    ));
                }
                let path: &[Pose] = match q as i64 {
                    0 => &[both],
                    1 => &[x_first, both],
                    2 => &[z_first, both],
                    3 => &[x_first],
                    4 => &[z_first],
                    _ => {
                        return Err((
                            gpos,
                            ProgramError::OutOfRange(format!("G14 Q{q}: expected 0 to 4")),
                        ));
                    }
                };
                for p in path {
                    l.line(*p, Feed::Rapid, loc, out);
                }
            }
            Some(18) => {}
            Some(33) => super::thread::g33(l, &mut self.thread, g, loc, out)?,
            Some(code @ (31 | 810 | 820 | 830 | 860 | 866 | 869 | 870 | 890)) => {
                self.contour_cycle(g, code, loc, out)?
            }
            Some(26) => {
                // G26 S: the main spindle's speed limit; under constant surface speed the
                // spindle follows it from here on.
                let limit = g
                    .value("S")?
                    .ok_or((gpos, ProgramError::Missing("G26 needs the speed limit S")))?;
                if !(limit.is_finite() && limit > 0.0) {
                    return Err((
                        g.get("S").map(|w| w.pos as u32).or(gpos),
                        ProgramError::OutOfRange(format!(
                            "G26 speed limit S{limit} must be positive"
                        )),
                    ));
                }
                l.speed_limit = Some(limit);
                if l.main_dir != SpindleDir::Off
                    && matches!(l.main_speed, SpindleSpeed::SurfaceSpeed(_))
                {
                    out.push_back(Op {
                        kind: l.main_spindle_op(),
                        loc,
                    });
                }
            }
            Some(side @ (40..=42)) => {
                let side = match side {
                    40 => CompSide::Off,
                    41 => CompSide::Left,
                    _ => CompSide::Right,
                };
                if side != l.comp {
                    l.comp = side;
                    out.push_back(Op {
                        kind: OpKind::RadiusComp { side },
                        loc,
                    });
                }
            }
            Some(unit @ (94 | 95 | 195)) => {
                l.feed_unit = match unit {
                    94 => FeedUnit::PerMinute,
                    95 => FeedUnit::PerRevolution,
                    _ => FeedUnit::DrivenPerRevolution,
                };
                if let Some(f) = g.get("F") {
                    l.set_feed(num(f)?, f)?;
                }
            }
            // speeds were applied before the block's other words (see `technology`)
            Some(96 | 97 | 197) => {}
            Some(110) => {
                let c = g
                    .value("C")?
                    .ok_or((gpos, ProgramError::Missing("G110 needs the angle C")))?;
                if !l.c_axis {
                    return Err((
                        gpos,
                        ProgramError::Missing("G110 needs the C axis switched on (M14)"),
                    ));
                }
                let mut to = l.pos;
                to[AxisLetter::C] = c;
                l.line(to, Feed::Rapid, loc, out);
            }
            Some(code @ (743..=746 | 71 | 74 | 36 | 791 | 793)) => {
                self.pattern_cycle(g, code, number, loc, out)?
            }
            Some(other) => {
                let name = match other {
                    792 | 794 | 797 | 798 => Some("contour milling cycles other than G793"),
                    72 | 73 => Some("boring and tapping cycles G72/G73"),
                    _ => None,
                };
                return Err((
                    gpos,
                    match name {
                        Some(n) => ProgramError::NotSupported(n.into()),
                        None => ProgramError::UnknownWord {
                            word: format!("G{other}"),
                            block: "MACHINING",
                        },
                    },
                ));
            }
        }
        Ok(())
    }

    fn motion(
        &mut self,
        g: &Group<'_>,
        code: u32,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let l = &mut self.lathe;
        match code {
            0 => {
                let to = l.target(g)?;
                l.line(to, Feed::Rapid, loc, out);
            }
            1 => {
                let to = l.target(g)?;
                if to != l.pos {
                    let f = l.need_feed()?;
                    l.line(to, f, loc, out);
                }
            }
            _ => l.arc(g, code, loc, out)?,
        }
        Ok(())
    }
}
