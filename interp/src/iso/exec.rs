//! TNC ISO executor: maps each ISO block onto the Klartext statement with the same meaning and
//! runs it on the Klartext machine, so both dialects produce the same ops.
//!
//! Mapping (TNC ISO → Klartext): G00 → `L … FMAX` (modal in ISO, so every G00 block is
//! rapid); G01 → `L`; G02/G03 with an end point → `C DR-`/`C DR+` about the pole; G02/G03
//! with `R` → `CR`; G05 → `C` in the last direction; G06 → `CT`; G10/G11 → `LP` with `R` as
//! PR and `H` as PA; G12/G13 → `CP DR-`/`CP DR+` with `H` as PA; G15 → `CP` in the last
//! direction; G16 → `CTP`; G24 R → `CHF`, G25 R → `RND`. `I J K` are the pole (CC) in X Y Z, modal, given in any block (also alone);
//! G29 makes the last position the pole. G90/G91 switch absolute/incremental input for all
//! coordinates, the pole and the polar values (modal). G40/G41/G42 → R0/RL/RR. `T n G17 S…`
//! → `TOOL CALL n Z S…` (G18 → Y, G19 → X; DL/DR deltas); G99 `T n L… R…` → `TOOL DEF n
//! L… R…`. G30/G31 → BLK FORM 0.1/0.2.
//! G43/G44 → `R+`/`R-` in that block: the one-axis move is lengthened (G43) or shortened
//! (G44) by the tool radius. G26 R… / G27 R… (tangential approach / departure on an arc of
//! radius R) are blocks of their own: G26 follows the block of the first contour point (the
//! first block with G41/G42), G27 the block of the last contour element; both round the
//! corner between the uncompensated approach (departure) line and that contour element
//! with a tangent arc of radius R, which is `RND R…` at the same place in Klartext.
//! Transformations (G28, G53, G54, G72, G73, G80), cycle definitions (`G2nn`) and the cycle
//! call G79 are in [`super::cycles`].
//! D00–D08 and D13 are FN 0–8/13 (`D01 Q6 P01 +Q5 P02 +Q108`), D09–D12 the conditional
//! jumps FN 9–12 to a G98 label. G04 F… dwells F seconds, G38 stops. M functions act as in
//! Klartext.

use std::collections::VecDeque;

use super::block::{Addr, IsoBlock, IsoWord};
use crate::diag::ProgramError;
use crate::klartext::parser::{Coord, FeedWord, MAX_M, Parser, Stmt, ToolCall, ToolId, Words};
use crate::op::{AxisLetter, CompSide, Op, OpKind, SourceLoc};
use crate::tnc::exec::{ExecError, Flow, Machine};
use crate::tnc::expr::Value;

/// What the runner does after a block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum IsoFlow {
    /// Next block.
    Continue,
    /// M02/M30: the program ends.
    End,
    /// `G98 L n`: a label (n = 0 ends a subprogram).
    Label(u32),
    /// `L n,0`: call the subprogram at label n.
    Call(u32),
    /// `L n,k`: repeat the section from label n k more times.
    Repeat(u32, u32),
    /// D09–D12 condition met: continue at label n.
    Goto(u32),
}

/// What the G words of a block say besides the motion.
#[derive(Debug, Clone, Copy)]
struct BlockFlags {
    /// A motion G is written in this block.
    g_here: bool,
    /// G40/G41/G42.
    comp: Option<CompSide>,
    /// G38: stop after the block.
    stop: bool,
    /// The block calls a tool (T).
    tool_call: bool,
    /// G43 (true: lengthen) / G44 (false: shorten) with the word position.
    paraxial: Option<(bool, u32)>,
}

/// The modal motion G code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Motion {
    Rapid,
    Line,
    ArcCw,
    ArcCcw,
    ArcLast,
    ArcTangent,
    PolarRapid,
    PolarLine,
    PolarCw,
    PolarCcw,
    PolarLast,
    PolarTangent,
}

/// Modal ISO state kept next to the Klartext machine.
#[derive(Debug)]
pub(crate) struct IsoState {
    /// The Klartext machine that produces the ops.
    pub machine: Machine,
    pub(super) parser: Parser,
    motion: Option<Motion>,
    incremental: bool,
    /// Direction of the last arc: true for counter-clockwise.
    last_ccw: Option<bool>,
    /// Tool axis chosen by the last G17/G18/G19.
    pub(super) axis: AxisLetter,
    /// A cycle definition whose `Q…=` lines are still being read.
    pub(super) open_cycle: Option<super::cycles::OpenCycle>,
    /// Where the head block of a cycle definition that failed stands: its error is reported
    /// there, not at the line that completed the definition.
    pub(super) failed_head: Option<SourceLoc>,
}

