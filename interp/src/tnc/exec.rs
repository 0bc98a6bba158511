//! Klartext executor: runs parsed blocks against the modal machine state and emits ops.
//!
//! Modal rules implemented (TNC behaviour): coordinates not programmed keep their value; `I`
//! words are relative to the last programmed position; F is modal, FMAX acts for its block
//! only, FAUTO takes the feed of TOOL CALL (also used when no F was ever programmed);
//! R0/RL/RR, the pole CC and the tool stay until changed. INCH programs are converted to mm
//! here: lengths ×25.4, and F — which the TNC takes in 0.1 inch/min in inch programs — ×2.54
//! to mm/min; every feed is then divided by 60 to give mm/s.
//!
//! M functions and their timing within the block (TNC M-function table): M3, M4, M8, M13,
//! M14 act at block start (before the motion); M5 and M9 at block end; M0 (stop, spindle off,
//! coolant off), M1 (optional stop) and M2/M30 (end, spindle off, coolant off) after the
//! block's motion. Other M numbers are the machine's own functions when its configuration
//! lists them (see the `mfunc` module), else they are reported as not supported.

use std::collections::VecDeque;

use super::expr::{ParamKind, ParamRef, Params, Rpn};
use super::geom::{self, P2};
use super::mfunc::MWords;
use super::stmt::{Cond, Coord, FeedWord, LabelRef, Parsed, Stmt, Words};
use super::tools::ToolTable;
use crate::diag::ProgramError;
use crate::op::{
    AxisLetter, CompSide, Feed, Op, OpKind, Plane, Pose, SourceLoc, SpindleDir, SpindleId,
    SpindleSpeed,
};

/// How far (mm) the end point of a C block may lie off the circle through its start point
/// about CC. Coordinates written to three decimals can be off by up to √2·0.5 µm ≈ 0.7 µm,
/// so 1 µm accepts them while catching real mistakes.
pub const C_RADIUS_TOLERANCE: f64 = 0.001;

/// In-plane distance (mm) below which a C end point counts as its start point (full circle).
pub const FULL_CIRCLE_EPS: f64 = 1e-6;

/// Largest |IPA| of a CP block (TNC 640 input limit), degrees.
pub const MAX_IPA: f64 = 99_999.999_9;

/// A jump target as the interpreter looks it up: a label number or a label name.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) enum LabelKey {
    /// `LBL n`.
    Num(u32),
    /// `LBL "name"`.
    Name(String),
}

impl std::fmt::Display for LabelKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LabelKey::Num(n) => write!(f, "LBL {n}"),
            LabelKey::Name(s) => write!(f, "LBL \"{s}\""),
        }
    }
}

impl LabelKey {
    /// The key of a label written in `text`.
    pub fn from_ref(r: LabelRef, text: &[u8]) -> LabelKey {
        match r {
            LabelRef::Num(n) => LabelKey::Num(n),
            LabelRef::Name(s, e) => LabelKey::Name(
                text.get(s as usize..e as usize)
                    .unwrap_or(&[])
                    .iter()
                    .map(|&b| char::from(b))
                    .collect(),
            ),
            LabelRef::Qs(n) => LabelKey::Name(format!("QS{n}")),
        }
    }
}

/// What happens after a block.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Flow {
    /// Go on with the next block.
    Continue,
    /// The program ended (M2, M30, END PGM).
    End,
    /// Continue at a label (FN 9–12).
    Goto(LabelKey),
    /// Call a subprogram (`rep: None`) or repeat a program section `rep` more times.
    Call {
        /// The label.
        label: LabelKey,
        /// Repeats of a section repeat.
        rep: Option<u32>,
    },
    /// Run another program file (CALL PGM), path as written.
    CallPgm(String),
    /// SL cycle call: run these contour subprograms (cycle 14) in collecting mode, then
    /// the cycle ([`Machine::finish_contours`]).
    Contours(Vec<LabelKey>),
    /// A `TCH PROBE` block waits for the machine to measure a probing move: run the block
    /// again once it has ([`super::probe_wait`]).
    ProbeWait,
}

/// An execution error, located at a byte position of the block (or the block start).
pub(crate) type ExecError = (Option<u32>, ProgramError);

/// The pole / circle centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Pole {
    pub(super) plane: Plane,
    pub(super) centre: P2,
}

