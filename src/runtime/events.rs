//! The run's events: non-motion ops as they reach the servo loop (the TCPM switch, program
//! stops, machine functions); the spindle commands are in `spindle.rs`.

use super::{LogRecord, Run, RunError};
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
            OpKind::RigidTap { .. } => self.rigid_tap(op),
            OpKind::Tcpm { .. } => {
                self.command.event(op);
                Ok(())
            }
            OpKind::Stop { optional } => {
                // A run without an operator cannot wait for a restart: it logs and goes on.
                self.log.send(LogRecord::ProgramStop {
                    line: op.loc.line,
                    optional: *optional,
                });
                Ok(())
            }
            OpKind::MachineFunction { number, stop, wait } => {
                // The simulated machine has nothing to switch: the function is logged; the
                // planner has already stopped the path and holds it for `wait`.
                self.log.send(LogRecord::MachineFunction {
                    line: op.loc.line,
                    number: *number,
                    stop: *stop,
                    wait: *wait,
                });
                Ok(())
            }
            OpKind::ProbeResult { result } => {
                // Read by displays; the values are already in the interpreter.
                self.report.probe_results.push(result.clone());
                Ok(())
            }
            _ => {
                self.log.send(LogRecord::Event { line: op.loc.line });
                Ok(())
            }
        }
    }

    pub(super) fn diagnostic(&self, loc: SourceLoc, message: String) -> RunError {
        RunError::Program(block_diagnostic(self.path, loc, message))
    }
}