pub(super) fn err(pos: u32, e: ProgramError) -> ExecError {
    (Some(pos), e)
}

pub(super) fn letter(w: &IsoWord) -> Option<u8> {
    match w.addr {
        Addr::Letter(c) => Some(c),
        _ => None,
    }
}

/// A whole non-negative number from a literal word value (G, M, L, D numbers).
pub(super) fn code(w: &IsoWord, what: &str) -> Result<u32, ExecError> {
    match w.value {
        Value::Num(v) if v >= 0.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX) => Ok(v as u32),
        _ => Err(err(
            w.pos,
            ProgramError::OutOfRange(format!("{what} needs a whole number")),
        )),
    }
}

/// Names of ISO functions recognised but not run by this version.
fn unsupported_g(g: u32) -> Option<&'static str> {
    Some(match g {
        7 => "G07 paraxial positioning",
        51 => "G51 next tool",
        _ if (37..=39).contains(&g) || (55..=59).contains(&g) || (74..=78).contains(&g) => {
            "old HEIDENHAIN ISO cycles"
        }
        _ if (85..=89).contains(&g) => "old HEIDENHAIN ISO cycles",
        _ if g >= 200 => "a cycle definition G2nn after other words (it starts its block)",
        _ => return None,
    })
}

/// Copies the M words of a block into Klartext words; returns how many there are.
pub(super) fn m_words(b: &IsoBlock, words: &mut Words) -> Result<usize, ExecError> {
    let mut n_m = 0usize;
    for w in b.words.iter().filter(|w| letter(w) == Some(b'M')) {
        let m = code(w, "M")?;
        if n_m >= MAX_M {
            return Err(err(
                w.pos,
                ProgramError::OutOfRange(format!("more than {MAX_M} M words in one block")),
            ));
        }
        if let (Some(slot), Some(p)) = (words.m.get_mut(n_m), words.m_pos.get_mut(n_m)) {
            *slot = m;
            *p = w.pos;
        }
        n_m += 1;
    }
    words.m_count = n_m as u8;
    Ok(n_m)
}

/// A value with the byte position of its word.
type Placed = (Value, u32);

/// The path feed F of a block and the F written directly after M128 (the feed of its
/// compensating moves, as in Klartext), with its position; any other second F is refused.
fn feed_words(b: &IsoBlock) -> Result<(Option<Value>, Option<Placed>), ExecError> {
    let (mut feed, mut m128_feed) = (None, None);
    let mut after_m128 = false;
    for w in &b.words {
        if letter(w) == Some(b'F') {
            if after_m128 && m128_feed.is_none() {
                m128_feed = Some((w.value, w.pos));
            } else if feed.is_none() {
                feed = Some(w.value);
            } else {
                return Err(err(w.pos, ProgramError::DuplicateWord("F".into())));
            }
        }
        after_m128 = letter(w) == Some(b'M') && w.value == Value::Num(128.0);
    }
    Ok((feed, m128_feed))
}

impl IsoState {
    /// A fresh state on a machine standing at `start`.
    pub fn new(machine: Machine) -> Self {
        IsoState {
            machine,
            parser: Parser::default(),
            motion: None,
            incremental: false,
            last_ccw: None,
            axis: AxisLetter::Z,
            open_cycle: None,
            failed_head: None,
        }
    }

    /// True while G91 (incremental input) is active.
    pub(super) fn incremental(&self) -> bool {
        self.incremental
    }

    /// Runs a formula block: the Klartext parser reads `Q… = …` once the closing `*` is blanked.
    pub fn formula(
        &mut self,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let mut copy = text.to_vec();
        let end = super::block::words_end(text);
        if copy.get(end) == Some(&b'*')
            && let Some(b) = copy.get_mut(end)
        {
            *b = b' ';
        }
        let block = self
            .parser
            .parse(&copy)
            .map_err(|pe| (Some(pe.pos as u32), pe.error))?;
        match block.stmt {
            Stmt::Assign { .. } => {
                self.machine
                    .exec(&block.stmt, &self.parser, &copy, loc, out)?;
                Ok(())
            }
            _ => Err((
                None,
                ProgramError::Unexpected("text in a Q parameter formula".into()),
            )),
        }
    }