/// Blank (workpiece) box from BLK FORM.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blank {
    /// Tool axis named in BLK FORM 0.1.
    pub axis: Option<AxisLetter>,
    /// MIN point (mm).
    pub min: Pose,
    /// MAX point (mm).
    pub max: Pose,
}

/// Modal state of a running Klartext program.
#[derive(Debug)]
pub(crate) struct Machine {
    /// Last programmed position (mm, degrees).
    pub pos: Pose,
    /// mm per program unit: 1 (MM) or 25.4 (INCH).
    pub(super) scale: f64,
    /// Tool axis of the last TOOL CALL (Z by default).
    pub(super) tool_axis: AxisLetter,
    /// Working plane from the tool axis (CR and CT work in it).
    pub(super) plane: Plane,
    /// Circle centre / pole from CC, with the plane it was given in.
    pub(super) pole: Option<Pole>,
    /// Modal feed, mm/s.
    pub(super) feed: Option<f64>,
    /// FAUTO feed from TOOL CALL, mm/s.
    pub(super) fauto: Option<f64>,
    /// M136: F is in mm per spindle revolution (M137 ends it).
    pub(super) per_rev: bool,
    /// The last F programmed under M136, mm per revolution.
    pub(super) feed_rev: Option<f64>,
    /// Active radius compensation.
    pub(super) comp: CompSide,
    /// Active tool number.
    pub(super) tool: Option<u32>,
    /// Active tool name, when called by name.
    pub(super) tool_name: Option<String>,
    /// Spindle state.
    pub(super) spindle: SpindleDir,
    /// Programmed spindle speed, rpm.
    pub(super) speed: f64,
    /// Coolant state.
    pub(super) coolant: bool,
    /// Direction at the end of the last contour element (for CT).
    pub(super) tangent: Option<[f64; 9]>,
    /// Q, QL and QR parameters.
    pub params: Params,
    /// Scratch stack for formulas.
    pub(super) stack: Vec<f64>,
    /// Blank from BLK FORM.
    pub blank: Option<Blank>,
    /// Active tool radius including deltas, mm.
    pub(super) tool_radius: f64,
    /// Active tool length including deltas, mm.
    pub(super) tool_length: f64,
    /// Tool table (from the machine configuration and TOOL DEF blocks).
    pub(super) tools: ToolTable,
    /// Feed of the last motion op (APPR LT/LN/CT use it up to PH).
    pub(super) last_feed: Option<Feed>,
    /// Index in the op queue of the last contour element, held back while an RND or CHF
    /// may still change its end point.
    pub held_at: Option<usize>,
    /// RND or CHF waiting for the next contour element.
    pub(super) corner: Option<super::contour::Corner>,
    /// The active tool as written (`7`, `"NAME"`) when no table and no TOOL DEF knows it:
    /// its length and radius are taken as 0.
    pub(super) tool_unknown: Option<String>,
    /// Table length and radius (with table deltas) of the active tool, mm.
    pub(super) tool_base: (f64, f64),
    /// M126: rotary axes take the shorter way.
    pub(super) shortest_rotary: bool,
    /// mm per program unit (public copy for the contour module).
    pub(super) unit: f64,
    /// Travel of the linear machine axes X, Y, Z (M140 MB MAX), when known.
    pub(crate) travel: super::retract::Travel,
    /// A program stop (STOP, M0, M1) has run: the operator may have moved the axes since.
    pub(crate) after_stop: bool,
    /// A position was read (FN 18 ID240/ID270) after a program stop: what is computed from
    /// it is only known at the machine.
    pub(crate) operator_value: bool,
    /// Files the program reads and writes (FN 16 output, FN 26–28 tables).
    pub(super) io: super::system::ProgramIo,
    /// Cycle definitions, transforms and cycle calls.
    pub(crate) cyc: super::cycle_exec::CycleState,
    /// Tilted working plane and TCPM.
    pub(super) tilt: super::plane::PlaneState,
    /// FK free contour elements waiting for data, FPOL pole, solved FK elements.
    pub(super) fk: super::fk_solve::FkState,
    /// Machine-dependent M functions from the machine configuration.
    pub(super) machine_functions: Vec<crate::op::MachineFunctionDef>,
    /// The touch probe and the state of an old-format probing cycle.
    pub(super) probe: super::probe_exec::ProbeState,
}

