//! The run's events: non-motion ops as they reach the servo loop (the TCPM switch, program
//! stops, machine functions); the spindle commands are in `spindle.rs`.

use super::{Run, RunError};
use crate::testrun::block_diagnostic;
use klar_interp::op::SpindleId;
use klar_interp::{Op, OpKind, SourceLoc};

impl Run<'_, '_> {
    /// A non-motion op reaching the servo loop.
    pub(super) fn handle_event(&mut self, op: &Op) -> Result<(), RunError> {
        match &op.kind {
            OpKind::Spindle {
                spindle: SpindleId::Main,
                dir,
                speed,
            } => self.spindle_command(op.loc, *dir, *speed),
            OpKind::SpindleSync { .. } => self.spindle_sync(op),
            OpKind::Tcpm { .. } => {
                self.command.event(op);
                Ok(())
            }
            OpKind::Stop { optional } => {
                // A run without an operator cannot wait for a restart: it logs and goes on.
                tracing::info!(
                    line = op.loc.line,
                    optional,
                    "program stop (no operator: continuing)"
                );
                Ok(())
            }
            OpKind::MachineFunction { number, stop, wait } => {
                // The simulated machine has nothing to switch: the function is logged; the
                // planner has already stopped the path and holds it for `wait`.
                tracing::info!(
                    line = op.loc.line,
                    number,
                    name = self.config.machine_function_name(*number),
                    stop,
                    wait,
                    "machine function M{number}"
                );
                Ok(())
            }
            other => {
                tracing::debug!(line = op.loc.line, ?other, "event");
                Ok(())
            }
        }
    }

    pub(super) fn diagnostic(&self, loc: SourceLoc, message: String) -> RunError {
        RunError::Program(block_diagnostic(self.path, loc, message))
    }
}
