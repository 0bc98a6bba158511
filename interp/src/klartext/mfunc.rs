//! M functions: which ones this version runs, and when they act within their block.
//!
//! Timing follows the TNC M-function table: M3, M4, M8, M13 and M14 act at block start, M5 and
//! M9 at block end, M0 (stop, spindle off, coolant off), M1 (optional stop) and M2/M30 (end,
//! spindle off, coolant off) after the block's motion. Other M numbers are reported as not
//! supported when their block runs.

use super::exec::{ExecError, Flow, Machine, at};
use super::parser::Words;
use crate::diag::ProgramError;
use crate::op::{OpKind, SpindleDir};

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
                other => return Err(at(pos, ProgramError::UnsupportedM(other))),
            }
        }
        Ok(m)
    }

    /// Ops acting at block start.
    pub(super) fn before(&self, mc: &mut Machine, emit: &mut impl FnMut(OpKind)) {
        if let Some(dir) = self.spindle_on {
            mc.spindle = dir;
            emit(mc.spindle_op());
        }
        if self.coolant_on {
            mc.coolant = true;
            emit(OpKind::Coolant { on: true });
        }
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