/// An execution error located at a word of the block.
pub(super) fn at(pos: u32, e: ProgramError) -> ExecError {
    (Some(pos), e)
}

/// An execution error located at the start of the block.
pub(super) fn here(e: ProgramError) -> ExecError {
    (None, e)
}

impl Machine {
    /// A machine standing at `start`, metric, tool axis Z, nothing switched on.
    pub fn new(start: Pose) -> Self {
        Machine {
            pos: start,
            scale: 1.0,
            tool_axis: AxisLetter::Z,
            plane: Plane::XY,
            pole: None,
            feed: None,
            fauto: None,
            per_rev: false,
            feed_rev: None,
            comp: CompSide::Off,
            tool: None,
            tool_name: None,
            spindle: SpindleDir::Off,
            speed: 0.0,
            coolant: false,
            tangent: None,
            params: Params::default(),
            stack: Vec::with_capacity(16),
            blank: None,
            tool_radius: 0.0,
            tool_length: 0.0,
            tools: ToolTable::default(),
            last_feed: None,
            held_at: None,
            corner: None,
            shortest_rotary: false,
            tool_base: (0.0, 0.0),
            tool_unknown: None,
            travel: [None; 3],
            after_stop: false,
            operator_value: false,
            unit: 1.0,
            io: Default::default(),
            cyc: Default::default(),
            tilt: Default::default(),
            fk: Default::default(),
            machine_functions: Vec::new(),
            probe: Default::default(),
        }
    }

    /// Uses `tools` for TOOL CALL from now on.
    pub fn set_tools(&mut self, tools: ToolTable) {
        self.tools = tools;
    }

    /// Releases a held contour element (nothing can change it any more).
    pub fn release(&mut self) {
        self.held_at = None;
    }

    /// Notes that the op at the front of the queue was handed out.
    pub fn popped(&mut self) {
        self.held_at = self.held_at.map(|h| h.saturating_sub(1));
        self.cyc.pre_mapped = self.cyc.pre_mapped.saturating_sub(1);
    }

    /// True when the front of the queue may be handed out.
    pub fn front_ready(&self) -> bool {
        self.held_at != Some(0)
    }

    /// Sets the program unit (BEGIN PGM).
    pub fn set_inch(&mut self, inch: bool) {
        self.scale = if inch { 25.4 } else { 1.0 };
        self.unit = self.scale;
        // Q113: unit of the main program, 0 = MM, 1 = INCH
        self.params.set(
            ParamRef {
                kind: ParamKind::Q,
                index: 113,
            },
            if inch { 1.0 } else { 0.0 },
        );
    }

    pub(super) fn length(&self, axis: AxisLetter, v: f64) -> f64 {
        if axis.is_rotary() { v } else { v * self.scale }
    }

    pub(super) fn resolve(&self, axis: AxisLetter, c: &Coord) -> f64 {
        let v = self.length(axis, self.params.value(c.value));
        if c.incremental {
            self.pos[axis] + v
        } else if self.shortest_rotary && axis.is_rotary() {
            // M126: go the shorter way round to the programmed angle
            let here = self.pos[axis];
            let d = (v - here + 180.0).rem_euclid(360.0) - 180.0;
            here + d
        } else {
            v
        }
    }

    /// The end pose from the axis words (unprogrammed axes keep their value).
    pub(super) fn target(&self, w: &Words) -> Pose {
        let mut p = self.pos;
        for a in AxisLetter::ALL {
            if let Some(c) = &w.axes[a.index()] {
                p[a] = self.resolve(a, c);
            }
        }
        p
    }

    /// Rejects in-plane axis words in polar blocks.
    pub(super) fn no_plane_axes(
        w: &Words,
        plane: Plane,
        block: &'static str,
    ) -> Result<(), ExecError> {
        let (a, b, _) = plane.axes();
        for ax in [a, b] {
            if let Some(c) = &w.axes[ax.index()] {
                return Err(at(
                    c.pos,
                    ProgramError::MisplacedWord {
                        word: ax.to_string(),
                        block,
                    },
                ));
            }
        }
        Ok(())
    }

