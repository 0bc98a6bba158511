//! M functions: which ones this version runs, and when they act within their block.
//!
//! Timing follows the TNC M-function table: M3, M4, M8, M13 and M14 act at block start, M5 and
//! M9 at block end, M0 (stop, spindle off, coolant off), M1 (optional stop) and M2/M30 (end,
//! spindle off, coolant off) after the block's motion.
//!
//! Motion-related functions: M91 (the coordinates of this `L` block are machine coordinates,
//! from the machine datum: no preset or datum transform acts on them) and M92 (from the
//! machine builder's fixed position, which klar's machines put at the machine datum; see
//! `Machine::machine_datum_target`). M126 makes absolute rotary moves take the shorter way
//! (less than 180°), M127 switches that off again. M116 makes F on rotary table axes the tool
//! point's speed in mm/min from its own block on, M117 (or the program end) switches it off
//! ([`super::rotary_feed`]). M128 switches TCPM on at block start, with the feed of its
//! compensating moves when an F follows it, M129 off ([`super::tcpm`]). M140 retracts along
//! the tool axis after the block's motion: `MB d` by d (rapid), `MB MAX` until a linear
//! machine axis reaches its travel limit (see [`super::retract`]). M97 (small contour steps) and M98 (open contour
//! corner) act on the corner at the end of their own block: they are passed on before the
//! block's motion as [`OpKind::CornerRule`] for the radius compensation stage; M6 is
//! accepted and does nothing (TOOL CALL changes the tool).
//!
//! Machine functions: every other M number belongs to the machine builder (door, clamping,
//! chip conveyor, …). The machine configuration lists the ones the machine has, each with
//! the moment it acts (block start or block end), whether the path stops exactly before it
//! and how long the machine waits after it; they are passed on as
//! [`OpKind::MachineFunction`]. At block start they come after M97/M98, M128/M129 and before
//! the spindle and coolant switch on; at block end after the spindle and coolant switch off
//! and before a program stop or the program end. An M number neither built in nor
//! configured is reported as not supported on this machine, at its word.
//!
//! Cycle calls: M99 calls the last defined machining cycle once, after the block's motion,
//! and ends M89; M89 calls it after every positioning block from its own on (modal).

use super::exec::{ExecError, Flow, Machine, at};
use super::expr::Value;
use super::stmt::{MAX_M, Parsed, Stmt, Words};
use crate::diag::ProgramError;
use crate::op::{CornerRule, Feed, MachineFunctionDef, MachineFunctionTime, OpKind, SpindleDir};

/// The M words of one block, sorted by when they act.
#[derive(Debug, Default)]
pub(super) struct MWords {
    spindle_on: Option<SpindleDir>,
    coolant_on: bool,
    spindle_off: bool,
    coolant_off: bool,
    stop: bool,
    optional_stop: bool,
    end: bool,
    retract: bool,
    retract_pos: u32,
    shortest: Option<bool>,
    corner: Option<CornerRule>,
    cycle_call: bool,
    modal_call: Option<bool>,
    tcpm: Option<bool>,
    /// The F written directly after M128 (feed of the compensating moves), with its position.
    tcpm_feed: Option<(Value, u32)>,
    /// M116 (true) / M117.
    rotary_feed: Option<bool>,
    /// M136 (true) / M137.
    per_rev: Option<bool>,
    /// Machine functions in the order written (checked against the machine beforehand).
    machine: [u32; MAX_M],
    /// How many of `machine` are used.
    machine_count: u8,
}

