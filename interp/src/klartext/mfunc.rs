//! M functions: which ones this version runs, and when they act within their block.
//!
//! Timing follows the TNC M-function table: M3, M4, M8, M13 and M14 act at block start, M5 and
//! M9 at block end, M0 (stop, spindle off, coolant off), M1 (optional stop) and M2/M30 (end,
//! spindle off, coolant off) after the block's motion.
//!
//! Motion-related functions: M91 (coordinates of this block relative to the machine datum) and
//! M92 (relative to the machine's fixed position) are accepted; the built-in machines have no
//! presets or datum shifts, so both leave the coordinates as programmed. M126 makes absolute
//! rotary moves take the shorter way (less than 180°), M127 switches that off again. M140
//! retracts along the tool axis after the block's motion: `MB d` by d (rapid), `MB MAX` to the
//! travel limit when the interpreter knows it. M97 (small contour steps) and M98 (open contour
//! corner) act on the corner at the end of their own block: they are passed on before the
//! block's motion as [`OpKind::CornerRule`] for the radius compensation stage; M6 is
//! accepted and does nothing (TOOL CALL changes the tool). Any other M number is reported as
//! not supported on this machine.
//!
//! Cycle calls: M99 calls the last defined machining cycle once, after the block's motion,
//! and ends M89; M89 calls it after every positioning block from its own on (modal).

use super::exec::{ExecError, Flow, Machine, at};
use super::parser::Words;
use crate::diag::ProgramError;
use crate::op::{CornerRule, Feed, OpKind, SpindleDir};

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
                other => return Err(at(pos, ProgramError::UnsupportedM(other))),
            }
        }
        Ok(m)
    }

    /// Modal switches that already apply to the block's own coordinates (M126/M127).
    pub(super) fn modal(&self, mc: &mut Machine) {
        if let Some(on) = self.shortest {
            mc.shortest_rotary = on;
        }
        if let Some(on) = self.modal_call {
            mc.cyc.modal_call = on;
        }
    }

    /// Ops acting at block start.
    pub(super) fn before(&self, mc: &mut Machine, emit: &mut impl FnMut(OpKind)) {
        if let Some(on) = self.tcpm {
            mc.set_m128(on, emit);
        }
        if let Some(rule) = self.corner {
            emit(OpKind::CornerRule { rule });
        }
        if let Some(dir) = self.spindle_on {
            mc.spindle = dir;
            emit(mc.spindle_op());
        }
        if self.coolant_on {
            mc.coolant = true;
            emit(OpKind::Coolant { on: true });
        }
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
            Some(None) => match mc.retract_limit {
                Some(limit) => limit,
                None => {
                    return Err(at(
                        self.retract_pos,
                        ProgramError::NotSupported(
                            "M140 MB MAX without a known travel limit of the tool axis".into(),
                        ),
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
