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
//! block's motion. Any other M is reported as not supported.

use std::collections::VecDeque;

use super::expr::{ParamKind, ParamRef, Params, Rpn, Value};
use super::geom::{self, P2};
use super::mfunc::MWords;
use super::parser::{Coord, FeedWord, Parser, Stmt, ToolCall, ToolId, Words};
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

/// What happens after a block.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Flow {
    /// Go on with the next block.
    Continue,
    /// The program ended (M2, M30, END PGM).
    End,
}

/// An execution error, located at a byte position of the block (or the block start).
pub(crate) type ExecError = (Option<u32>, ProgramError);

/// The pole / circle centre.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Pole {
    plane: Plane,
    centre: P2,
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
    scale: f64,
    /// Tool axis of the last TOOL CALL (Z by default).
    tool_axis: AxisLetter,
    /// Working plane from the tool axis (CR and CT work in it).
    plane: Plane,
    /// Circle centre / pole from CC, with the plane it was given in.
    pole: Option<Pole>,
    /// Modal feed, mm/s.
    feed: Option<f64>,
    /// FAUTO feed from TOOL CALL, mm/s.
    fauto: Option<f64>,
    /// Active radius compensation.
    comp: CompSide,
    /// Active tool number.
    tool: Option<u32>,
    /// Active tool name, when called by name.
    tool_name: Option<String>,
    /// Spindle state.
    pub(super) spindle: SpindleDir,
    /// Programmed spindle speed, rpm.
    speed: f64,
    /// Coolant state.
    pub(super) coolant: bool,
    /// Direction at the end of the last contour element (for CT).
    tangent: Option<[f64; 9]>,
    /// Q, QL and QR parameters.
    pub params: Params,
    /// Scratch stack for formulas.
    stack: Vec<f64>,
    /// Blank from BLK FORM.
    pub blank: Option<Blank>,
}

/// An execution error located at a word of the block.
pub(super) fn at(pos: u32, e: ProgramError) -> ExecError {
    (Some(pos), e)
}