impl MWords {
    pub(super) fn classify(w: &Words) -> Result<MWords, ExecError> {
        let mut m = MWords::default();
        for (num, pos) in w.m_words() {
            match num {
                0 => m.stop = true,
                1 => m.optional_stop = true,
                2 | 30 => m.end = true,
                3 => m.spindle_on = Some(SpindleDir::Cw),
                4 => m.spindle_on = Some(SpindleDir::Ccw),
                5 => m.spindle_off = true,
                8 => m.coolant_on = true,
                9 => m.coolant_off = true,
                13 => {
                    m.spindle_on = Some(SpindleDir::Cw);
                    m.coolant_on = true;
                }
                14 => {
                    m.spindle_on = Some(SpindleDir::Ccw);
                    m.coolant_on = true;
                }
                97 => m.corner = Some(CornerRule::Intersect),
                98 => m.corner = Some(CornerRule::Open),
                6 | 91 | 92 => {}
                126 | 127 => m.shortest = Some(num == 126),
                // M116: F on rotary table axes in mm/min at the tool point; M117 ends it
                116 | 117 => m.rotary_feed = Some(num == 116),
                // M136: F in mm per spindle revolution from this block on; M137 ends it
                136 | 137 => m.per_rev = Some(num == 136),
                // M99: call the last defined cycle after this block's motion (and end M89);
                // M89: call it after every positioning block from now on
                99 => {
                    m.cycle_call = true;
                    m.modal_call = Some(false);
                }
                89 => m.modal_call = Some(true),
                // M128: keep the tool tip on the path while rotary axes turn; M129 ends it
                128 | 129 => m.tcpm = Some(num == 128),
                140 => {
                    m.retract = true;
                    m.retract_pos = pos;
                }
                // not built in: a machine function, which the executor has checked against
                // the machine's list before running the block
                other => {
                    if let Some(slot) = m.machine.get_mut(usize::from(m.machine_count)) {
                        *slot = other;
                        m.machine_count += 1;
                    }
                }
            }
        }
        m.tcpm_feed = w.m128_feed;
        Ok(m)
    }

    /// Emits the machine functions of this block that act at `when`.
    fn machine_functions(
        &self,
        mc: &Machine,
        when: MachineFunctionTime,
        emit: &mut impl FnMut(OpKind),
    ) {
        let n = usize::from(self.machine_count).min(MAX_M);
        for number in self.machine.iter().take(n) {
            if let Some(def) = find(&mc.machine_functions, *number)
                && def.at == when
            {
                emit(OpKind::MachineFunction {
                    number: def.number,
                    stop: def.stop,
                    wait: def.wait,
                });
            }
        }
    }

    /// Modal switches that already apply to the block's own coordinates and feed (M126/M127,
    /// M116/M117, M136/M137).
    pub(super) fn modal(&self, mc: &mut Machine) {
        if let Some(on) = self.per_rev {
            if on != mc.per_rev {
                mc.feed_rev = None;
            }
            mc.per_rev = on;
        }
        if let Some(on) = self.shortest {
            mc.shortest_rotary = on;
        }
        if let Some(on) = self.rotary_feed {
            mc.tilt.m116 = on;
        }
        if let Some(on) = self.modal_call {
            mc.cyc.modal_call = on;
        }
    }

    /// Ops acting at block start; refuses an M128 feed that is not a positive number.
    pub(super) fn before(
        &self,
        mc: &mut Machine,
        emit: &mut impl FnMut(OpKind),
    ) -> Result<(), ExecError> {
        if let Some(on) = self.rotary_feed {
            mc.tilt.m116 = on;
        }
        if let Some(on) = self.tcpm {
            let feed = match self.tcpm_feed {
                Some((v, pos)) => {
                    let f = mc.params.value(v);
                    if !(f > 0.0 && f.is_finite()) {
                        return Err(at(
                            pos,
                            ProgramError::OutOfRange(format!(
                                "feed rate F{f} after M128 must be positive"
                            )),
                        ));
                    }
                    Some(f * mc.feed_scale() / 60.0)
                }
                None => None,
            };
            mc.set_m128(on, feed, emit);
        }
        if let Some(rule) = self.corner {
            emit(OpKind::CornerRule { rule });
        }
        self.machine_functions(mc, MachineFunctionTime::Start, emit);
        if let Some(dir) = self.spindle_on {
            mc.spindle = dir;
            emit(mc.spindle_op());
        }
        if self.coolant_on {
            mc.coolant = true;
            emit(OpKind::Coolant { on: true });
        }
        Ok(())
    }

    /// M140: the retract along the tool axis after the block's motion.
    pub(super) fn motion(
        &self,
        mc: &mut Machine,
        w: &Words,
        emit: &mut impl FnMut(OpKind),
    ) -> Result<(), ExecError> {
        if self.cycle_call {
            mc.call_machining(emit)?;
        }
        if !self.retract {
            return Ok(());
        }
        let axis = mc.tool_axis;
        let target = match w.mb {
            Some(Some(v)) => mc.pos[axis] + mc.params.value(v) * mc.unit,
            Some(None) => match mc.retract_distance() {
                Some(s) => mc.pos[axis] + s,
                None => {
                    return Err(at(
                        self.retract_pos,
                        ProgramError::NotSupported(format!(
                            "M140 MB MAX without a known travel of the tool axis {axis} \
                             (give the machine with --machine, or `travel` for {axis})"
                        )),
                    ));
                }
            },
            None => {
                return Err(at(
                    self.retract_pos,
                    ProgramError::Missing("M140 needs MB (retract distance or MAX)"),
                ));
            }
        };
        let from = mc.pos;
        let mut to = from;
        to[axis] = target;
        if to != from {
            mc.pos = to;
            mc.last_feed = Some(Feed::Rapid);
            emit(OpKind::Line {
                from,
                to,
                feed: Feed::Rapid,
            });
        }
        Ok(())
    }

