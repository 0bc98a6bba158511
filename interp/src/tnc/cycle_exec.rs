//! Running cycle blocks: DEF-active transforms and functions, machining cycle definitions
//! and their calls (`CYCL CALL`, `CYCL CALL POS`, `CYCL CALL PAT`, M99, M89), patterns.
//!
//! Rules this executor follows (TNC cycle descriptions, in short):
//! - DEF-active cycles act when their block runs: 7 datum shift, 8 mirror image, 10 rotation,
//!   11 scaling, 26 axis-specific scaling, 247 datum setting (preset), 9 dwell, 32 tolerance,
//!   220/221 point patterns (they call the last defined machining cycle at once).
//! - A datum shift `7.n` sets the named axes (absolute) or adds to them (`IX…`); axes a
//!   definition does not name keep their shift. `7.1 #n` takes row n of the datum table.
//!   `X+0 Y+0 Z+0` resets. Mirror `8.1` lists the mirrored axes (none: off); the tool axis
//!   cannot be mirrored. Rotation `10.1 ROT` (absolute) / `IROT` (added) turns the working
//!   plane about the datum; `ROT+0` resets. Scaling `11.1 SCL f` scales X, Y and Z about the
//!   datum (`SCL 1` resets); `26.1` scales the named axes about CCX/CCY/CCZ. Cycles 11 and 26
//!   replace each other. Cycle 247 activates preset `Q339` from the preset table and, as on
//!   the control, cancels datum shift, mirror, rotation and scaling.
//! - A transform change re-expresses the current position in the new system, so axes not
//!   programmed in the next block stay where they are on the machine.
//! - Current-format definitions write their values into the Q parameters of the same
//!   numbers (Q200 of cycle 200 is the global Q200 afterwards).
//! - Call-active cycles run on `CYCL CALL`, after the motion of a block with M99, after
//!   every positioning block while M89 is active (a new machining cycle definition or M99
//!   ends M89), at the points of `PATTERN DEF` with `CYCL CALL PAT`, and at the position of
//!   `CYCL CALL POS`, where the tool-axis coordinate acts as an additional shift of the
//!   surface coordinate Q203. To reach that position the tool first moves in the working
//!   plane and then along the tool axis when it is above the target, else the other way
//!   round, with radius compensation off.
//! - Cycle parameters are in program units as written; INCH programs are not converted
//!   for machining cycles yet.

use std::collections::VecDeque;

use super::cycle_table::DatumTable;
use super::cycle_words::{CallKind, CycleValue, OldItem};
use super::exec::{ExecError, Flow, Machine, at, here};
use super::expr::{ParamKind, ParamRef};
use super::mfunc::MWords;
use super::stmt::Parsed;
use super::transform::Transform;
use crate::cycles::{self, CycleContext, CycleError, CycleFeed, Move, P3, ParamKey, ParamSource};
use crate::diag::ProgramError;
use crate::op::{AxisLetter, CompSide, Feed, Op, OpKind, SourceLoc};

/// The generator behind cycle calls (the real one, or a stand-in in tests).
pub(crate) type Generator =
    fn(u32, &dyn ParamSource, &CycleContext, &mut Vec<Move>) -> Result<(), CycleError>;

/// A defined cycle: its number and parameter values.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct CycleDef {
    /// Cycle number.
    pub number: u32,
    /// Values by key.
    pub params: Vec<(ParamKey, f64)>,
}

impl ParamSource for CycleDef {
    fn get(&self, key: ParamKey) -> Option<f64> {
        self.params.iter().find(|(k, _)| *k == key).map(|(_, v)| *v)
    }
}