    pub(super) fn feed(&mut self, fw: Option<FeedWord>) -> Result<Option<Feed>, ExecError> {
        match fw {
            Some(FeedWord::Max) => Ok(Some(Feed::Rapid)),
            Some(FeedWord::Auto) => match self.fauto {
                Some(f) => Ok(Some(Feed::Rate(f))),
                None => Err(here(ProgramError::Missing(
                    "FAUTO without a feed in TOOL CALL",
                ))),
            },
            Some(FeedWord::Value(v)) => {
                let f = self.params.value(v);
                if !(f > 0.0 && f.is_finite()) {
                    return Err(here(ProgramError::OutOfRange(format!(
                        "feed rate F{f} must be positive"
                    ))));
                }
                if self.per_rev {
                    // M136: mm (or inch) per revolution of the spindle.
                    let mm = f * if self.scale == 1.0 { 1.0 } else { 25.4 };
                    self.feed_rev = Some(mm);
                    return Ok(Some(Feed::PerRevolution(mm)));
                }
                let mm_s = f * self.feed_scale() / 60.0;
                self.feed = Some(mm_s);
                Ok(Some(Feed::Rate(mm_s)))
            }
            None if self.per_rev => match self.feed_rev {
                Some(mm) => Ok(Some(Feed::PerRevolution(mm))),
                None => Err(here(ProgramError::Missing(
                    "M136 needs a feed F in mm per revolution",
                ))),
            },
            None => Ok(self.feed.or(self.fauto).map(Feed::Rate)),
        }
    }

    /// mm/min per programmed feed unit: 1 in MM, 2.54 in INCH (F in 0.1 inch/min).
    pub(super) fn feed_scale(&self) -> f64 {
        if self.scale == 1.0 { 1.0 } else { 2.54 }
    }