    /// Ops acting after the motion; `stop_block` for STOP.
    pub(super) fn after(
        &self,
        mc: &mut Machine,
        stop_block: bool,
        emit: &mut impl FnMut(OpKind),
    ) -> Flow {
        if self.spindle_off {
            mc.spindle = SpindleDir::Off;
            emit(mc.spindle_op());
        }
        if self.coolant_off {
            mc.coolant = false;
            emit(OpKind::Coolant { on: false });
        }
        self.machine_functions(mc, MachineFunctionTime::End, emit);
        if self.end {
            mc.end_ops(emit);
            return Flow::End;
        }
        if self.stop || stop_block || self.optional_stop {
            mc.after_stop = true;
        }
        if self.stop {
            mc.spindle_coolant_off(emit);
            emit(OpKind::Stop { optional: false });
        } else if stop_block {
            // STOP without M0 halts the program run only
            emit(OpKind::Stop { optional: false });
        } else if self.optional_stop {
            emit(OpKind::Stop { optional: true });
        }
        Flow::Continue
    }
}

/// The machine's definition of M function `number`, if it has one.
fn find(defs: &[MachineFunctionDef], number: u32) -> Option<&MachineFunctionDef> {
    defs.iter().find(|d| d.number == number)
}

/// True when klar gives M `number` a meaning itself (see [`MWords::classify`]).
fn built_in(number: u32) -> bool {
    crate::op::BUILT_IN_M_NUMBERS.contains(&number)
}

/// The words whose M functions a statement runs, if it runs any: path blocks, M-only and
/// STOP blocks, SPL, APPR/DEP and cycle calls carry them in the block's words, FK blocks in
/// the FK words. (Other statements leave the words of an earlier block in place.)
fn m_words_of<'a>(stmt: &Stmt, parsed: &'a Parsed) -> Option<&'a Words> {
    match stmt {
        Stmt::Misc
        | Stmt::Stop
        | Stmt::Line
        | Stmt::LinePolar
        | Stmt::Circle
        | Stmt::CircleRadius
        | Stmt::CircleTangent
        | Stmt::CirclePolar
        | Stmt::CircleTangentPolar
        | Stmt::Spline
        | Stmt::ApproachDepart { .. }
        | Stmt::CycleCall { .. } => Some(&parsed.words),
        Stmt::Fk(_) => Some(&parsed.fk.base),
        _ => None,
    }
}

impl Machine {
    /// Uses `defs` as the machine's own M functions from now on. Entries with a built-in
    /// number are ignored (the built-in meaning wins); for a number listed twice the first
    /// entry counts.
    pub(crate) fn set_machine_functions(&mut self, defs: &[MachineFunctionDef]) {
        self.machine_functions = defs
            .iter()
            .filter(|d| !built_in(d.number))
            .copied()
            .collect();
    }