/// Cycle and transform state of a running program.
#[derive(Debug)]
pub(crate) struct CycleState {
    /// Active transforms.
    pub xf: Transform,
    /// Ops at the front of the op queue already in machine coordinates.
    pub pre_mapped: usize,
    /// `xf` is the identity (kept with it, so the per-op test is one flag).
    pub identity: bool,
    /// The last defined call-active cycle.
    pub machining: Option<CycleDef>,
    /// M89 is active.
    pub modal_call: bool,
    /// Datum table for `7.1 #n`.
    pub datums: Option<DatumTable>,
    /// Preset table for cycle 247.
    pub presets: Option<DatumTable>,
    /// The preset table row active now (start preset or cycle 247), if any.
    pub active_preset: Option<i64>,
    /// Points of the last PATTERN DEF, program coordinates `[a, b, surface]`.
    pub pattern: Vec<P3>,
    /// Contour labels of the last cycle 14.
    pub contours: Vec<u32>,
    /// The last cycle 20 (contour data).
    pub p20: Option<CycleDef>,
    /// Machining cycle generator.
    pub generator: Generator,
    /// SL contours: collector state while the contour subprograms run.
    pub sl: super::cycle_sl::SlState,
}

impl Default for CycleState {
    fn default() -> Self {
        CycleState {
            xf: Transform::default(),
            pre_mapped: 0,
            identity: true,
            machining: None,
            modal_call: false,
            datums: None,
            presets: None,
            active_preset: None,
            pattern: Vec::new(),
            contours: Vec::new(),
            p20: None,
            generator: cycles::generate,
            sl: Default::default(),
        }
    }
}

/// DEF-active cycles handled here rather than by the generators.
fn is_def_active(n: u32) -> bool {
    matches!(n, 7 | 8 | 9 | 10 | 11 | 14 | 20 | 26 | 32 | 247) || cycles::is_pattern(n)
}

/// SL cycles that machine the contours of cycle 14.
pub(super) fn is_sl_call(n: u32) -> bool {
    matches!(n, 21..=24)
}

fn cycle_err(e: CycleError) -> ExecError {
    here(ProgramError::Cycle(e))
}

impl Machine {
    /// A cycle's error as the program should hear it: a cycle that cannot use a zero tool
    /// radius because the called tool is in no tool table says so.
    pub(super) fn cycle_error(&self, e: CycleError) -> ProgramError {
        match (&e, &self.tool_unknown) {
            (CycleError::ToolRadius { cycle, radius }, Some(tool)) if *radius == 0.0 => {
                ProgramError::UnknownToolRadius {
                    tool: tool.clone(),
                    cycle: *cycle,
                }
            }
            _ => ProgramError::Cycle(e),
        }
    }

    /// Uses `table` for `CYCL DEF 7.1 #n`.
    pub fn set_datum_table(&mut self, table: DatumTable) {
        self.cyc.datums = Some(table);
    }

    /// Uses `table` for cycle 247.
    pub fn set_preset_table(&mut self, table: DatumTable) {
        self.cyc.presets = Some(table);
    }

    /// Makes row `nr` of the preset table the active preset at program start, as the preset
    /// the operator activated on the machine: program coordinates count from it, and the
    /// position the machine stands at is re-expressed in them. `false` (nothing changed)
    /// when there is no such row.
    pub fn activate_preset(&mut self, nr: i64) -> bool {
        let Some(row) = self.cyc.presets.as_ref().and_then(|t| t.row(nr)).copied() else {
            return false;
        };
        let rot = self.cyc.presets.as_ref().map_or(0.0, |t| t.rot(nr));
        let machine = self.cyc.xf.map_point(&self.pos);
        for (p, v) in self.cyc.xf.preset.iter_mut().zip(row.iter()) {
            *p = v.unwrap_or(0.0);
        }
        self.cyc.xf.basic_rot = rot;
        self.cyc.active_preset = Some(nr);
        self.pos = self.cyc.xf.unmap_point(&machine);
        self.cyc.identity = self.cyc.xf.is_identity();
        true
    }

    /// Maps an op leaving the queue to machine coordinates (unless it was mapped when the
    /// transforms changed).
    pub fn output(&self, op: Op) -> Op {
        if self.cyc.pre_mapped > 0 || self.cyc.identity {
            return op;
        }
        match self.cyc.xf.map_op(&op.kind) {
            Ok(kind) => Op { kind, loc: op.loc },
            Err(_) => op, // refused when the block ran (check_mapping)
        }
    }

    /// Checks that the queued ops of the block can be mapped (arcs under axis-specific
    /// scaling or out-of-plane rotation cannot).
    pub(super) fn check_mapping(&self, out: &VecDeque<Op>) -> Result<(), ExecError> {
        if self.cyc.identity {
            return Ok(());
        }
        for op in out.iter().skip(self.cyc.pre_mapped) {
            self.cyc
                .xf
                .map_op(&op.kind)
                .map_err(|m| here(ProgramError::Transform(m)))?;
        }
        Ok(())
    }