    /// Runs a block of address words.
    pub fn words(
        &mut self,
        b: &IsoBlock,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<IsoFlow, ExecError> {
        let mark = out.len();
        let mirror = b
            .words
            .iter()
            .any(|w| letter(w) == Some(b'G') && w.value == Value::Num(28.0));
        if let Some(w) = b.words.iter().find(|w| w.bare && !mirror) {
            return Err(err(
                w.pos,
                ProgramError::MissingValue(
                    letter(w).map_or(String::new(), |c| char::from(c).to_string()),
                ),
            ));
        }
        let r = self.words_inner(b, text, loc, out);
        if r.is_err() {
            out.truncate(mark);
        }
        r
    }

    fn words_inner(
        &mut self,
        b: &IsoBlock,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<IsoFlow, ExecError> {
        let mut motion_here = None;
        let mut corner = None;
        let mut plane_axis = None;
        let mut comp = None;
        let mut label_def = false;
        let mut tool_def = false;
        let mut pole_from_pos = false;
        let mut blank = None;
        let mut dwell = false;
        let mut stop = false;
        let mut paraxial = None;
        let mut transform = None;
        let mut cycle_call = false;
        let mut old_cycle = None;
        if let Some(w) = b
            .words
            .iter()
            .find(|w| matches!(letter(w), Some(b'E' | b'N' | b'O')))
        {
            return Err(err(
                w.pos,
                ProgramError::UnknownWord {
                    word: letter(w).map_or(String::new(), |c| char::from(c).to_string()),
                    block: "ISO",
                },
            ));
        }
        for w in b.words.iter().filter(|w| letter(w) == Some(b'G')) {
            let g = code(w, "G")?;
            match g {
                0 => motion_here = Some(Motion::Rapid),
                1 => motion_here = Some(Motion::Line),
                2 => motion_here = Some(Motion::ArcCw),
                3 => motion_here = Some(Motion::ArcCcw),
                5 => motion_here = Some(Motion::ArcLast),
                6 => motion_here = Some(Motion::ArcTangent),
                10 => motion_here = Some(Motion::PolarRapid),
                11 => motion_here = Some(Motion::PolarLine),
                12 => motion_here = Some(Motion::PolarCw),
                13 => motion_here = Some(Motion::PolarCcw),
                15 => motion_here = Some(Motion::PolarLast),
                16 => motion_here = Some(Motion::PolarTangent),
                24 => corner = Some(Stmt::Chamfer),
                // G26/G27: a rounding arc between the uncompensated approach (departure)
                // line and the first (last) compensated contour element, like G25
                25..=27 => corner = Some(Stmt::Round),
                43 => paraxial = Some((true, w.pos)),
                44 => paraxial = Some((false, w.pos)),
                28 | 53 | 54 | 62 | 72 | 73 | 80 => {
                    if transform.is_some() {
                        return Err(err(
                            w.pos,
                            ProgramError::Unexpected(
                                "two coordinate transformations in one block".into(),
                            ),
                        ));
                    }
                    transform = Some((g, w.pos));
                }
                79 => cycle_call = true,
                83 | 84 => old_cycle = Some(g),
                17 => plane_axis = Some(AxisLetter::Z),
                18 => plane_axis = Some(AxisLetter::Y),
                19 => plane_axis = Some(AxisLetter::X),
                20 => {
                    return Err(err(
                        w.pos,
                        ProgramError::NotSupported("G20 (tool axis other than X, Y, Z)".into()),
                    ));
                }
                29 => pole_from_pos = true,
                30 => blank = Some(1u8),
                31 => blank = Some(2u8),
                4 => dwell = true,
                38 => stop = true,
                40 => comp = Some(CompSide::Off),
                41 => comp = Some(CompSide::Left),
                42 => comp = Some(CompSide::Right),
                70 | 71 => {
                    return Err(err(
                        w.pos,
                        ProgramError::Unexpected(
                            "G70/G71 outside the `%NAME` block: the unit is set once".into(),
                        ),
                    ));
                }
                90 => self.incremental = false,
                91 => self.incremental = true,
                98 => label_def = true,
                99 => tool_def = true,
                other => {
                    return Err(err(
                        w.pos,
                        match unsupported_g(other) {
                            Some(name) => ProgramError::NotSupported(name.into()),
                            None => ProgramError::UnknownWord {
                                word: format!("G{other}"),
                                block: "ISO",
                            },
                        },
                    ));
                }
            }
        }
        if let Some(a) = plane_axis {
            self.axis = a;
        }
        if let Some((g, pos)) = transform {
            self.transform(g, pos, b, text, loc, out)?;
            return Ok(IsoFlow::Continue);
        }
        if cycle_call {
            return self.cycle_call(b, text, loc, out);
        }
        if let Some(g) = old_cycle {
            self.old_cycle(g, b, text, loc, out)?;
            return Ok(IsoFlow::Continue);
        }
        let find = |c: u8| b.words.iter().find(|w| letter(w) == Some(c));
        if label_def {
            let l = find(b'L').ok_or((None, ProgramError::Missing("G98 needs a label L")))?;
            return Ok(IsoFlow::Label(code(l, "L")?));
        }
        if tool_def {
            // G99 T… L… R…: TOOL DEF with length and radius
            let t = find(b'T').ok_or((None, ProgramError::Missing("G99 needs a tool T")))?;
            let stmt = Stmt::ToolDef {
                number: Some(t.value),
                length: find(b'L').map(|w| w.value),
                radius: find(b'R').map(|w| w.value),
            };
            self.exec(&stmt, text, loc, out)?;
            return Ok(IsoFlow::Continue);
        }
        if let Some(d) = find(b'D') {
            return self.d_function(b, d, loc, out);
        }
        if let Some(l) = find(b'L') {
            let n = code(l, "L")?;
            let count = l.count.unwrap_or(0.0);
            if count < 0.0 || count.fract() != 0.0 || count > 65_535.0 {
                return Err(err(
                    l.pos,
                    ProgramError::OutOfRange(format!("repeat count {count} out of range")),
                ));
            }
            return Ok(if count == 0.0 {
                IsoFlow::Call(n)
            } else {
                IsoFlow::Repeat(n, count as u32)
            });
        }
        if dwell {
            let f = find(b'F').ok_or((None, ProgramError::Missing("G04 needs the time F")))?;
            let s = self.machine.params.value(f.value);
            if !(s >= 0.0 && s.is_finite()) {
                return Err(err(
                    f.pos,
                    ProgramError::OutOfRange(format!("dwell time {s} s")),
                ));
            }
            out.push_back(Op {
                kind: OpKind::Dwell { seconds: s },
                loc,
            });
            return Ok(IsoFlow::Continue);
        }
        if let Some(stmt) = corner {
            // G24 R… chamfer / G25 R… rounding between the neighbouring contour elements
            let r = find(b'R').ok_or((None, ProgramError::Missing("G24/G25 need the size R")))?;
            let mut words = Words {
                radius: Some((r.value, r.pos)),
                ..Words::default()
            };
            words.feed = find(b'F').map(|w| FeedWord::Value(w.value));
            self.parser.words = words;
            self.exec(&stmt, text, loc, out)?;
            return Ok(IsoFlow::Continue);
        }
        if let Some(corner) = blank {
            let mut words = Words::default();
            self.axes_into(b, &mut words)?;
            self.parser.words = words;
            let axis = (corner == 1).then_some(self.axis);
            self.exec(&Stmt::BlkForm { corner, axis }, text, loc, out)?;
            return Ok(IsoFlow::Continue);
        }
        let tool_call = find(b'T').is_some();
        if let Some(t) = find(b'T') {
            self.tool_call(b, t, text, loc, out)?;
        } else if find(b'S').is_some() {
            // a speed without T: same tool, new speed (TOOL CALL S…)
            let s = find(b'S').map(|w| w.value);
            self.parser.tool = ToolCall {
                speed: s,
                ..ToolCall::default()
            };
            self.exec(&Stmt::ToolCall, text, loc, out)?;
        }
        // the pole: I J K, or G29
        let pole_words: Vec<&IsoWord> = b
            .words
            .iter()
            .filter(|w| matches!(letter(w), Some(b'I' | b'J' | b'K')))
            .collect();
        if !pole_words.is_empty() || pole_from_pos {
            let mut words = Words::default();
            for w in &pole_words {
                let axis = match letter(w) {
                    Some(b'I') => AxisLetter::X,
                    Some(b'J') => AxisLetter::Y,
                    _ => AxisLetter::Z,
                };
                words.set_axis(
                    axis,
                    Coord {
                        value: w.value,
                        incremental: self.incremental,
                        pos: w.pos,
                    },
                );
            }
            if pole_from_pos {
                if !pole_words.is_empty() {
                    return Err((
                        None,
                        ProgramError::Unexpected("G29 together with I, J or K".into()),
                    ));
                }
                // zero increments: the last position in both axes of the working plane
                let (a, c, _) = crate::op::Plane::from_tool_axis(self.axis)
                    .unwrap_or(crate::op::Plane::XY)
                    .axes();
                for ax in [a, c] {
                    words.set_axis(
                        ax,
                        Coord {
                            value: Value::Num(0.0),
                            incremental: true,
                            pos: 0,
                        },
                    );
                }
            }
            self.parser.words = words;
            self.exec(&Stmt::Centre, text, loc, out)?;
        }
        if let Some(m) = motion_here {
            self.motion = Some(m);
        }
        let flags = BlockFlags {
            g_here: motion_here.is_some(),
            comp,
            stop,
            tool_call,
            paraxial,
        };
        self.motion_block(b, flags, text, loc, out)
    }

    /// Copies the axis words of a block into Klartext words.
    pub(super) fn axes_into(&self, b: &IsoBlock, words: &mut Words) -> Result<(), ExecError> {
        for w in &b.words {
            let Some(c) = letter(w) else { continue };
            let Some(axis) = AxisLetter::from_char(char::from(c)) else {
                continue;
            };
            if words.axes[axis.index()].is_some() {
                return Err(err(
                    w.pos,
                    ProgramError::DuplicateWord(char::from(c).to_string()),
                ));
            }
            words.set_axis(
                axis,
                Coord {
                    value: w.value,
                    incremental: self.incremental,
                    pos: w.pos,
                },
            );
        }
        Ok(())
    }

    fn motion_block(
        &mut self,
        b: &IsoBlock,
        flags: BlockFlags,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<IsoFlow, ExecError> {
        let BlockFlags {
            g_here,
            comp,
            stop,
            tool_call,
            paraxial,
        } = flags;
        let mut words = Words::default();
        self.axes_into(b, &mut words)?;
        words.comp = comp;
        words.paraxial = paraxial;
        let n_m = m_words(b, &mut words)?;
        let find = |c: u8| b.words.iter().find(|w| letter(w) == Some(c));
        let (feed, m128_feed) = feed_words(b)?;
        words.m128_feed = m128_feed;
        // in a T block F is the tool's automatic feed (FAUTO), not a path feed
        let feed = feed.filter(|_| !tool_call).map(FeedWord::Value);
        let radius = find(b'R');
        let angle = find(b'H');
        let has_axes = words.axes.iter().any(Option::is_some);
        let motion = self.motion;
        let polar = matches!(
            motion,
            Some(
                Motion::PolarRapid
                    | Motion::PolarLine
                    | Motion::PolarCw
                    | Motion::PolarCcw
                    | Motion::PolarLast
                    | Motion::PolarTangent
            )
        );
        let has_pole_words = b
            .words
            .iter()
            .any(|w| matches!(letter(w), Some(b'I' | b'J' | b'K')));
        // A block moves when it programs an end point, a polar value, or writes an arc G
        // without a pole (a full circle about the current pole).
        let moves = has_axes
            || (polar && (radius.is_some() || angle.is_some()))
            || (g_here
                && !has_pole_words
                && matches!(
                    motion,
                    Some(Motion::ArcCw | Motion::ArcCcw | Motion::ArcLast)
                ));
        if !moves {
            if let Some(r) = radius {
                return Err(err(
                    r.pos,
                    ProgramError::MisplacedWord {
                        word: "R".into(),
                        block: "ISO block without motion",
                    },
                ));
            }
            if feed.is_some() || comp.is_some() {
                // modal feed or compensation without motion: an L block without axes
                words.feed = feed;
                self.parser.words = words;
                self.exec(&Stmt::Line, text, loc, out)?;
                return Ok(self.after_stop(stop, loc, out));
            }
            if n_m > 0 || stop {
                self.parser.words = words;
                let flow =
                    self.exec(if stop { &Stmt::Stop } else { &Stmt::Misc }, text, loc, out)?;
                return Ok(if flow == Flow::End {
                    IsoFlow::End
                } else {
                    IsoFlow::Continue
                });
            }
            return Ok(IsoFlow::Continue);
        }
        let Some(motion) = motion else {
            return Err((
                None,
                ProgramError::Missing("no motion G code (G00, G01, G02, …) programmed yet"),
            ));
        };
        let polar_coord = |w: &IsoWord| Coord {
            value: w.value,
            incremental: self.incremental,
            pos: w.pos,
        };
        let stmt = match motion {
            Motion::Rapid | Motion::Line => {
                if let Some(w) = radius.or(angle) {
                    return Err(err(
                        w.pos,
                        ProgramError::MisplacedWord {
                            word: letter(w).map_or(String::new(), |c| char::from(c).to_string()),
                            block: "G00/G01",
                        },
                    ));
                }
                if motion == Motion::Rapid {
                    if feed.is_some() {
                        // F in a rapid block only sets the modal feed
                        let mut fw = Words {
                            feed,
                            ..Words::default()
                        };
                        fw.m_count = 0;
                        self.parser.words = fw;
                        self.exec(&Stmt::Line, text, loc, out)?;
                    }
                    words.feed = Some(FeedWord::Max);
                } else {
                    words.feed = feed;
                }
                Stmt::Line
            }
            Motion::ArcCw | Motion::ArcCcw | Motion::ArcLast => {
                words.feed = feed;
                let ccw = self.direction(motion)?;
                words.dr = Some((ccw, 0));
                match radius {
                    Some(r) => {
                        words.radius = Some((r.value, r.pos));
                        Stmt::CircleRadius
                    }
                    None => Stmt::Circle,
                }
            }
            Motion::ArcTangent => {
                words.feed = feed;
                Stmt::CircleTangent
            }
            Motion::PolarRapid | Motion::PolarLine => {
                words.feed = if motion == Motion::PolarRapid {
                    Some(FeedWord::Max)
                } else {
                    feed
                };
                words.pr = radius.map(polar_coord);
                words.pa = angle.map(polar_coord);
                Stmt::LinePolar
            }
            Motion::PolarTangent => {
                words.feed = feed;
                words.pr = radius.map(polar_coord);
                words.pa = angle.map(polar_coord);
                Stmt::CircleTangentPolar
            }
            Motion::PolarCw | Motion::PolarCcw | Motion::PolarLast => {
                words.feed = feed;
                let ccw = self.direction(motion)?;
                words.dr = Some((ccw, 0));
                if let Some(r) = radius {
                    return Err(err(
                        r.pos,
                        ProgramError::MisplacedWord {
                            word: "R".into(),
                            block: "G12/G13/G15",
                        },
                    ));
                }
                words.pa = angle.map(polar_coord);
                Stmt::CirclePolar
            }
        };
        if matches!(stmt, Stmt::Circle | Stmt::CircleRadius | Stmt::CirclePolar)
            && let Some((ccw, _)) = words.dr
        {
            self.last_ccw = Some(ccw);
        }
        self.parser.words = words;
        let flow = self.exec(&stmt, text, loc, out)?;
        if flow == Flow::End {
            return Ok(IsoFlow::End);
        }
        Ok(self.after_stop(stop, loc, out))
    }

    pub(super) fn after_stop(&self, stop: bool, loc: SourceLoc, out: &mut VecDeque<Op>) -> IsoFlow {
        if stop {
            out.push_back(Op {
                kind: OpKind::Stop { optional: false },
                loc,
            });
        }
        IsoFlow::Continue
    }

    fn direction(&self, motion: Motion) -> Result<bool, ExecError> {
        match motion {
            Motion::ArcCw | Motion::PolarCw => Ok(false),
            Motion::ArcCcw | Motion::PolarCcw => Ok(true),
            _ => self.last_ccw.ok_or((
                None,
                ProgramError::Missing("G05/G15 need an earlier arc with a direction"),
            )),
        }
    }

    pub(super) fn exec(
        &mut self,
        stmt: &Stmt,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<Flow, ExecError> {
        self.machine.exec(stmt, &self.parser, text, loc, out)
    }

    fn tool_call(
        &mut self,
        b: &IsoBlock,
        t: &IsoWord,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<(), ExecError> {
        let find = |a: Addr| b.words.iter().find(|w| w.addr == a);
        let tc = ToolCall {
            tool: Some(ToolId::Number(t.value)),
            axis: Some(self.axis),
            speed: find(Addr::Letter(b'S')).map(|w| w.value),
            feed: find(Addr::Letter(b'F')).map(|w| w.value),
            dl: find(Addr::Dl).map(|w| w.value),
            dr: find(Addr::Dr).map(|w| w.value),
            dr2: None,
        };
        self.parser.tool = tc;
        self.exec(&Stmt::ToolCall, text, loc, out)?;
        Ok(())
    }
}