    /// Runs one statement; `parsed` holds its words and formula, `text` is the block text.
    pub fn exec(
        &mut self,
        stmt: &Stmt,
        parsed: &Parsed,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<Flow, ExecError> {
        let mark = out.len();
        let mut r = self
            .check_m_numbers(stmt, parsed)
            .and_then(|()| self.exec_inner(stmt, parsed, text, loc, out));
        if r.is_ok()
            && let Err(e) = self.check_mapping(out)
        {
            r = Err(e);
        }
        if r.is_ok()
            && let Err(e) = self.check_tilt(out, mark)
        {
            r = Err(e);
        }
        // a probing move that found nothing has run its distance before the program stops
        let probed = matches!(
            r,
            Err((
                _,
                ProgramError::Probe(crate::probe::ProbeError::NotReached { .. })
            ))
        );
        if r.is_err() && !probed {
            out.truncate(mark);
        }
        r
    }

    fn exec_inner(
        &mut self,
        stmt: &Stmt,
        parsed: &Parsed,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<Flow, ExecError> {
        let w = &parsed.words;
        let code: &[Rpn] = &parsed.code;
        let emits = !matches!(
            stmt,
            Stmt::Empty
                | Stmt::Label(_)
                | Stmt::Assign { .. }
                | Stmt::AssignString { .. }
                | Stmt::Table(_)
                | Stmt::Centre
                | Stmt::Round
                | Stmt::Chamfer
                | Stmt::Jump { .. }
                | Stmt::SysRead { .. }
                | Stmt::Print { .. }
                | Stmt::ToolDef { .. }
                | Stmt::BlkForm { .. }
                | Stmt::BeginPgm { .. }
        );
        let path = matches!(
            stmt,
            Stmt::Line
                | Stmt::LinePolar
                | Stmt::Circle
                | Stmt::CircleRadius
                | Stmt::CircleTangent
                | Stmt::CirclePolar
                | Stmt::CircleTangentPolar
        );
        if (emits || matches!(stmt, Stmt::Round | Stmt::Chamfer)) && !matches!(stmt, Stmt::Fk(_)) {
            // a block other than FK ends an FK section
            self.fk_flush(out)?;
        }
        if emits && !path {
            if self.corner.is_some() {
                return Err(here(ProgramError::Geometry(
                    "RND/CHF must be followed by a contour element (L, C, CR, CT, LP, CP, CTP)"
                        .into(),
                )));
            }
            self.release();
        }
        let mut emit = |kind: OpKind| out.push_back(Op { kind, loc });
        match stmt {
            Stmt::Empty | Stmt::Label(_) | Stmt::BeginPgm { .. } => Ok(Flow::Continue),
            Stmt::EndPgm => {
                self.end_ops(&mut emit);
                Ok(Flow::End)
            }
            Stmt::Unsupported { what, number } => {
                Err(here(ProgramError::NotSupported(match number {
                    Some(n) => format!("{what} {n}"),
                    None => (*what).to_string(),
                })))
            }
            Stmt::BlkForm { corner, axis } => {
                self.blk_form(w, *corner, *axis);
                Ok(Flow::Continue)
            }
            Stmt::Assign { target } => {
                let v = self.params.eval(code, &mut self.stack).map_err(here)?;
                self.params.set(*target, v);
                Ok(Flow::Continue)
            }
            Stmt::AssignString { target } => {
                self.assign_string(*target, code, text)?;
                Ok(Flow::Continue)
            }
            Stmt::Table(op) => {
                self.table_op(op, text)?;
                Ok(Flow::Continue)
            }
            Stmt::ToolCall => {
                self.tool_call(&parsed.tool, text, &mut emit)?;
                Ok(Flow::Continue)
            }
            Stmt::ToolDef {
                number,
                length,
                radius,
            } => {
                self.tool_def(*number, *length, *radius)?;
                Ok(Flow::Continue)
            }
            Stmt::Centre => {
                self.centre(w)?;
                Ok(Flow::Continue)
            }
            Stmt::Misc | Stmt::Stop => {
                let stop = matches!(stmt, Stmt::Stop);
                let ms = MWords::classify(w)?;
                ms.modal(self);
                ms.before(self, &mut emit)?;
                ms.motion(self, w, &mut emit)?;
                let flow = ms.after(self, stop, &mut emit);
                Ok(flow)
            }
            Stmt::Round | Stmt::Chamfer => {
                self.corner_request(stmt, w)?;
                Ok(Flow::Continue)
            }
            Stmt::CycleDef { number: 19, sub } => self.cycle19(*sub, parsed, out, loc),
            Stmt::CycleDef { number, sub } => self.cycle_def(*number, *sub, parsed, out, loc),
            Stmt::Plane => self.plane_block(parsed, out, loc),
            Stmt::TouchProbe { number, sub } => self.touch_probe(*number, *sub, parsed, out, loc),
            Stmt::Tcpm { on, mode } => Ok(self.tcpm_block(*on, *mode, out, loc)),
            Stmt::CycleCall { kind } => self.cycle_call(*kind, parsed, out, loc),
            Stmt::PatternDef => self.pattern_def(parsed),
            Stmt::Fk(kind) => self.fk_exec(*kind, &parsed.fk, loc, out),
            Stmt::Spline => {
                let ms = MWords::classify(w)?;
                let op = self.spline(w, &parsed.spline)?;
                ms.before(self, &mut emit)?;
                let fed = self.rotary_feed(&op)?;
                self.commit(&op);
                emit(fed);
                Ok(ms.after(self, false, &mut emit))
            }
            Stmt::ApproachDepart {
                approach,
                kind,
                polar,
            } => {
                let ms = MWords::classify(w)?;
                let op = self.approach_depart(w, *approach, *kind, *polar)?;
                ms.before(self, &mut emit)?;
                emit(op);
                Ok(ms.after(self, false, &mut emit))
            }
            Stmt::CallLbl { .. } | Stmt::CallPgm { .. } | Stmt::Jump { .. } => {
                self.flow(stmt, text)
            }
            Stmt::FnError { code } => {
                let n = self.params.value(*code);
                Err(here(ProgramError::FnError(n)))
            }
            Stmt::Print { file, start, end } => {
                let arg = text
                    .get(*start as usize..*end as usize)
                    .unwrap_or(&[])
                    .iter()
                    .map(|&b| char::from(b))
                    .collect::<String>();
                self.print(*file, &arg)?;
                Ok(Flow::Continue)
            }
            Stmt::SysRead {
                target,
                id,
                nr,
                idx,
            } => {
                let v = self.sysread(*id, *nr, *idx)?;
                // positions read after a program stop are wherever the operator left the axes
                let which = self.params.value(*id);
                if self.after_stop && (which == 240.0 || which == 270.0) {
                    self.operator_value = true;
                }
                self.params.set(*target, v);
                Ok(Flow::Continue)
            }
            Stmt::Line
            | Stmt::LinePolar
            | Stmt::Circle
            | Stmt::CircleRadius
            | Stmt::CircleTangent
            | Stmt::CirclePolar
            | Stmt::CircleTangentPolar => {
                let plain = w.m_count == 0;
                let ms = if plain {
                    MWords::default()
                } else {
                    MWords::classify(w)?
                };
                ms.modal(self);
                let motion = self.motion(stmt, w)?;
                if self.corner.is_some() {
                    let Some(m) = &motion else {
                        return Err(here(ProgramError::Geometry(
                            "RND/CHF must be followed by a block that moves".into(),
                        )));
                    };
                    let m = self.resolve_corner(m, out)?;
                    self.release();
                    return self.finish_path(m, w, ms, plain, loc, out);
                }
                self.release();
                match motion {
                    Some(m) => self.finish_path(m, w, ms, plain, loc, out),
                    None => {
                        let mut emit = |kind: OpKind| out.push_back(Op { kind, loc });
                        if !plain {
                            ms.before(self, &mut emit)?;
                        }
                        if let Some(side) = w.comp
                            && side != self.comp
                        {
                            self.comp = side;
                            emit(OpKind::RadiusComp { side });
                        }
                        if self.cyc.modal_call && w.axes_set != 0 {
                            // M89 after a positioning block that is already there
                            self.call_machining(&mut emit)?;
                        }
                        if plain {
                            return Ok(Flow::Continue);
                        }
                        ms.motion(self, w, &mut emit)?;
                        Ok(ms.after(self, false, &mut emit))
                    }
                }
            }
        }
    }

    /// Emits the M functions, compensation change and motion of a path block; the motion
    /// becomes the held contour element.
    #[inline(always)]
    pub(super) fn finish_path(
        &mut self,
        m: OpKind,
        w: &Words,
        ms: MWords,
        plain: bool,
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<Flow, ExecError> {
        let mut emit = |kind: OpKind| out.push_back(Op { kind, loc });
        if !plain {
            ms.before(self, &mut emit)?;
        }
        if let Some(side) = w.comp
            && side != self.comp
        {
            self.comp = side;
            emit(OpKind::RadiusComp { side });
        }
        let fed = self.rotary_feed(&m)?;
        self.commit(&m);
        let contour = matches!(fed, OpKind::Line { .. } | OpKind::Arc { .. });
        out.push_back(Op { kind: fed, loc });
        if contour {
            self.held_at = Some(out.len() - 1);
        }
        if self.cyc.modal_call {
            // M89: the cycle runs after every positioning block
            let mut emit = |kind: OpKind| out.push_back(Op { kind, loc });
            self.call_machining(&mut emit)?;
        }
        if plain {
            return Ok(Flow::Continue);
        }
        let mut emit = |kind: OpKind| out.push_back(Op { kind, loc });
        ms.motion(self, w, &mut emit)?;
        Ok(ms.after(self, false, &mut emit))
    }

    /// BLK FORM: records the blank corners.
    fn blk_form(&mut self, words: &Words, corner: u8, axis: Option<AxisLetter>) {
        if corner == 0 {
            return;
        }
        let mut b = self.blank.unwrap_or(Blank {
            axis: None,
            min: Pose::ZERO,
            max: Pose::ZERO,
        });
        let mut p = if corner == 1 { b.min } else { b.max };
        for a in AxisLetter::ALL {
            if let Some(c) = &words.axes[a.index()] {
                let v = self.length(a, self.params.value(c.value));
                // incremental MAX point coordinates are relative to the MIN point
                p[a] = if c.incremental { b.min[a] + v } else { v };
            }
        }
        if corner == 1 {
            b.min = p;
            b.axis = axis.or(b.axis);
        } else {
            b.max = p;
        }
        self.blank = Some(b);
    }

    /// Label, calls and jumps: tells the interpreter where to go on.
    fn flow(&mut self, stmt: &Stmt, text: &[u8]) -> Result<Flow, ExecError> {
        match stmt {
            Stmt::CallLbl { label, rep } => {
                let key = self.label_key(*label, text)?;
                let rep = match rep {
                    None => None,
                    Some(v) => {
                        // A repeat count taken from a Q parameter counts whole repeats: the
                        // fraction of a computed count (`Q9 = 71 / 2` → REPQ9) is dropped, as
                        // the control takes the parameter as an integer count. A count
                        // written as a number must be whole (the parser sees to that).
                        let mut n = self.params.value(*v);
                        if matches!(v, super::expr::Value::Param { .. }) && n >= 0.0 {
                            n = n.trunc();
                        }
                        if !(n >= 0.0 && n.fract() == 0.0 && n <= 65_534.0) {
                            return Err(here(ProgramError::OutOfRange(format!(
                                "REP {n} is not a whole number from 0 to 65534"
                            ))));
                        }
                        Some(n as u32)
                    }
                };
                if key == LabelKey::Num(0) {
                    return Err(here(ProgramError::Geometry(
                        "CALL LBL 0 is not allowed: LBL 0 ends a subprogram".into(),
                    )));
                }
                Ok(Flow::Call { label: key, rep })
            }
            Stmt::CallPgm { start, end } => Ok(Flow::CallPgm(
                text.get(*start as usize..*end as usize)
                    .unwrap_or(&[])
                    .iter()
                    .map(|&b| char::from(b))
                    .collect(),
            )),
            Stmt::Jump { a, cond, b, label } => {
                let (x, y) = (self.params.value(*a), self.params.value(*b));
                let jump = match cond {
                    Cond::Equ => x == y,
                    Cond::Ne => x != y,
                    Cond::Gt => x > y,
                    Cond::Lt => x < y,
                };
                Ok(if jump {
                    Flow::Goto(self.label_key(*label, text)?)
                } else {
                    Flow::Continue
                })
            }
            _ => Ok(Flow::Continue),
        }
    }

    /// Emits spindle and coolant off when they are on.
    pub(super) fn spindle_coolant_off(&mut self, emit: &mut impl FnMut(OpKind)) {
        if self.spindle != SpindleDir::Off {
            self.spindle = SpindleDir::Off;
            emit(self.spindle_op());
        }
        if self.coolant {
            self.coolant = false;
            emit(OpKind::Coolant { on: false });
        }
    }

    pub(super) fn end_ops(&mut self, emit: &mut impl FnMut(OpKind)) {
        self.tilt.m116 = false;
        self.spindle_coolant_off(emit);
        emit(OpKind::End);
    }

    pub(super) fn spindle_op(&self) -> OpKind {
        OpKind::Spindle {
            spindle: SpindleId::Main,
            dir: self.spindle,
            speed: SpindleSpeed::Rpm(self.speed),
        }
    }

    /// Updates position and end tangent after a motion op.
    pub(super) fn commit(&mut self, m: &OpKind) {
        if let OpKind::Line { feed, .. } | OpKind::Arc { feed, .. } | OpKind::Spline { feed, .. } =
            m
        {
            self.last_feed = Some(*feed);
        }
        match m {
            OpKind::Line { from, to, .. } => {
                let mut d = [0.0; 9];
                for (i, v) in d.iter_mut().enumerate() {
                    *v = to.0[i] - from.0[i];
                }
                if d.iter().any(|v| *v != 0.0) {
                    self.tangent = Some(d);
                }
                self.pos = *to;
            }
            OpKind::Arc {
                to,
                center,
                plane,
                sweep,
                ..
            } => {
                let (a, b, _) = plane.axes();
                let t = geom::arc_end_tangent(*center, [to[a], to[b]], *sweep);
                let mut d = [0.0; 9];
                d[a.index()] = t[0];
                d[b.index()] = t[1];
                self.tangent = Some(d);
                self.pos = *to;
            }
            OpKind::Spline { to, axes, .. } => {
                // direction of travel at the end (t = 0): -K1 per axis
                let mut d = [0.0; 9];
                for ax in axes {
                    d[ax.axis.index()] = -ax.k[2];
                }
                self.tangent = d.iter().any(|v| *v != 0.0).then_some(d);
                self.pos = *to;
            }
            _ => {}
        }
    }

    pub(super) fn need_feed(&self, f: Option<Feed>) -> Result<Feed, ExecError> {
        f.ok_or_else(|| here(ProgramError::NoFeed))
    }

    pub(super) fn pole_for(&self, block: &'static str) -> Result<Pole, ExecError> {
        self.pole.ok_or_else(|| here(ProgramError::NoPole(block)))
    }
}