    /// Makes `new` the active transform: maps what is queued with the old one, and
    /// re-expresses the position in the new system.
    pub(super) fn set_transform(&mut self, new: Transform, out: &mut VecDeque<Op>, loc: SourceLoc) {
        let old = self.cyc.xf;
        if old == new {
            return;
        }
        if !old.is_identity() {
            for op in out.iter_mut().skip(self.cyc.pre_mapped) {
                if let Ok(k) = old.map_op(&op.kind) {
                    op.kind = k;
                }
            }
        }
        self.cyc.pre_mapped = out.len();
        let machine = old.map_point(&self.pos);
        self.pos = new.unmap_point(&machine);
        self.cyc.xf = new;
        self.cyc.identity = new.is_identity();
        if self.comp != CompSide::Off && old.flips(old.plane) != new.flips(new.plane) {
            // mirroring changed the side: tell compensation (mapped with the new transform)
            out.push_back(Op {
                kind: OpKind::RadiusComp { side: self.comp },
                loc,
            });
        }
    }

    pub(super) fn item_value(&self, it: &OldItem) -> Option<f64> {
        it.value.map(|v| self.params.value(v))
    }

    /// `CYCL DEF n…` blocks.
    pub(super) fn cycle_def(
        &mut self,
        number: u32,
        sub: Option<u8>,
        parsed: &Parsed,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Result<Flow, ExecError> {
        match sub {
            Some(0) => self.old_head(number),
            Some(s) => self.old_sub(number, s, &parsed.cycle.items, out, loc),
            None => self.new_def(number, parsed, out, loc),
        }
        .map(|()| Flow::Continue)
    }

    fn old_head(&mut self, number: u32) -> Result<(), ExecError> {
        if is_def_active(number) {
            return Ok(());
        }
        if !cycles::is_call_active(number) && !is_sl_call(number) {
            // a later call must not run the cycle defined before this one
            self.cyc.machining = None;
            return Err(cycle_err(CycleError::Unknown(number)));
        }
        self.cyc.machining = Some(CycleDef {
            number,
            params: Vec::new(),
        });
        self.cyc.modal_call = false;
        Ok(())
    }

    fn old_sub(
        &mut self,
        number: u32,
        sub: u8,
        items: &[OldItem],
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Result<(), ExecError> {
        let mut xf = self.cyc.xf;
        xf.plane = self.plane;
        match number {
            7 => self.datum_shift(&mut xf, items)?,
            8 => self.mirror(&mut xf, items)?,
            10 => {
                for it in items {
                    let v = self.item_value(it).unwrap_or(0.0);
                    match it.word() {
                        b"ROT" => xf.rot = v,
                        b"IROT" => xf.rot += v,
                        _ => return Err(word_err(it, "10 (ROT or IROT)")),
                    }
                }
                xf.rot = xf.rot.rem_euclid(360.0);
            }
            11 => {
                for it in items {
                    match it.word() {
                        b"SCL" | b"" => {
                            let f = self.item_value(it).unwrap_or(1.0);
                            check_factor(f, it)?;
                            xf.scale = [f; 3];
                            xf.centre = [0.0; 3];
                        }
                        _ => return Err(word_err(it, "11 (SCL)")),
                    }
                }
            }
            26 => {
                let mut scale = [1.0; 3];
                let mut centre = [0.0; 3];
                for it in items {
                    let w = it.word();
                    let v = self.item_value(it).unwrap_or(0.0);
                    let axis = |s: &[u8]| match s {
                        b"X" => Some(0usize),
                        b"Y" => Some(1),
                        b"Z" => Some(2),
                        _ => None,
                    };
                    if let Some(i) = axis(w) {
                        check_factor(v, it)?;
                        scale[i] = v;
                    } else if let Some(i) = w.strip_prefix(b"CC").and_then(axis) {
                        centre[i] = v * self.unit;
                    } else {
                        return Err(word_err(it, "26 (X, Y, Z, CCX, CCY, CCZ)"));
                    }
                }
                xf.scale = scale;
                xf.centre = centre;
            }
            9 => {
                let t = items
                    .iter()
                    .find_map(|it| self.item_value(it))
                    .unwrap_or(0.0);
                if !(t >= 0.0 && t.is_finite()) {
                    return Err(here(ProgramError::OutOfRange(format!(
                        "dwell time {t} s must not be negative"
                    ))));
                }
                out.push_back(Op {
                    kind: OpKind::Dwell { seconds: t },
                    loc,
                });
                return Ok(());
            }
            32 => {
                if sub == 1 {
                    let t = items
                        .iter()
                        .find(|it| matches!(it.word(), b"T" | b""))
                        .and_then(|it| self.item_value(it));
                    let mm = match t {
                        Some(t) if t >= 0.0 && t.is_finite() => Some(t * self.unit),
                        Some(t) => {
                            return Err(here(ProgramError::OutOfRange(format!(
                                "tolerance T{t} must not be negative"
                            ))));
                        }
                        None => None,
                    };
                    out.push_back(Op {
                        kind: OpKind::Tolerance { mm },
                        loc,
                    });
                }
                return Ok(());
            }
            14 => {
                self.cyc.contours = items
                    .iter()
                    .filter_map(|it| self.item_value(it))
                    .filter(|v| *v >= 0.0 && v.fract() == 0.0)
                    .map(|v| v as u32)
                    .collect();
                return Ok(());
            }
            _ => return self.old_params(number, sub, items),
        }
        self.set_transform(xf, out, loc);
        Ok(())
    }

    fn old_params(&mut self, number: u32, sub: u8, items: &[OldItem]) -> Result<(), ExecError> {
        let feed_scale = self.feed_scale();
        let mut vals = Vec::with_capacity(items.len());
        let mut index = 0u8;
        for it in items {
            match it.word() {
                b"F" => {
                    let f = self.item_value(it).unwrap_or(0.0);
                    vals.push((ParamKey::OldWord("F"), f * feed_scale / 60.0));
                    vals.push((ParamKey::OldFeed { line: sub }, f * feed_scale / 60.0));
                }
                b"DR" => {
                    let neg = it.sign_only.unwrap_or(false)
                        || self.item_value(it).is_some_and(|v| v < 0.0);
                    vals.push((ParamKey::OldWord("DR"), if neg { -1.0 } else { 1.0 }));
                }
                _ => {
                    if let Some(v) = self.item_value(it) {
                        vals.push((ParamKey::Old { line: sub, index }, v));
                        index = index.saturating_add(1);
                    }
                }
            }
        }
        match self.cyc.machining.as_mut() {
            Some(def) if def.number == number => {
                def.params.extend(vals);
                Ok(())
            }
            _ => Err(here(ProgramError::Missing(
                "old-format cycle sub-block without its head block CYCL DEF n.0",
            ))),
        }
    }

    fn datum_shift(&self, xf: &mut Transform, items: &[OldItem]) -> Result<(), ExecError> {
        for it in items {
            let w = it.word();
            if w == b"#" {
                let n = self.item_value(it).unwrap_or(-1.0);
                let Some(table) = &self.cyc.datums else {
                    return Err(at(
                        it.pos,
                        ProgramError::NoTable {
                            table: "datum",
                            row: n,
                            key: "datum_table",
                        },
                    ));
                };
                let row = (n.fract() == 0.0 && n.abs() < 1e15)
                    .then(|| table.row(n as i64))
                    .flatten()
                    .ok_or(at(
                        it.pos,
                        ProgramError::NoDatumRow {
                            table: "datum",
                            row: n,
                        },
                    ))?;
                for (s, v) in xf.shift.iter_mut().zip(row.iter()) {
                    if let Some(v) = v {
                        *s = *v;
                    }
                }
                continue;
            }
            let (inc, letter) = match w {
                [l] => (false, *l),
                [b'I', l] => (true, *l),
                _ => return Err(word_err(it, "7 (axis words or #row)")),
            };
            let axis = AxisLetter::from_char(char::from(letter))
                .ok_or_else(|| word_err(it, "7 (axis words or #row)"))?;
            let v = self.length(axis, self.item_value(it).unwrap_or(0.0));
            let slot = &mut xf.shift[axis.index()];
            *slot = if inc { *slot + v } else { v };
        }
        Ok(())
    }

    fn mirror(&self, xf: &mut Transform, items: &[OldItem]) -> Result<(), ExecError> {
        let mut m = [false; 3];
        for it in items {
            let idx = match it.word() {
                b"X" => 0,
                b"Y" => 1,
                b"Z" => 2,
                _ => return Err(word_err(it, "8 (X, Y or Z)")),
            };
            if idx == self.tool_axis.index() {
                return Err(at(
                    it.pos,
                    ProgramError::Transform(format!(
                        "the tool axis {} cannot be mirrored",
                        self.tool_axis
                    )),
                ));
            }
            m[idx] = true;
        }
        xf.mirror = m;
        Ok(())
    }

    /// The Q assignments of a current-format definition, evaluated; each is also set as
    /// the Q parameter of its number (as the TNC does).
    pub(super) fn read_q_def(
        &mut self,
        number: u32,
        parsed: &Parsed,
    ) -> Result<CycleDef, ExecError> {
        let mut def = CycleDef {
            number,
            params: Vec::with_capacity(parsed.cycle.q.len()),
        };
        for e in &parsed.cycle.q {
            let v = match e.value {
                CycleValue::Val(v) => self.params.value(v),
                CycleValue::Auto => match self.fauto {
                    Some(f) => f * 60.0,
                    None => {
                        return Err(at(
                            e.pos,
                            ProgramError::Missing("AUTO feed without a feed in TOOL CALL"),
                        ));
                    }
                },
                CycleValue::Max => f64::INFINITY,
                CycleValue::Predef => continue,
            };
            let q = ParamRef {
                kind: ParamKind::Q,
                index: e.q,
            };
            self.params.set(q, if v.is_finite() { v } else { 99_999.0 });
            def.params.retain(|(k, _)| *k != ParamKey::Q(e.q));
            def.params.push((ParamKey::Q(e.q), v));
        }
        Ok(def)
    }

    fn new_def(
        &mut self,
        number: u32,
        parsed: &Parsed,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Result<(), ExecError> {
        let def = self.read_q_def(number, parsed)?;
        match number {
            247 => {
                let n = def.get(ParamKey::Q(339)).unwrap_or(0.0);
                let mut xf = Transform {
                    plane: self.plane,
                    ..Transform::default()
                };
                match &self.cyc.presets {
                    Some(t) => {
                        let row = (n.fract() == 0.0 && n.abs() < 1e15)
                            .then(|| t.row(n as i64))
                            .flatten()
                            .ok_or(here(ProgramError::NoDatumRow {
                                table: "preset",
                                row: n,
                            }))?;
                        for (p, v) in xf.preset.iter_mut().zip(row.iter()) {
                            *p = v.unwrap_or(0.0);
                        }
                        xf.basic_rot = t.rot(n as i64);
                        self.cyc.active_preset = Some(n as i64);
                    }
                    None if n == 0.0 => {}
                    None => {
                        return Err(here(ProgramError::NoTable {
                            table: "preset",
                            row: n,
                            key: "preset_table",
                        }));
                    }
                }
                self.set_transform(xf, out, loc);
                Ok(())
            }
            20 => {
                self.cyc.p20 = Some(def);
                Ok(())
            }
            n if cycles::is_pattern(n) => {
                let Some(m) = self.cyc.machining.clone() else {
                    return Err(here(ProgramError::NoCycle("pattern cycle")));
                };
                let ctx = self.cycle_ctx();
                let mut moves = Vec::new();
                cycles::generate_pattern(n, &def, m.number, &m, &ctx, &mut moves)
                    .map_err(cycle_err)?;
                let mut emit = |kind: OpKind| out.push_back(Op { kind, loc });
                self.emit_moves(&moves, &mut emit);
                Ok(())
            }
            n if cycles::is_call_active(n) || is_sl_call(n) => {
                self.cyc.machining = Some(def);
                self.cyc.modal_call = false;
                Ok(())
            }
            n => {
                self.cyc.machining = None;
                Err(cycle_err(CycleError::Unknown(n)))
            }
        }
    }

    /// What the generators need to know about the machine now.
    pub(super) fn cycle_ctx(&self) -> CycleContext {
        let (a, b, n) = self.plane.axes();
        CycleContext {
            pos: [self.pos[a], self.pos[b], self.pos[n]],
            tool_radius: self.tool_radius,
            spindle_rpm: self.speed,
            spindle: self.spindle,
            feed: self.feed,
            rough_out_radius: None,
        }
    }

    /// Runs the last defined machining cycle at the current position (CYCL CALL, M99,
    /// M89).
    pub(super) fn call_machining(
        &mut self,
        emit: &mut impl FnMut(OpKind),
    ) -> Result<(), ExecError> {
        self.call_with(emit, None, None)
    }

    /// Runs the machining cycle; `surface_shift` is added to Q203 (CYCL CALL POS),
    /// `points` runs it at pattern points instead of here.
    fn call_with(
        &mut self,
        emit: &mut impl FnMut(OpKind),
        surface_shift: Option<f64>,
        points: Option<&[P3]>,
    ) -> Result<(), ExecError> {
        let Some(def) = self.cyc.machining.clone() else {
            return Err(here(ProgramError::NoCycle("cycle call")));
        };
        if is_sl_call(def.number) {
            return Err(here(ProgramError::Missing(
                "SL cycles (21-24) are called with CYCL CALL only",
            )));
        }
        let shifted = |k: ParamKey| match (k, surface_shift) {
            (ParamKey::Q(203), Some(z)) => def.get(k).map(|v| v + z),
            _ => def.get(k),
        };
        let ctx = self.cycle_ctx();
        let mut moves = Vec::new();
        match points {
            Some(pts) => cycles::generate_at_points(pts, def.number, &shifted, &ctx, &mut moves),
            None => (self.cyc.generator)(def.number, &shifted, &ctx, &mut moves),
        }
        .map_err(|e| here(self.cycle_error(e)))?;
        self.emit_moves(&moves, emit);
        self.release();
        Ok(())
    }

    /// Turns cycle moves (working-plane frame) into ops in program coordinates.
    pub(super) fn emit_moves(&mut self, moves: &[Move], emit: &mut impl FnMut(OpKind)) {
        let (a, b, n) = self.plane.axes();
        let feed = |f: CycleFeed| match f {
            CycleFeed::Rapid => Feed::Rapid,
            CycleFeed::Rate(v) => Feed::Rate(v),
            CycleFeed::PerRev(p) => Feed::PerRevolution(p),
        };
        for mv in moves {
            let from = self.pos;
            let op = match *mv {
                Move::Line { to, feed: f } => {
                    let mut p = from;
                    (p[a], p[b], p[n]) = (to[0], to[1], to[2]);
                    OpKind::Line {
                        from,
                        to: p,
                        feed: feed(f),
                    }
                }
                Move::Arc {
                    centre,
                    to,
                    ccw,
                    turns,
                    feed: f,
                } => {
                    let mut p = from;
                    (p[a], p[b], p[n]) = (to[0], to[1], to[2]);
                    OpKind::Arc {
                        from,
                        to: p,
                        center: centre,
                        plane: self.plane,
                        sweep: sweep_of([from[a], from[b]], [to[0], to[1]], centre, ccw, turns),
                        feed: feed(f),
                    }
                }
                Move::Dwell(seconds) => OpKind::Dwell { seconds },
                Move::RigidTap {
                    to,
                    pitch,
                    hand,
                    lead_in,
                    infeed,
                    back,
                    retract_factor,
                } => {
                    let mut bottom = from;
                    (bottom[a], bottom[b], bottom[n]) = (to[0], to[1], to[2]);
                    let depth = (0..9)
                        .map(|i| (bottom.0[i] - from.0[i]).powi(2))
                        .sum::<f64>()
                        .sqrt();
                    let strokes = cycles::tap_strokes(lead_in, depth, infeed, back);
                    // The tool ends where it started (the last stroke's depth is 0).
                    OpKind::RigidTap {
                        from,
                        to: bottom,
                        pitch,
                        hand,
                        strokes,
                        retract_factor,
                    }
                }
                Move::Spindle(dir) => {
                    self.spindle = dir;
                    self.spindle_op()
                }
            };
            self.commit(&op);
            emit(op);
        }
    }

    /// `CYCL CALL`, `CYCL CALL POS`, `CYCL CALL PAT`.
    pub(super) fn cycle_call(
        &mut self,
        kind: CallKind,
        parsed: &Parsed,
        out: &mut VecDeque<Op>,
        loc: SourceLoc,
    ) -> Result<Flow, ExecError> {
        let w = &parsed.words;
        let ms = MWords::classify(w)?;
        ms.modal(self);
        let mut emit = |kind: OpKind| out.push_back(Op { kind, loc });
        ms.before(self, &mut emit)?;
        if kind == CallKind::Here
            && let Some(def) = &self.cyc.machining
            && is_sl_call(def.number)
        {
            // the contour subprograms run first; the cycle and the block's later M
            // functions follow in finish_contours
            return self.sl_call(w, loc);
        }
        match kind {
            CallKind::Here => self.call_machining(&mut emit)?,
            CallKind::Pos => {
                let target = self.target(w);
                // the feed of CYCL CALL POS acts on the traverse to the position only
                let modal = self.feed;
                let feed = match w.feed {
                    Some(_) => self.feed(w.feed)?.unwrap_or(Feed::Rapid),
                    None => Feed::Rapid,
                };
                self.feed = modal;
                if self.comp != CompSide::Off {
                    self.comp = CompSide::Off;
                    emit(OpKind::RadiusComp {
                        side: CompSide::Off,
                    });
                }
                let (_, _, n) = self.plane.axes();
                // above the target: working plane first, then down the tool axis; below
                // it: up the tool axis first
                let mut between = if self.pos[n] >= target[n] {
                    target
                } else {
                    self.pos
                };
                between[n] = if self.pos[n] >= target[n] {
                    self.pos[n]
                } else {
                    target[n]
                };
                for to in [between, target] {
                    if to != self.pos {
                        let op = OpKind::Line {
                            from: self.pos,
                            to,
                            feed,
                        };
                        self.commit(&op);
                        emit(op);
                    }
                }
                self.call_with(&mut emit, Some(target[n]), None)?;
            }
            CallKind::Pat => {
                if self.cyc.pattern.is_empty() {
                    return Err(here(ProgramError::Missing(
                        "CYCL CALL PAT without a PATTERN DEF",
                    )));
                }
                let pts = std::mem::take(&mut self.cyc.pattern);
                let r = self.call_with(&mut emit, None, Some(&pts));
                self.cyc.pattern = pts;
                r?;
            }
        }
        ms.motion(self, w, &mut emit)?;
        Ok(ms.after(self, false, &mut emit))
    }
}

fn word_err(it: &OldItem, cycle: &str) -> ExecError {
    at(
        it.pos,
        ProgramError::Unexpected(format!(
            "word '{}' in cycle {cycle}",
            String::from_utf8_lossy(it.word())
        )),
    )
}

fn check_factor(f: f64, it: &OldItem) -> Result<(), ExecError> {
    if f > 0.0 && f < 100.0 {
        Ok(())
    } else {
        Err(at(
            it.pos,
            ProgramError::OutOfRange(format!(
                "scaling factor {f} is outside 0.000001 to 99.999999"
            )),
        ))
    }
}

/// Signed sweep (degrees) of an arc from `s` to `e` about `c`, direction `ccw`, with
/// `turns` extra revolutions; equal start and end points make a full circle.
fn sweep_of(s: [f64; 2], e: [f64; 2], c: [f64; 2], ccw: bool, turns: u32) -> f64 {
    let a0 = (s[1] - c[1]).atan2(s[0] - c[0]).to_degrees();
    let a1 = (e[1] - c[1]).atan2(e[0] - c[0]).to_degrees();
    let same = (s[0] - e[0]).hypot(s[1] - e[1]) < 1e-9;
    let base = if same {
        360.0
    } else if ccw {
        (a1 - a0).rem_euclid(360.0)
    } else {
        (a0 - a1).rem_euclid(360.0)
    };
    let total = base + 360.0 * f64::from(turns);
    if ccw { total } else { -total }
}

#[cfg(test)]
#[path = "cycle_tests.rs"]
mod tests;