/// An execution error located at the start of the block.
fn here(e: ProgramError) -> ExecError {
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
        }
    }

    /// Sets the program unit (BEGIN PGM).
    pub fn set_inch(&mut self, inch: bool) {
        self.scale = if inch { 25.4 } else { 1.0 };
    }

    fn length(&self, axis: AxisLetter, v: f64) -> f64 {
        if axis.is_rotary() { v } else { v * self.scale }
    }

    fn resolve(&self, axis: AxisLetter, c: &Coord) -> f64 {
        let v = self.length(axis, self.params.value(c.value));
        if c.incremental { self.pos[axis] + v } else { v }
    }

    /// The end pose from the axis words (unprogrammed axes keep their value).
    fn target(&self, w: &Words) -> Pose {
        let mut p = self.pos;
        for a in AxisLetter::ALL {
            if let Some(c) = &w.axes[a.index()] {
                p[a] = self.resolve(a, c);
            }
        }
        p
    }

    /// Rejects in-plane axis words in polar blocks.
    fn no_plane_axes(w: &Words, plane: Plane, block: &'static str) -> Result<(), ExecError> {
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

    fn feed(&mut self, fw: Option<FeedWord>) -> Result<Option<Feed>, ExecError> {
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
                let mm_s = f * self.feed_scale() / 60.0;
                self.feed = Some(mm_s);
                Ok(Some(Feed::Rate(mm_s)))
            }
            None => Ok(self.feed.or(self.fauto).map(Feed::Rate)),
        }
    }

    /// mm/min per programmed feed unit: 1 in MM, 2.54 in INCH (F in 0.1 inch/min).
    fn feed_scale(&self) -> f64 {
        if self.scale == 1.0 { 1.0 } else { 2.54 }
    }

    /// Runs one statement; `parsed` holds its words and formula, `text` is the block text.
    pub fn exec(
        &mut self,
        stmt: &Stmt,
        parsed: &Parser,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<Flow, ExecError> {
        let mark = out.len();
        let r = self.exec_inner(stmt, parsed, text, loc, out);
        if r.is_err() {
            out.truncate(mark);
        }
        r
    }

    fn exec_inner(
        &mut self,
        stmt: &Stmt,
        parsed: &Parser,
        text: &[u8],
        loc: SourceLoc,
        out: &mut VecDeque<Op>,
    ) -> Result<Flow, ExecError> {
        let w = &parsed.words;
        let code: &[Rpn] = &parsed.code;
        let mut emit = |kind: OpKind| out.push_back(Op { kind, loc });
        match stmt {
            Stmt::Empty | Stmt::Label | Stmt::BeginPgm { .. } => Ok(Flow::Continue),
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
                let words = w;
                if *corner == 0 {
                    return Ok(Flow::Continue);
                }
                let mut b = self.blank.unwrap_or(Blank {
                    axis: None,
                    min: Pose::ZERO,
                    max: Pose::ZERO,
                });
                let mut p = if *corner == 1 { b.min } else { b.max };
                for a in AxisLetter::ALL {
                    if let Some(c) = &words.axes[a.index()] {
                        let v = self.length(a, self.params.value(c.value));
                        // incremental MAX point coordinates are relative to the MIN point
                        p[a] = if c.incremental { b.min[a] + v } else { v };
                    }
                }
                if *corner == 1 {
                    b.min = p;
                    b.axis = axis.or(b.axis);
                } else {
                    b.max = p;
                }
                self.blank = Some(b);
                Ok(Flow::Continue)
            }
            Stmt::Assign { target } => {
                let v = self.params.eval(code, &mut self.stack).map_err(here)?;
                self.params.set(*target, v);
                Ok(Flow::Continue)
            }
            Stmt::ToolCall => {
                self.tool_call(&parsed.tool, text, &mut emit)?;
                Ok(Flow::Continue)
            }
            Stmt::Centre => {
                self.centre(w)?;
                Ok(Flow::Continue)
            }
            Stmt::Misc | Stmt::Stop => {
                let stop = matches!(stmt, Stmt::Stop);
                let ms = MWords::classify(w)?;
                ms.before(self, &mut emit);
                let flow = ms.after(self, stop, &mut emit);
                Ok(flow)
            }
            Stmt::Line
            | Stmt::LinePolar
            | Stmt::Circle
            | Stmt::CircleRadius
            | Stmt::CircleTangent
            | Stmt::CirclePolar => {
                let ms = MWords::classify(w)?;
                let motion = self.motion(stmt, w)?;
                ms.before(self, &mut emit);
                if let Some(side) = w.comp
                    && side != self.comp
                {
                    self.comp = side;
                    emit(OpKind::RadiusComp { side });
                }
                if let Some(m) = motion {
                    self.commit(&m);
                    emit(m);
                }
                Ok(ms.after(self, false, &mut emit))
            }
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
    fn commit(&mut self, m: &OpKind) {
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
            _ => {}
        }
    }

    fn need_feed(&self, f: Option<Feed>) -> Result<Feed, ExecError> {
        f.ok_or_else(|| here(ProgramError::NoFeed))
    }

    fn pole_for(&self, block: &'static str) -> Result<Pole, ExecError> {
        self.pole.ok_or_else(|| here(ProgramError::NoPole(block)))
    }

    fn direction(w: &Words, block: &'static str) -> Result<bool, ExecError> {
        w.dr.map(|(ccw, _)| ccw).ok_or_else(|| {
            here(ProgramError::Missing(match block {
                "C" => "C needs the direction DR+ or DR-",
                "CR" => "CR needs the direction DR+ or DR-",
                _ => "CP needs the direction DR+ or DR-",
            }))
        })
    }

    /// Computes the motion op of a path block (None when nothing moves).
    fn motion(&mut self, stmt: &Stmt, w: &Words) -> Result<Option<OpKind>, ExecError> {
        let feed = self.feed(w.feed)?;
        let from = self.pos;
        match stmt {
            Stmt::Line => {
                let to = self.target(w);
                if to == from {
                    return Ok(None);
                }
                Ok(Some(OpKind::Line {
                    from,
                    to,
                    feed: self.need_feed(feed)?,
                }))
            }
            Stmt::LinePolar => {
                let pole = self.pole_for("LP")?;
                Self::no_plane_axes(w, pole.plane, "LP")?;
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
                if to == from {
                    return Ok(None);
                }
                Ok(Some(OpKind::Line {
                    from,
                    to,
                    feed: self.need_feed(feed)?,
                }))
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
            Stmt::CircleTangent => {
                let plane = self.plane;
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
                let to = self.target(w);
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

    /// CC: sets the pole. The plane follows the two axes programmed (X/Y → XY, Z/X → ZX,
    /// Y/Z → YZ); with one axis or none it is the working plane, and missing coordinates come
    /// from the previous pole in that plane, else from the current position. `I` words are
    /// relative to the last programmed position.
    fn centre(&mut self, w: &Words) -> Result<(), ExecError> {
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
        let prev = self.pole.filter(|p| p.plane == plane);
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

    fn tool_call(
        &mut self,
        tc: &ToolCall,
        text: &[u8],
        emit: &mut impl FnMut(OpKind),
    ) -> Result<(), ExecError> {
        match tc.tool {
            Some(ToolId::Number(v)) => {
                let n = self.params.value(v);
                if !(n >= 0.0 && n.fract() == 0.0 && n <= f64::from(u32::MAX)) {
                    return Err(here(ProgramError::OutOfRange(format!(
                        "tool number {n} is not a whole number from 0 to {}",
                        u32::MAX
                    ))));
                }
                self.tool = Some(n as u32);
                self.tool_name = None;
            }
            Some(ToolId::Name(s, e)) => {
                let name: String = text
                    .get(s..e)
                    .unwrap_or(&[])
                    .iter()
                    .map(|&b| char::from(b))
                    .collect();
                self.tool = Some(0);
                self.tool_name = Some(name);
            }
            None => {}
        }
        if let Some(axis) = tc.axis {
            match Plane::from_tool_axis(axis) {
                Some(p) => {
                    self.tool_axis = axis;
                    self.plane = p;
                }
                None => {
                    return Err(here(ProgramError::NotSupported(format!(
                        "tool axis {axis}"
                    ))));
                }
            }
        }
        let val = |v: Option<Value>| v.map(|v| self.params.value(v));
        let length = val(tc.dl).unwrap_or(0.0) * self.scale;
        let radius = val(tc.dr).unwrap_or(0.0) * self.scale;
        if let Some(f) = val(tc.feed) {
            if !(f > 0.0 && f.is_finite()) {
                return Err(here(ProgramError::OutOfRange(format!(
                    "feed rate F{f} must be positive"
                ))));
            }
            self.fauto = Some(f * self.feed_scale() / 60.0);
        }
        let new_speed = val(tc.speed);
        if let Some(s) = new_speed
            && !(s >= 0.0 && s.is_finite())
        {
            return Err(here(ProgramError::OutOfRange(format!(
                "spindle speed S{s} must not be negative"
            ))));
        }
        emit(OpKind::ToolChange {
            tool: self.tool.unwrap_or(0),
            name: self.tool_name.clone(),
            axis: self.tool_axis,
            length,
            radius,
        });
        // Q108: active tool radius, Q114: active tool length (program units)
        self.params.set(
            ParamRef {
                kind: ParamKind::Q,
                index: 108,
            },
            radius / self.scale,
        );
        self.params.set(
            ParamRef {
                kind: ParamKind::Q,
                index: 114,
            },
            length / self.scale,
        );
        if let Some(s) = new_speed {
            self.speed = s;
            if self.spindle != SpindleDir::Off {
                emit(self.spindle_op());
            }
        }
        Ok(())
    }
}