    /// Refuses, at its word, an M number of the statement that is neither built in nor one
    /// of the machine's functions. Runs before the statement, so nothing of the block runs.
    pub(super) fn check_m_numbers(&self, stmt: &Stmt, parsed: &Parsed) -> Result<(), ExecError> {
        let Some(w) = m_words_of(stmt, parsed) else {
            return Ok(());
        };
        for (number, pos) in w.m_words() {
            if !built_in(number) && find(&self.machine_functions, number).is_none() {
                return Err(at(pos, ProgramError::UnsupportedM(number)));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::interpreter::Interpreter;
    use crate::klartext::test_support::run;
    use crate::op::{
        AxisLetter, BUILT_IN_M_NUMBERS, MachineFunctionDef, MachineFunctionTime, Op, OpKind, Pose,
        SpindleDir,
    };
    use crate::tnc::exec::Machine;

    /// M25 at block end with a stop and 2 s wait, M26 at block start without a stop.
    fn door() -> Vec<MachineFunctionDef> {
        vec![
            MachineFunctionDef {
                number: 25,
                at: MachineFunctionTime::End,
                stop: true,
                wait: 2.0,
            },
            MachineFunctionDef {
                number: 26,
                at: MachineFunctionTime::Start,
                stop: false,
                wait: 0.0,
            },
        ]
    }

    fn klartext(body: &str) -> String {
        format!("0 BEGIN PGM T MM\n{body}\n99 END PGM T MM\n")
    }

    /// All ops of a program, or the first error as `(line, col, message)`.
    fn run_ops(
        name: &str,
        text: &str,
        defs: &[MachineFunctionDef],
    ) -> Result<Vec<Op>, (u32, u32, String)> {
        Interpreter::from_source(name, text, Pose::ZERO)
            .with_machine_functions(defs)
            .collect::<Result<Vec<_>, _>>()
            .map_err(|d| (d.line, d.col, d.message))
    }

    /// A short name per op kind, the machine functions with their number.
    fn kinds(ops: &[Op]) -> Vec<String> {
        ops.iter()
            .map(|o| match &o.kind {
                OpKind::Line { to, .. } => format!("L{}", to[AxisLetter::X]),
                OpKind::MachineFunction { number, .. } => format!("M{number}"),
                OpKind::Spindle { dir, .. } => format!("S{dir:?}"),
                OpKind::Coolant { on } => format!("K{on}"),
                OpKind::End => "end".into(),
                other => format!("{other:?}"),
            })
            .collect()
    }

    #[test]
    fn a_function_at_block_end_follows_the_motion() {
        let text = klartext("1 L X+0 Y+0 Z+50 R0 FMAX\n2 L X+10 F600 M25\n3 L X+20");
        let ops = run_ops("t.h", &text, &door()).unwrap();
        assert_eq!(kinds(&ops), ["L0", "L10", "M25", "L20", "end"]);
        let mf = &ops[2];
        assert_eq!(
            mf.kind,
            OpKind::MachineFunction {
                number: 25,
                stop: true,
                wait: 2.0
            }
        );
        // it belongs to the block that programs it (line 3 of the file)
        assert_eq!(mf.loc.line, 3);
    }

    #[test]
    fn a_function_at_block_start_precedes_the_motion() {
        let text = klartext("1 L X+0 Y+0 Z+50 R0 FMAX\n2 L X+10 F600 M26\n3 L X+20");
        let ops = run_ops("t.h", &text, &door()).unwrap();
        assert_eq!(kinds(&ops), ["L0", "M26", "L10", "L20", "end"]);
        assert_eq!(
            ops[1].kind,
            OpKind::MachineFunction {
                number: 26,
                stop: false,
                wait: 0.0
            }
        );
        assert_eq!(ops[1].loc.line, 3);
    }

    #[test]
    fn order_among_the_built_in_functions_of_the_block() {
        // start: machine functions before spindle and coolant on; end: after spindle and
        // coolant off, before the program end
        let text = klartext(
            "1 L X+0 Y+0 Z+50 R0 FMAX\n2 L X+10 F600 M13 M25 M26\n3 L X+20 M5 M9 M25 M26 M2",
        );
        let ops = run_ops("t.h", &text, &door()).unwrap();
        assert_eq!(
            kinds(&ops),
            [
                "L0", "M26", "SCw", "Ktrue", "L10", "M25", "M26", "L20", "SOff", "Kfalse", "M25",
                "end"
            ]
        );
        assert!(matches!(
            ops[2].kind,
            OpKind::Spindle {
                dir: SpindleDir::Cw,
                ..
            }
        ));
    }

    #[test]
    fn a_function_alone_in_its_block() {
        let text = klartext("1 L X+5 R0 FMAX\n2 M25\n3 M26");
        let ops = run_ops("t.h", &text, &door()).unwrap();
        assert_eq!(kinds(&ops), ["L5", "M25", "M26", "end"]);
    }

    #[test]
    fn unknown_numbers_stay_errors_at_their_word() {
        let body = "1 L X+0 Y+0 Z+50 R0 FMAX\n2 L X+10 F600 M25 M27";
        let text = klartext(body);
        let col = body.lines().nth(1).unwrap().find("M27").unwrap() as u32 + 1;
        let err = run_ops("t.h", &text, &door()).unwrap_err();
        assert_eq!(
            err,
            (3, col, "block 2: M27 not supported on this machine".into())
        );
        // without the machine's list M25 itself is unknown
        let text = klartext("1 L X+0 Y+0 Z+50 R0 FMAX\n2 L X+10 F600 M25");
        let err = run_ops("t.h", &text, &[]).unwrap_err();
        assert_eq!(
            err,
            (3, 15, "block 2: M25 not supported on this machine".into())
        );
    }

    #[test]
    fn an_unknown_number_stops_before_anything_of_its_block_runs() {
        // the line of block 2 and its M26 must not come out
        let text = klartext("1 L X+0 Y+0 Z+50 R0 FMAX\n2 L X+10 F600 M26 M27");
        let mut it =
            Interpreter::from_source("t.h", &text, Pose::ZERO).with_machine_functions(&door());
        let mut seen = Vec::new();
        for r in it.by_ref() {
            match r {
                Ok(op) => seen.push(op),
                Err(d) => {
                    assert_eq!(d.message, "block 2: M27 not supported on this machine");
                    break;
                }
            }
        }
        assert_eq!(kinds(&seen), ["L0"]);
    }

    #[test]
    fn check_accepts_configured_numbers_only() {
        let text = klartext("1 L X+0 Y+0 Z+50 R0 FMAX\n2 L X+10 F600 M25\n3 M26\n4 M27");
        let report = Interpreter::from_source("t.h", &text, Pose::ZERO)
            .with_machine_functions(&door())
            .check_report();
        let lines: Vec<u32> = report.errors.iter().map(|d| d.line).collect();
        assert_eq!(lines, [5], "{:?}", report.errors);
        let report = Interpreter::from_source("t.h", &text, Pose::ZERO).check_report();
        assert_eq!(report.errors.len(), 3, "{:?}", report.errors);
    }

    #[test]
    fn fk_blocks_and_cycle_calls_carry_them_too() {
        let text = klartext(
            "1 L X+0 Y+0 Z+50 R0 FMAX\n2 FL X+10 Y+0 F600 M25\n3 L X+20\n\
             4 CYCL DEF 200 DRILLING Q200=2 Q201=-5 Q206=150 Q202=5 Q210=0 Q203=+0 Q204=20 \
             Q211=0\n5 CYCL CALL M26",
        );
        let ops = run_ops("t.h", &text, &door()).unwrap();
        let k = kinds(&ops);
        let at = |s: &str| k.iter().position(|x| x == s).unwrap();
        assert!(at("L10") < at("M25") && at("M25") < at("L20"), "{k:?}");
        assert!(at("M26") > at("L20"), "{k:?}");
        // M26 acts at the start of the cycle call: before the cycle's first move
        assert!(ops[at("M26") + 1].kind.is_motion(), "{k:?}");
        let err = run_ops("t.h", &text.replace("M25", "M27"), &door()).unwrap_err();
        assert_eq!(err.2, "block 2: M27 not supported on this machine");
    }

    #[test]
    fn iso_programs_use_the_same_list() {
        let text = "%T G71 *\nN10 G00 G40 X+0 Y+0 Z+50 *\nN20 G01 X+10 F600 M25 *\n\
                    N30 G01 X+20 M26 *\nN99999999 %T G71 *\n";
        let ops = run_ops("t.i", text, &door()).unwrap();
        assert_eq!(kinds(&ops), ["L0", "L10", "M25", "M26", "L20", "end"]);
        let err = run_ops("t.i", text, &[]).unwrap_err();
        assert_eq!(err.0, 3);
        assert_eq!(err.2, "block 20: M25 not supported on this machine");
    }

    #[test]
    fn built_in_numbers_are_exactly_the_ones_the_executor_knows() {
        // Every number is either built in (never "not supported") or refused without a
        // machine list; the list in op.rs must match the executor's own M table.
        for n in 0..=9999u32 {
            let mut m = Machine::new(Pose::ZERO);
            let r = run(&mut m, &format!("L X+1 F100 M{n}"));
            let refused = matches!(&r, Err(e) if e.ends_with("not supported on this machine"));
            assert_eq!(refused, !BUILT_IN_M_NUMBERS.contains(&n), "M{n}: {r:?}");
        }
    }

    #[test]
    fn built_in_numbers_in_the_machine_list_are_ignored() {
        let mut defs = door();
        defs.push(MachineFunctionDef {
            number: 8,
            at: MachineFunctionTime::End,
            stop: true,
            wait: 1.0,
        });
        let text = klartext("1 L X+0 Y+0 Z+50 R0 FMAX M8");
        let ops = run_ops("t.h", &text, &defs).unwrap();
        assert_eq!(kinds(&ops), ["Ktrue", "L0", "Kfalse", "end"]);
    }
}
